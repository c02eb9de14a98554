#pragma once
// The CUDA backend: the kernels of pd_kernels.hpp launched one GPU thread per particle over
// device copies of a PdSystem's arrays (docs/cuda.md). The physics is not repeated here;
// only where the loop runs and where the data lives differ from the OpenMP backend.
//
// This header is plain C++ (no CUDA types), so host-only code such as breccia-solve's CLI
// can include it and link breccia_solver_cuda without being compiled by nvcc.
#include <memory>
#include <optional>
#include <string>

#include "breccia/solver/cuda_device.hpp"  // cuda_device_available, cuda_device_description
#include "breccia/solver/halo_transport.hpp"
#include "breccia/solver/kernel_times.hpp"
#include "breccia/solver/pd_system.hpp"
#include "breccia/solver/run.hpp"

namespace breccia::solver {

// A PdSystem's arrays on the device. The host PdSystem stays the owner of the case (config,
// loads, constraints, metadata); this object owns the device copies of every array a step
// reads or writes. Residency contract:
//   - construction uploads everything from `sys` (so it also continues a restart);
//   - step() advances the device state and the host's step/time counters only;
//   - external_work and dissipated_energy accumulate on the device and are copied into
//     the host mirror by measure() and download();
//   - download() copies all per-particle and per-bond state back for outputs/checkpoints.
// Throws RunError naming the kernel or copy if CUDA reports an error.
class CudaSystem {
public:
  // `halo`: a distributed run's rank system (owned particles, then ghosts: rank_system.hpp),
  // whose step exchanges the ghosts' values through it (packed on the device); it must
  // outlive this object. Null: one process.
  explicit CudaSystem(const PdSystem& sys, HaloTransport* halo = nullptr);
  ~CudaSystem();
  CudaSystem(const CudaSystem&) = delete;
  CudaSystem& operator=(const CudaSystem&) = delete;

  // One velocity-Verlet step of size sys.dt: the same phases, in the same order, as cpu_step.
  // Honours sys.diagnostics (damage/energy density skipped between output steps).
  void step(PdSystem& host_mirror_meta);
  // cpu_compute_forces at the current displacement (e.g. diagnostics for an unplanned output).
  void compute_forces(PdSystem& host_mirror_meta);
  // Energies reduced on the device (no per-particle download); also refreshes the host
  // mirror's external_work and dissipated_energy.
  Energies measure(PdSystem& host_mirror_meta);
  // Copy u, v, a, force, body, per-particle fields, bond states and the energy
  // accumulators into `sys` (outputs, checkpoints, comparisons).
  void download(PdSystem& sys);
  // Copy only u and v (history probes need nothing more).
  void download_kinematics(PdSystem& sys);
  // --kernel-times: from `warmup_steps` steps on (counted from now), every launch is bracketed
  // by two CUDA events and its elapsed time summed per kernel name (docs/cuda.md, "Per-kernel
  // times"). The events are resolved in batches, so timing adds no synchronisation per step.
  void time_kernels(long long warmup_steps);
  // What was timed so far (waits for the pending events); nullopt unless time_kernels was called.
  std::optional<KernelTimes> kernel_times();
  // The device memory this system took (run.hpp DeviceMemory), measured by cudaMemGetInfo.
  DeviceMemory device_memory();

  struct Impl;  // defined in cuda_backend.cu only (named there by its execution space)

private:
  std::unique_ptr<Impl> impl_;
};

// The device every CudaSystem built from now on uses: `index` mod the number of devices (a
// distributed run passes the rank's place on its node, so ranks spread over a node's GPUs
// and several share one when there are more ranks). Returns the device chosen, -1 if none.
int cuda_use_device(int index);
// The device CudaSystems use now (0 unless cuda_use_device chose another).
int cuda_device_in_use();

// run_system's time loop on the device: same outputs (results.h5, history.csv, checkpoint),
// same instability check and Ctrl-C handling; arrays are downloaded only when an output,
// a probe row or a checkpoint needs them. Quasi-static cases (ADR) run on the host.
RunResult run_system_cuda(PdSystem& sys, const RunOptions& options);
// A StepBackend (run.hpp) owning a CudaSystem built from `sys` as it is now (float32: after
// float32_upload), for callers that drive the steps themselves (breccia-atlas).
std::unique_ptr<StepBackend> make_cuda_step_backend(PdSystem& sys);
// The same for a distributed run's rank system, its ghosts filled through `halo` (CudaSystem's
// constructor; solver/mpi/).
std::unique_ptr<StepBackend> make_cuda_rank_backend(PdSystem& sys, HaloTransport* halo);
// The dynamic loop on the GPU, for RunOptions::backend_loop (run_system calls it).
RunResult cuda_time_loop(PdSystem& sys, const RunOptions& options, ResultsWriter* results, HistoryWriter* history);

}  // namespace breccia::solver
