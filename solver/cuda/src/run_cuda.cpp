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

// Owns the device copy. float32: the float state is refreshed from the double one first,
// which a checkpoint may have replaced (as the CPU's float backend does when it starts).
class CudaStepBackend final : public StepBackend {
public:
  CudaStepBackend(PdSystem& s, HaloTransport* halo) : gpu_(prepared(s), halo) {}
  void step(PdSystem& s) override { gpu_.step(s); }
  Energies measure(PdSystem& s) override { return gpu_.measure(s); }
  void compute_forces(PdSystem& s) override { gpu_.compute_forces(s); }
  void download(PdSystem& s) override { gpu_.download(s); }
  void download_kinematics(PdSystem& s) override { gpu_.download_kinematics(s); }
  bool time_kernels(long long warmup_steps) override {
    gpu_.time_kernels(warmup_steps);
    return true;
  }
  std::optional<KernelTimes> kernel_times() override { return gpu_.kernel_times(); }
  std::optional<DeviceMemory> device_memory() override { return gpu_.device_memory(); }

private:
  static PdSystem& prepared(PdSystem& s) {
    if (s.f32.active) float32_upload(s);
    return s;
  }
  CudaSystem gpu_;
};

}  // namespace

RunResult cuda_time_loop(PdSystem& s, const RunOptions& o, ResultsWriter* results, HistoryWriter* history) {
  CudaStepBackend backend(s, nullptr);
  if (o.progress) std::fprintf(stderr, "  CUDA device: %s\n", cuda_device_description().c_str());
  return run_time_loop(s, o, backend, results, history);
}

std::unique_ptr<StepBackend> make_cuda_step_backend(PdSystem& s) { return std::make_unique<CudaStepBackend>(s, nullptr); }

std::unique_ptr<StepBackend> make_cuda_rank_backend(PdSystem& s, HaloTransport* halo) {
  return std::make_unique<CudaStepBackend>(s, halo);
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
