// run_system's time loop with the state on the GPU. The loop, its outputs and its checks
// are those of run.cpp; what changes is that arrays come back to the host only when a file
// needs them (results, probes, checkpoint, an instability message).
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "breccia/solver/cuda_backend.hpp"
#include "breccia/solver/outputs.hpp"

namespace breccia::solver {
namespace {

std::atomic<bool> g_interrupted{false};
void on_sigint(int) { g_interrupted = true; }

long long total_steps_of(const PdSystem& s, const RunOptions& o) {
  if (o.steps) return *o.steps + s.step;
  if (s.config.steps) return *s.config.steps;
  return static_cast<long long>(std::ceil(*s.config.end_time / s.dt - 1e-9));
}

}  // namespace

RunResult run_system_cuda(PdSystem& s, const RunOptions& o) {
  // Adaptive dynamic relaxation is a handful of host loops over forces; it stays on the CPU.
  if (s.config.quasi_static) return run_system(s, o);

  CudaSystem gpu(s);  // first: without a device nothing is written
  RunResult r;
  const bool restart = !o.restart_file.empty();
  std::filesystem::create_directories(o.out_dir);
  std::unique_ptr<ResultsWriter> results;
  if (s.config.write_results) results = std::make_unique<ResultsWriter>(s, o.out_dir, restart);
  HistoryWriter history(s, o.out_dir, restart);
  if (o.progress) std::fprintf(stderr, "  CUDA device: %s\n", cuda_device_description().c_str());

  const long long total_steps = total_steps_of(s, o);
  Energies e = gpu.measure(s);
  double supplied = e.kinetic + e.strain;  // the scale against which blow-up is judged
  if (!restart) {
    history.write(s, e);  // the host state equals the device state before the first step
    if (results) results->write(s);
  }
  g_interrupted = false;
  auto previous = std::signal(SIGINT, on_sigint);
  const long long first_step = s.step;
  const auto t0 = std::chrono::steady_clock::now();
  auto last_report = t0;
  r.status = "completed";
  while (s.step < total_steps) {
    // Damage and energy density only where something will read them (as run_system does).
    const long long next = s.step + 1;
    s.diagnostics = next % s.config.history_every == 0 || next % s.config.output_every == 0 ||
                    next == total_steps || (s.config.checkpoint_every > 0 && next % s.config.checkpoint_every == 0);
    gpu.step(s);
    s.diagnostics = true;
    const bool history_due = s.step % s.config.history_every == 0 || s.step == total_steps;
    const bool output_due = s.step % s.config.output_every == 0 || s.step == total_steps;
    if (history_due || output_due) {
      e = gpu.measure(s);
      supplied = std::max(supplied, std::fabs(s.external_work) + s.dissipated_energy);
      supplied = std::max(supplied, 1e-300);
      if (!instability_message(s, e, supplied).empty()) {
        gpu.download(s);  // the message names the fastest particle: it needs current velocities
        r.status = "unstable";
        r.message = instability_message(s, e, supplied);
        break;
      }
      if (output_due) gpu.download(s);
      else if (!s.config.probes.empty()) gpu.download_kinematics(s);
      if (history_due) history.write(s, e);
      if (output_due && results) results->write(s);
    }
    if (s.config.checkpoint_every > 0 && s.step % s.config.checkpoint_every == 0) {
      gpu.download(s);
      write_checkpoint(s, o.out_dir + "/checkpoint.h5");
    }
    if (g_interrupted) {
      r.status = "interrupted";
      r.message = "interrupted by the user at step " + std::to_string(s.step) + "; continue with --restart " +
                  o.out_dir + "/checkpoint.h5";
      gpu.compute_forces(s);  // diagnostics at this step (no bond can break again here)
      e = gpu.measure(s);
      gpu.download(s);
      history.write(s, e);
      if (results) results->write(s);
      write_checkpoint(s, o.out_dir + "/checkpoint.h5");
      break;
    }
    if (o.progress) {
      const auto now = std::chrono::steady_clock::now();
      if (std::chrono::duration<double>(now - last_report).count() > 2.0) {
        last_report = now;
        print_progress(s.step, total_steps, s.time, s.step - first_step,
                       std::chrono::duration<double>(now - t0).count(), e.max_damage);
      }
    }
  }
  std::signal(SIGINT, previous);
  // The last step always measures (output_due), which synchronises: the clock sees the GPU's work.
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.steps = s.step - first_step;
  r.bond_updates_per_s = r.wall_s > 0 ? static_cast<double>(s.bond_count()) * r.steps / r.wall_s : 0.0;
  if (r.status == "completed") {
    r.final_energies = gpu.measure(s);
    gpu.download(s);
    write_checkpoint(s, o.out_dir + "/checkpoint.h5");
  } else {
    r.final_energies = e;
  }
  return r;
}

}  // namespace breccia::solver
