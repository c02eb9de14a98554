#pragma once
// Entry point of the MPS solver, called by breccia-solve for `model: {type: mps}` and by
// the stand-alone breccia-mps CLI. Writes history.csv, summary.json and results.h5 into
// out_dir. Returns a process exit code; throws breccia::InputError for bad input.
#include <memory>
#include <string>

namespace breccia::mps {

class Simulation;
class StepDevice;
class Solid;
class SolidStepDevice;

struct RunCaseOptions {
  int threads = 0;  // OpenMP threads (0: the default)
  // Build the devices that run the steps (breccia-solve --backend cuda passes
  // make_cuda_step_device and make_cuda_solid_device); empty: the OpenMP loops. A stress
  // case with a feature the solid launcher does not run is refused (InputError naming the
  // key, solid_device_refusal) when solid_device is set.
  // (Plain function pointers: callers that see the device classes only declared can set them.)
  std::unique_ptr<StepDevice> (*device)(const Simulation&) = nullptr;
  std::unique_ptr<SolidStepDevice> (*solid_device)(const Solid&) = nullptr;
  // --backend auto: a refused stress case runs on the CPU instead, saying why.
  bool cpu_when_refused = false;
  // breccia-solve --steps N: stop after N steps (before time.end if that comes later; 0: the
  // set-up and the initial outputs alone, as for PD); -1: to time.end.
  long long max_steps = -1;
  // breccia-solve --quiet: no progress and no summary lines (errors only), whatever the case's
  // output.progress says.
  bool quiet = false;
};

int run_case(const std::string& case_file, const std::string& out_dir, const RunCaseOptions& options);
int run_case(const std::string& case_file, const std::string& out_dir, int threads);

}  // namespace breccia::mps
