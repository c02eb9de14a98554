// The CUDA backend's time loop: run.cpp's shared loop (run_time_loop) driven by a
// StepBackend that keeps the state on the GPU and copies arrays back only when a file needs
// them (results, probes, checkpoint, an instability message).
#include <cstdio>

#include "breccia/common/error.hpp"
#include "breccia/solver/cuda_backend.hpp"
#include "breccia/solver/float32_state.hpp"
#include "breccia/solver/outputs.hpp"

namespace breccia::solver {
namespace {

class CudaStepBackend final : public StepBackend {
public:
  explicit CudaStepBackend(CudaSystem& gpu) : gpu_(gpu) {}
  void step(PdSystem& s) override { gpu_.step(s); }
  Energies measure(PdSystem& s) override { return gpu_.measure(s); }
  void compute_forces(PdSystem& s) override { gpu_.compute_forces(s); }
  void download(PdSystem& s) override { gpu_.download(s); }
  void download_kinematics(PdSystem& s) override { gpu_.download_kinematics(s); }

private:
  CudaSystem& gpu_;
};

}  // namespace

RunResult cuda_time_loop(PdSystem& s, const RunOptions& o, ResultsWriter* results, HistoryWriter& history) {
  // float32: the float state from the double one, which a checkpoint may have replaced (as
  // the CPU's float backend does when it starts).
  if (s.f32.active) float32_upload(s);
  CudaSystem gpu(s);
  if (o.progress) std::fprintf(stderr, "  CUDA device: %s\n", cuda_device_description().c_str());
  CudaStepBackend backend(gpu);
  return run_time_loop(s, o, backend, results, history);
}

RunResult run_system_cuda(PdSystem& s, const RunOptions& o) {
  // Without a device nothing may be written: fail before run_system opens any file.
  if (!cuda_device_available())
    throw RunError("no CUDA device is available on this machine; use --backend cpu or auto");
  RunOptions with_gpu = o;
  // Adaptive dynamic relaxation is a handful of host loops over forces; it stays on the CPU.
  if (!s.config.quasi_static) with_gpu.backend_loop = cuda_time_loop;
  return run_system(s, with_gpu);
}

}  // namespace breccia::solver
