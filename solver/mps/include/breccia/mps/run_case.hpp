#pragma once
// Entry point of the MPS solver, called by breccia-solve for `model: {type: mps}` and by
// the stand-alone breccia-mps CLI. Writes history.csv, summary.json and results.h5 into
// out_dir. Returns a process exit code; throws breccia::InputError for bad input.
#include <memory>
#include <string>

namespace breccia::mps {

class Simulation;
class StepDevice;

struct RunCaseOptions {
  int threads = 0;  // OpenMP threads (0: the default)
  // Builds the device that runs the displacement formulation's steps (breccia-solve
  // --backend cuda passes make_cuda_step_device); empty: the OpenMP loops. The stress
  // formulation has no device launcher: a case with formulation: stress is refused
  // (InputError naming model.formulation) when this is set.
  // (A plain function pointer: callers that see StepDevice only declared can still set it.)
  std::unique_ptr<StepDevice> (*device)(const Simulation&) = nullptr;
};

int run_case(const std::string& case_file, const std::string& out_dir, const RunCaseOptions& options);
int run_case(const std::string& case_file, const std::string& out_dir, int threads);

}  // namespace breccia::mps
