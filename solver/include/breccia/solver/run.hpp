#pragma once
// Running a PD case: the time loop with outputs, progress, instability detection,
// checkpoints and Ctrl-C, and adaptive dynamic relaxation for quasi-static problems.
#include <functional>
#include <optional>
#include <string>
#include <utility>

#include "breccia/solver/kernel_times.hpp"
#include "breccia/solver/pd_system.hpp"

namespace breccia::solver {

struct RunResult;
struct PdSystem;
class ResultsWriter;
class HistoryWriter;

struct RunOptions {
  std::string out_dir = "out";
  int threads = 0;                      // 0: OpenMP default
  std::string restart_file;             // continue from this checkpoint
  std::optional<long long> steps;       // override the number of steps
  bool progress = true;
  std::string backend = "cpu";
  // This process writes the files and prints (false on the ranks other than 0 of a
  // distributed run, solver/mpi/: rank 0 writes history.csv, summary.json and, with serial
  // HDF5, every file from its gathered state).
  bool root = true;
  int ranks = 1;  // processes of the run (summary.json)
  // --kernel-times WARMUP: time every GPU launch with CUDA events after WARMUP steps
  // (kernel_times.hpp; summary.json `kernel_times`). A backend without kernels ignores it.
  std::optional<long long> kernel_times_warmup;
  // A backend's dynamic loop (the CUDA backend sets it; it runs run_time_loop with its own
  // StepBackend); empty: the CPU backend.
  std::function<RunResult(PdSystem&, const RunOptions&, ResultsWriter*, HistoryWriter*)> backend_loop;
  // What a distributed run shares of the set-up (its stable step's force passes, its bond
  // coefficients) between the ranks.
  SetupHooks setup_hooks;
  // A backend's dynamic relaxation (a distributed run's): the iterations (-1: not converged)
  // and the final state's energies, which the backend measures (a distributed set-up's global
  // system holds no bonds to measure them with); it writes the output group itself (the root's
  // writer is null on the other ranks). Empty: relax_to_equilibrium here.
  // It writes the history line too (the root's writer, null elsewhere), since a distributed
  // run's probes are read on their ranks.
  std::function<std::pair<long long, Energies>(PdSystem&, const RunOptions&, ResultsWriter*, HistoryWriter*)> relax;
};

// A GPU backend's memory (summary.json device_memory): the device memory its copy of the
// system took (the free memory before its upload less the free memory after it, or at the end
// of the loop if more), the memory free before it, and the device's total.
struct DeviceMemory {
  int64_t system_bytes = 0;
  int64_t free_before_bytes = 0;
  int64_t total_bytes = 0;
};

struct RunResult {
  std::string status;   // completed | unstable | interrupted | converged | not_converged
  long long steps = 0;  // steps taken in this invocation
  double wall_s = 0.0;
  double cpu_s = 0.0;  // process CPU time of the loop (all threads): robust on a shared machine
  double bond_updates_per_s = 0.0;
  Energies final_energies;
  std::string message;
  // The process's resident set (VmRSS, MB) when the time loop's last step is done, before the
  // final outputs: what the loop holds, where the peak (VmHWM) is usually the set-up's. One
  // value per rank of a distributed run (rank 0 first); empty where it cannot be read.
  std::vector<double> loop_resident_mb;
  // A distributed run: the bytes of whole per-particle and per-entry arrays rank 0's global
  // system holds after the loop and its final outputs (loop_state_bytes); -1 elsewhere.
  long long loop_whole_bytes_rank0 = -1;
  // --kernel-times: the GPU time of each kernel (this process's device; rank 0's under MPI).
  std::optional<KernelTimes> kernel_times;
  std::optional<DeviceMemory> device_memory;  // a GPU run's (this process's device; rank 0's under MPI)
  // Writes outside the set-up and the loop that the user still waits for (summary.json): the
  // results file's header (identity, particles, the bond list), before the first step, and the
  // checkpoint after the last. Wall seconds, the root's.
  double results_header_wall_s = 0.0;
  double final_checkpoint_wall_s = 0.0;
};

// What the time loop needs from a backend. The CPU backend works on the PdSystem in place;
// the CUDA backend keeps the state on the device and copies it back only when a file needs it.
class StepBackend {
public:
  virtual ~StepBackend() = default;
  virtual void step(PdSystem& s) = 0;            // one velocity-Verlet step
  virtual Energies measure(PdSystem& s) = 0;     // energies and checks at the current step
  virtual void compute_forces(PdSystem& s) = 0;  // refresh forces and diagnostics in place
  virtual void download(PdSystem&) {}            // whole state to the host (outputs, checkpoint)
  virtual void download_kinematics(PdSystem&) {} // u and v only (probes)
  // What the root's next history line reads of single particles (every process calls it):
  // none here, the history writer reads the host system (after download_kinematics or an
  // output); a distributed backend has their owners send them to the root.
  virtual std::optional<HistoryParticles> history_particles(PdSystem&) { return std::nullopt; }
  // Whether the run blew up at this step (instability_message's tests), the same answer on
  // every process (`root` judges), and then its message (every process calls it; the root's
  // is the one used): here from the host system, downloaded first (it names the fastest
  // particle); a distributed backend takes the sums and the particle over its ranks.
  virtual bool unstable(PdSystem& s, const Energies& e, double energy_scale, bool root);
  virtual std::string instability(PdSystem& s, const Energies& e, double energy_scale);
  // checkpoint.h5 at the current step (every process calls it; `downloaded`: download ran
  // since the last step). Here: the whole state to the host, written by the root alone; a
  // distributed backend with parallel HDF5 writes every rank's rows together instead.
  virtual void checkpoint(PdSystem& s, const std::string& path, bool root, bool downloaded = false);
  // An output step of the time loop: the whole state to the host, and the root's writer (the
  // only one; null elsewhere) writes the output group. A distributed backend with parallel
  // HDF5 has every rank write its rows together and gathers only what the root still reads.
  virtual void output(PdSystem& s, ResultsWriter* results, const std::string& out_dir);
  // The time loop's first output group, the set-up's state (not after a restart): here the
  // root's writer writes the host system as it is; a distributed backend with parallel HDF5
  // has every rank write its rows together, as for output().
  virtual void first_output(PdSystem& s, ResultsWriter* results, const std::string& out_dir);
  // A decision every process must take together (stop on Ctrl-C, on a blow-up): true if it
  // is true on any of them. One process: the flag itself.
  virtual bool any(bool flag) { return flag; }
  // --kernel-times: start timing every launch after `warmup_steps` steps of this run; false
  // where the backend launches no GPU kernels (the CPU's), which then times nothing.
  virtual bool time_kernels(long long /*warmup_steps*/) { return false; }
  // What it timed (every event resolved); nullopt where nothing was asked or timed.
  virtual std::optional<KernelTimes> kernel_times() { return std::nullopt; }
  // A GPU backend's memory (DeviceMemory); nullopt on the CPU.
  virtual std::optional<DeviceMemory> device_memory() { return std::nullopt; }
};

// The dynamic time loop shared by every backend: outputs, history, checkpoints, progress,
// instability detection and Ctrl-C. On the root (o.root) the history writer must exist
// (run_system creates it); other ranks pass null writers and write nothing.
RunResult run_time_loop(PdSystem& s, const RunOptions& o, StepBackend& backend, ResultsWriter* results,
                        HistoryWriter* history);

// Throws InputError for bad input; returns status "unstable" (and writes its message into
// summary.json) when the run blows up, keeping the last good output.
RunResult run_case(const CaseConfig& config, const RunOptions& options);
RunResult run_system(PdSystem& sys, const RunOptions& options);

// What adaptive dynamic relaxation needs beyond the PdSystem, for a distributed run: its
// force pass (with the halo exchange), its external forces (a gas load's sums and front over
// every rank) and a sum over ranks in place. Empty: one process.
struct RelaxHooks {
  std::function<void(PdSystem&)> forces;
  std::function<void(PdSystem&, double t)> external;  // compute_external's part (a gas load over ranks)
  std::function<void(double* values, int count)> sum;  // in place, over ranks
  std::function<void(double* values, int count)> max;
};

// Adaptive dynamic relaxation (Kilic & Madenci 2010) to static equilibrium; returns the
// number of iterations, or -1 if not converged within config.adr_max_steps.
long long relax_to_equilibrium(PdSystem& sys, bool progress, const RelaxHooks& hooks = {});

// One progress line on stderr: step, simulated time, rate, ETA, max damage. The rate (and the
// ETA from it) is that of the `recent_steps` made in the last `recent_s` seconds, since the
// previous line: a blast's steps get many times cheaper as its bonds break (the concrete demo
// on 2 threads: 11 steps/s at its start, 150 near its end), and the mean rate since the start
// put the ETA at 60 s with 14 s left (step 261 of 1,216).
void print_progress(long long step, long long total_steps, double time_s, long long recent_steps, double recent_s,
                    double max_damage);

// Checks a state for blow-up; empty string if healthy, else the message for the user.
std::string instability_message(const PdSystem& sys, const Energies& e, double energy_scale);

// Its parts, for a system that does not hold the state whole (a distributed run's): which
// blow-up the energies show (`nonaffine`: correspondence's non-affine energy,
// nonaffine_energy, where the model has one), and the message of one naming `where`: the
// particle of largest non-affine energy, the non-finite one (Energies::bad_particle), or the
// fastest (the first of equally fast ones).
enum class Instability { None, ZeroEnergyModes, NonFinite, EnergyGrowth };
Instability instability_kind(const PdSystem& sys, const Energies& e, double energy_scale,
                             std::optional<double> nonaffine);
std::string instability_text(const PdSystem& sys, const Energies& e, double energy_scale, Instability kind,
                             double nonaffine, const NamedParticle& where);
// The particle of [0, count) a message names: the first of the fastest (`v`: 3 per particle)
// with its squared speed, the first of the largest `values` with its value.
std::pair<double, int64_t> first_fastest(const std::vector<double>& v, size_t count);
std::pair<double, int64_t> first_largest(const std::vector<double>& values, size_t count);

}  // namespace breccia::solver
