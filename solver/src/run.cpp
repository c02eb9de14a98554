#include "breccia/solver/run.hpp"

#include <omp.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <ctime>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <tuple>
#if defined(__GLIBC__)
#include <malloc.h>  // malloc_trim
#endif

#include "breccia/common/error.hpp"
#include "breccia/common/json_file.hpp"
#include "breccia/common/output_file.hpp"
#include "breccia/common/reproducible_sum.hpp"
#include "breccia/common/step_count.hpp"
#include "breccia/common/units.hpp"
#include "breccia/common/yaml_input.hpp"
#include "breccia/solver/boundary_field.hpp"
#include "breccia/solver/correspondence.hpp"
#include "breccia/solver/distributed_setup.hpp"
#include "breccia/solver/outputs.hpp"

namespace breccia::solver {
namespace {

std::atomic<bool> g_interrupted{false};

// This process's resident set now (VmRSS of /proc/self/status, Linux), in MB; -1 where it
// cannot be read.
double resident_mb() {
  std::FILE* f = std::fopen("/proc/self/status", "r");
  if (!f) return -1.0;
  char line[256];
  double kb = -1.0;
  while (std::fgets(line, sizeof line, f))
    if (std::sscanf(line, "VmRSS: %lf kB", &kb) == 1) break;
  std::fclose(f);
  return kb < 0 ? -1.0 : kb / 1024.0;
}
void on_sigint(int) { g_interrupted = true; }

void write_summary(const PdSystem& s, const RunOptions& o, const RunResult& r, double setup_s) {
  const size_t n = s.whole_n();  // (a distributed run's rank 0 holds its window: the body's count)
  const double bytes_per_particle =
      (s.bond_count() * s.bytes_per_bond_entry() +
       n * (13 * sizeof(double) + sizeof(int64_t) + sizeof(int32_t) + 1)) / std::max<double>(1.0, n);
  // json_file.hpp escapes the strings (a message may quote a path); a value that is not
  // finite (a run stopped for blowing up) is written as null and named in non_finite, so
  // the file stays JSON that any strict parser reads.
  Json j;
  std::vector<std::string> non_finite;
  auto number = [&](const char* key, double v) { set_json_number(j, key, v, &non_finite); };
  j["case"] = s.config.name;
  j["status"] = r.status;
  j["message"] = r.message;
  j["model"] = s.config.model_name;
  j["backend"] = o.backend;
  j["precision"] = s.f32.active ? "float32" : "float64";
  j["threads"] = omp_get_max_threads();
  j["ranks"] = o.ranks;
  // Whether each rank built only its own bonds (distributed_setup.hpp) or the whole system.
  j["distributed_setup"] = !s.distributed_rows.empty();
  j["dimension"] = s.dimension;
  j["particles"] = n;
  j["bonds"] = s.bond_count();
  // The bond entries each rank's set-up built (PdSystem::setup_candidate_entries), rank 0 first.
  j["setup_entries_per_rank"] = {{"candidates", s.setup_candidate_entries}, {"kept", s.setup_kept_entries}};
  j["setup_window_particles_per_rank"] = s.setup_window_particles;  // the family search's particles
  j["setup_system_particles_per_rank"] = s.setup_system_particles;  // the set-up system's per-particle arrays
  j["setup_file_rows_per_rank"] = s.setup_file_rows;  // the most particle-file rows the set-up held at once
  if (!s.setup_offsets_rows.empty()) j["offsets_rows_per_rank"] = s.setup_offsets_rows;  // the longest row offsets held
  if (!s.file_offsets_rows.empty()) j["file_offsets_rows_per_rank"] = s.file_offsets_rows;  // results.h5's bond-list offsets held
  if (!s.restart_rows.empty()) j["restart_rows_per_rank"] = s.restart_rows;  // a checkpoint's per-particle rows read
  if (!s.broken_bits_bytes.empty()) j["broken_bits_bytes_per_rank"] = s.broken_bits_bytes;  // an output's broken bits held
  number("mean_family_size", static_cast<double>(s.bond_count()) / std::max<size_t>(1, n));
  number("bytes_per_particle", bytes_per_particle);
  j["steps"] = s.step;
  j["steps_this_run"] = r.steps;
  number("time_s", s.time);
  number("dt_s", s.dt);
  number("stable_dt_s", s.stable_dt);
  number("silling_askari_dt_s", s.silling_askari_dt);
  number("setup_wall_s", setup_s);
  number("results_header_wall_s", r.results_header_wall_s);
  number("final_checkpoint_wall_s", r.final_checkpoint_wall_s);
  Json phases;  // where the set-up's time went (setup_system)
  for (const auto& [name, seconds] : s.setup_phases) phases[name] = seconds;
  j["setup_phases_s"] = phases;
  Json phases_cpu;  // the same phases' process CPU time (all threads)
  for (size_t k = 0; k < s.setup_phases.size() && k < s.setup_phases_cpu.size(); ++k)
    phases_cpu[s.setup_phases[k].first] = s.setup_phases_cpu[k];
  j["setup_phases_cpu_s"] = phases_cpu;
  j["stable_step_force_passes"] = s.stable_step_passes;
  j["stable_step_particles"] = static_cast<int64_t>(s.stable_step_particles);  // the region it moved
  number("wall_s", r.wall_s);
  number("bond_updates_per_s", r.bond_updates_per_s);
  number("loop_cpu_s", r.cpu_s);
  number("bond_updates_per_cpu_s", r.cpu_s > 0 ? s.bond_count() * static_cast<double>(r.steps) / r.cpu_s : 0.0);
  j["bond_updates_note"] = "bond entries (each bond counted once from each end) x steps / wall time of the time loop";
  number("kinetic_J", r.final_energies.kinetic);
  number("strain_J", r.final_energies.strain);
  number("external_work_J", s.external_work);
  number("dissipated_J", s.dissipated_energy);
  number("max_damage", r.final_energies.max_damage);
  if (s.gas.active) {  // a gas load: its state at the end and what its passes cost
    number("gas_pressure_Pa", s.gas.pressure);
    number("gas_cavity_volume_m3", s.gas.volume);
    number("gas_work_J", s.gas.work);
    j["gas_vented"] = s.gas.vented;
    number("gas_wall_s", s.gas.wall_s);
    number("gas_share_of_loop", r.wall_s > 0 ? s.gas.wall_s / r.wall_s : 0.0);
    number("gas_cpu_s", s.gas.cpu_s);  // the same share in process CPU time: not inflated by other load
    number("gas_cpu_share_of_loop", r.cpu_s > 0 ? s.gas.cpu_s / r.cpu_s : 0.0);
  }
  if (r.kernel_times) {  // --kernel-times: each kernel's GPU time over the timed steps
    const KernelTimes& t = *r.kernel_times;
    Json kernels = Json::array();
    for (const KernelTime& k : t.kernels)
      kernels.push_back({{"name", k.name},
                         {"launches", k.launches},
                         {"seconds", k.seconds},
                         {"us_per_step", t.us_per_step(k.seconds)}});
    j["kernel_times"] = {{"warmup_steps", t.warmup_steps},
                         {"steps_timed", t.steps_timed},
                         {"seconds", t.seconds()},
                         {"kernels", kernels},
                         {"note", "CUDA events around every launch of the timed steps, summed per kernel name"}};
  }
  if (r.device_memory) {  // a GPU run: its device copy's memory, and how many such particles would fit
    const DeviceMemory& d = *r.device_memory;
    // (under MPI rank 0's device holds its own particles and ghosts, not the body's n: no per-particle figure)
    const double per_particle =
        n > 0 && o.ranks == 1 ? static_cast<double>(d.system_bytes) / static_cast<double>(n) : 0.0;
    j["device_memory"] = {
        {"system_bytes", d.system_bytes},
        {"bytes_per_particle", per_particle},
        {"free_before_bytes", d.free_before_bytes},
        {"total_bytes", d.total_bytes},
        {"particles_that_would_fit", per_particle > 0 ? static_cast<int64_t>(d.free_before_bytes / per_particle) : 0},
        {"note", "cudaMemGetInfo: free memory before the upload less free memory after it (or at the loop's end); "
                 "particles_that_would_fit: the free memory before it over bytes_per_particle, same model and "
                 "family size"}};
  }
  j["broken_bonds"] = r.final_energies.broken_half_bonds / 2;
  // What the time loop holds (RunResult::loop_resident_mb): per rank, rank 0 first.
  if (!r.loop_resident_mb.empty()) j["loop_resident_mb"] = r.loop_resident_mb;
  // What rank 0 of a distributed run holds whole after it (RunResult::loop_whole_bytes_rank0).
  if (r.loop_whole_bytes_rank0 >= 0) j["loop_whole_bytes_rank0"] = r.loop_whole_bytes_rank0;
  j["non_finite"] = non_finite;
  if (!non_finite.empty())
    j["non_finite_note"] = "these values were not finite when the run stopped (status " + r.status +
                           "): written as null; the last good values are in history.csv";
  write_json_file(o.out_dir + "/summary.json", j);
}

}  // namespace

void print_progress(long long step, long long total_steps, double time_s, long long recent_steps, double recent_s,
                    double max_damage) {
  const double rate = recent_steps / std::max(recent_s, 1e-9);
  std::fprintf(stderr, "step %lld/%lld  t = %.4e s  %.1f steps/s  ETA %.1f s  max damage %.3f\n", step, total_steps,
               time_s, rate, (total_steps - step) / std::max(rate, 1e-9), max_damage);
}

Instability instability_kind(const PdSystem& s, const Energies& e, double energy_scale,
                             std::optional<double> nonaffine) {
  // Correspondence: zero-energy modes grow without a blow-up of the energy (correspondence.cpp).
  if (e.finite && nonaffine && zero_energy_modes_grew(e, *nonaffine)) return Instability::ZeroEnergyModes;
  if (!e.finite) return Instability::NonFinite;
  // Energy far above everything put in: an exponentially growing mode. Not at step 1: a
  // load that starts from zero gives the particles the second half-kick's velocity before
  // the trapezoid has any displacement to count work on (external work 0, kinetic > 0); from
  // step 2 the two lag by at most about 2x, far below the 10x that marks a growing mode.
  // The energy judged is the body's with what fracture booked as dissipated: energy the
  // solver created shows in either. (Counted as supplied instead, as until 2026-12-07, the
  // dissipation hid a blow-up whose breaking bonds booked what the growing mode had put in
  // them: correspondence's breaks book the drop of the particle's energy, which a blow-up
  // makes as large as it likes; a pre-cracked plate under a sudden load booked 2e14 J and
  // ran to its end with every bond broken.)
  const double energy = e.kinetic + e.strain + std::max(s.dissipated_energy, 0.0);
  if (s.step >= 2 && energy > 10.0 * energy_scale && energy > 1e-30) return Instability::EnergyGrowth;
  return Instability::None;
}

std::string instability_text(const PdSystem& s, const Energies& e, double energy_scale, Instability kind,
                             double nonaffine, const NamedParticle& where) {
  if (kind == Instability::None) return "";
  if (kind == Instability::ZeroEnergyModes) return zero_energy_mode_message(s, e, nonaffine, where);
  std::ostringstream m;
  const auto at = [&] {
    std::ostringstream w;
    w << "particle " << where.file_index << " at (" << where.x0[0] << ", " << where.x0[1] << ", " << where.x0[2]
      << ")";
    return w.str();
  };
  if (kind == Instability::NonFinite) {
    m << "run became unstable at step " << s.step << " (t = " << s.time << " s): " << at()
      << " has a non-finite displacement or velocity";
  } else {
    m << "run became unstable at step " << s.step << " (t = " << s.time << " s): energy "
      << e.kinetic + e.strain + std::max(s.dissipated_energy, 0.0)
      << " J (kinetic, strain and dissipated) grew beyond 10x the energy supplied (" << energy_scale << " J); fastest "
      << at();
  }
  m << ". Likely cause: time step too large (dt = " << s.dt << " s, stable step 2/omega_max = " << s.stable_dt
    << " s)";
  if (s.dt <= s.stable_dt) m << ", or a horizon too small for irregular particles (raise model.horizon_factor)";
  m << ". The last good output is kept.";
  return m.str();
}

std::pair<double, int64_t> first_fastest(const std::vector<double>& v, size_t count) {
  int64_t i = 0;
  double vmax = -1;
  for (size_t k = 0; k < count; ++k) {
    const double v2 = v[3 * k] * v[3 * k] + v[3 * k + 1] * v[3 * k + 1] + v[3 * k + 2] * v[3 * k + 2];
    if (v2 > vmax) {
      vmax = v2;
      i = static_cast<int64_t>(k);
    }
  }
  return {vmax, i};
}

std::pair<double, int64_t> first_largest(const std::vector<double>& values, size_t count) {
  size_t i = 0;
  for (size_t k = 1; k < count; ++k)
    if (values[k] > values[i]) i = k;
  return {count > 0 ? values[i] : 0.0, static_cast<int64_t>(i)};
}

std::string instability_message(const PdSystem& s, const Energies& e, double energy_scale) {
  std::optional<double> nonaffine;
  if (s.config.model == PdModel::Correspondence && s.corr_nonaffine.size() == s.n) nonaffine = nonaffine_energy(s);
  const Instability kind = instability_kind(s, e, energy_scale, nonaffine);
  size_t i = 0;  // the particle the message names
  if (kind == Instability::ZeroEnergyModes) i = static_cast<size_t>(first_largest(s.corr_nonaffine, s.n).second);
  else if (kind == Instability::NonFinite) i = e.bad_particle >= 0 ? static_cast<size_t>(e.bad_particle) : 0;
  else if (kind == Instability::EnergyGrowth) i = static_cast<size_t>(first_fastest(s.v, s.n).second);
  else return "";
  NamedParticle where;
  where.file_index = s.original_index[i];
  for (int d = 0; d < 3; ++d) where.x0[d] = s.x0[3 * i + d];
  return instability_text(s, e, energy_scale, kind, nonaffine.value_or(0.0), where);
}

long long relax_to_equilibrium(PdSystem& s, bool progress, const RelaxHooks& hooks) {
  // A distributed run passes its force pass (with the halo exchange) and its sum over ranks.
  const auto forces = hooks.forces ? hooks.forces : [](PdSystem& sys) { cpu_compute_forces(sys); };
  // And its external forces: a gas load's sums and front are taken over every rank.
  const auto external = hooks.external ? hooks.external : [](PdSystem& sys, double t) { compute_external(sys, t); };
  // Its sums steer the iteration (damping, convergence): they are taken reproducibly, so
  // that P ranks, or any thread count, follow one process's path bit for bit.
  std::vector<double> sums_out;
  const auto sum_terms = [&](int quantities, const std::function<double(size_t, int)>& term) {
    reproducible_sums(3 * s.n, quantities, term, sums_out, hooks.max, hooks.sum);
    return sums_out;
  };
  // Fictitious density rho* = 1.2 rho omega_max^2 / 4 makes the unit step stable.
  const size_t n3 = 3 * s.n;
  const double omega2 = std::pow(2.0 / s.stable_dt, 2);
  std::vector<double> lam(s.n), f_prev(n3, 0.0), v_half(n3, 0.0);
  for (size_t i = 0; i < s.n; ++i) lam[i] = 1.2 * s.density[i] * omega2 / 4.0;
  apply_constraints(s, 1e300, 0.0);  // prescribed values at their full size
  for (auto& x : s.v) x = 0.0;
  external(s, 0.0);
  const double load_norm =
      std::sqrt(sum_terms(1, [&](size_t k, int) { return s.body[k] * s.body[k] * s.volume[k / 3]; })[0]);
  auto is_free = [&](size_t k) { return !(s.fixed_dof[k / 3] & (1u << (k % 3))); };
  const auto start = std::chrono::steady_clock::now();
  auto last = start;
  for (long long it = 0; it < s.config.adr_max_steps; ++it) {
    commit_min_stretch(s);
    if (s.gas.active && it > 0) external(s, 0.0);  // the gas follows the cavity's volume
    forces(s);
    // Terms per component: the Rayleigh quotient's numerator and denominator of the local
    // stiffness (Kilic & Madenci's damping), the squared residual force, and without a load
    // the squared reaction on the prescribed components (the residual's scale, below).
    const bool unloaded = !(load_norm > 0);
    const std::vector<double> totals = sum_terms(unloaded ? 4 : 3, [&](size_t k, int q) {
      if (q == 3) return is_free(k) ? 0.0 : std::pow(s.force[k] + s.body[k], 2) * s.volume[k / 3];
      if (!is_free(k)) return 0.0;
      if (q == 0) {
        if (it == 0 || v_half[k] == 0.0) return 0.0;
        const double f = (s.force[k] + s.body[k]) / lam[k / 3];
        const double kdiag = -(f - f_prev[k]) / v_half[k];
        return s.u[k] * kdiag * s.u[k];
      }
      if (q == 1) return s.u[k] * s.u[k];
      return std::pow(s.force[k] + s.body[k], 2) * s.volume[k / 3];
    });
    const double num = totals[0], den = totals[1], residual = std::sqrt(totals[2]);
    // The residual is judged against the load; a body driven by prescribed displacements alone
    // has none, and there the reaction on the prescribed components sets the scale (an
    // absolute 1 made one bar converge at E = 1 kPa and not at 10 GPa).
    double ref = unloaded ? std::sqrt(totals[3]) : load_norm;
    if (!(ref > 0)) ref = 1.0;
    if (it > 10 && residual <= s.config.adr_tolerance * ref) {
      s.step = it;
      return it;
    }
    double damping = (den > 0 && num > 0) ? 2.0 * std::sqrt(num / den) : 0.0;
    damping = std::min(damping, 1.9);
    for (size_t k = 0; k < n3; ++k) {
      if (!is_free(k)) continue;
      const double f = (s.force[k] + s.body[k]) / lam[k / 3];
      v_half[k] = it == 0 ? 0.5 * f : ((2.0 - damping) * v_half[k] + 2.0 * f) / (2.0 + damping);
      s.u[k] += v_half[k];
      f_prev[k] = f;
    }
    if (progress) {
      const auto now = std::chrono::steady_clock::now();
      if (std::chrono::duration<double>(now - last).count() > 2.0) {
        last = now;
        std::fprintf(stderr, "[adr] iteration %lld  residual/load %.3e  (tolerance %.1e)\n", it, residual / ref,
                     s.config.adr_tolerance);
      }
    }
  }
  return -1;
}

namespace {

class CpuBackend final : public StepBackend {
public:
  void step(PdSystem& s) override { cpu_step(s); }
  Energies measure(PdSystem& s) override { return solver::measure(s); }
  void compute_forces(PdSystem& s) override { cpu_compute_forces(s); }
};

long long total_steps_of(const PdSystem& s, const RunOptions& o) {
  if (o.steps) return *o.steps + s.step;
  if (s.config.steps) return *s.config.steps;
  return steps_to_reach(*s.config.end_time, s.dt, s.config.file, "time.end");
}

}  // namespace

bool StepBackend::unstable(PdSystem& s, const Energies& e, double energy_scale, bool root) {
  return any(root && !instability_message(s, e, energy_scale).empty());
}

std::string StepBackend::instability(PdSystem& s, const Energies& e, double energy_scale) {
  download(s);  // the message names the fastest particle: it needs velocities
  return instability_message(s, e, energy_scale);
}

void StepBackend::checkpoint(PdSystem& s, const std::string& path, bool root, bool downloaded) {
  if (!downloaded) download(s);
  if (root) write_checkpoint(s, path);
}

void StepBackend::output(PdSystem& s, ResultsWriter* results, const std::string&) {
  download(s);
  if (results) results->write(s);
}

void StepBackend::first_output(PdSystem& s, ResultsWriter* results, const std::string&) {
  if (results) results->write(s);
}

RunResult run_time_loop(PdSystem& s, const RunOptions& o, StepBackend& backend, ResultsWriter* results,
                        HistoryWriter* history) {
  RunResult r;
  const bool restart = !o.restart_file.empty();
  const bool root = o.root;  // writes and judges; the others follow its decisions (backend.any)
  const long long total_steps = total_steps_of(s, o);
  Energies e = backend.measure(s);
  double supplied = e.kinetic + e.strain;  // the scale against which blow-up is judged
  // A history line: its particles' values from the backend (every process takes part), the
  // line from the root.
  const auto write_history = [&] {
    const std::optional<HistoryParticles> particles = backend.history_particles(s);
    if (root) history->write(s, e, particles ? &*particles : nullptr);
  };
  if (!restart) {
    write_history();  // host and backend agree before the first step
    backend.first_output(s, results, o.out_dir);
  }
  const long long first_step = s.step;
  if (o.kernel_times_warmup && !backend.time_kernels(*o.kernel_times_warmup) && root && o.progress)
    std::fprintf(stderr, "note: --kernel-times: the time loop runs on the CPU, which launches no GPU kernels; "
                         "nothing is timed\n");
  const std::clock_t cpu0 = std::clock();
  const auto t0 = std::chrono::steady_clock::now();
  auto last_report = t0;
  long long last_report_step = s.step;
  r.status = "completed";
  while (s.step < total_steps) {
    // Damage and energy density only where something will read them.
    const long long next = s.step + 1;
    s.diagnostics = next % s.config.history_every == 0 || next % s.config.output_every == 0 ||
                    next == total_steps || (s.config.checkpoint_every > 0 && next % s.config.checkpoint_every == 0);
    backend.step(s);
    s.diagnostics = true;
    const bool history_due = s.step % s.config.history_every == 0 || s.step == total_steps;
    const bool output_due = s.step % s.config.output_every == 0 || s.step == total_steps;
    if (history_due || output_due) {
      e = backend.measure(s);
      supplied = std::max(supplied, std::fabs(s.external_work));  // dissipation is judged, not supplied
      supplied = std::max(supplied, 1e-300);
      if (backend.unstable(s, e, supplied, root)) {
        r.status = "unstable";
        const std::string message = backend.instability(s, e, supplied);
        if (root) r.message = message;
        break;
      }
      if (output_due) backend.output(s, results, o.out_dir);
      else if (!s.config.probes.empty() || s.config.indenter.enabled) backend.download_kinematics(s);
      if (history_due) write_history();
    }
    if (s.config.checkpoint_every > 0 && s.step % s.config.checkpoint_every == 0)
      backend.checkpoint(s, o.out_dir + "/checkpoint.h5", root);
    if (backend.any(g_interrupted)) {
      r.status = "interrupted";
      r.message = "interrupted by the user at step " + std::to_string(s.step) + "; continue with --restart " +
                  o.out_dir + "/checkpoint.h5";
      backend.compute_forces(s);  // diagnostics at this step (no bond can break again here)
      e = backend.measure(s);
      backend.download(s);
      // Not twice where this step already wrote them (a repeated time in results.xdmf and
      // history.csv, kept by a restart).
      if (!history_due) write_history();
      if (!output_due) backend.output(s, results, o.out_dir);  // a distributed one written by every rank together
      backend.checkpoint(s, o.out_dir + "/checkpoint.h5", root, true);
      break;
    }
    if (o.progress) {
      const auto now = std::chrono::steady_clock::now();
      if (std::chrono::duration<double>(now - last_report).count() > 2.0) {
        print_progress(s.step, total_steps, s.time, s.step - last_report_step,
                       std::chrono::duration<double>(now - last_report).count(), e.max_damage);
        last_report = now;
        last_report_step = s.step;
      }
    }
  }
  // The last step always measures, which synchronises a device: the clock sees its work.
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.steps = s.step - first_step;
  r.cpu_s = static_cast<double>(std::clock() - cpu0) / CLOCKS_PER_SEC;
  r.bond_updates_per_s = r.wall_s > 0 ? static_cast<double>(s.bond_count()) * r.steps / r.wall_s : 0.0;
  if (const double mb = resident_mb(); mb >= 0) r.loop_resident_mb = {mb};
  r.kernel_times = backend.kernel_times();  // the loop's launches only (resolves every event)
  r.device_memory = backend.device_memory();
  if (r.kernel_times && root && o.progress) std::fputs(kernel_times_table(*r.kernel_times).c_str(), stderr);
  if (r.status == "completed") {
    r.final_energies = backend.measure(s);
    backend.download(s);
    const auto checkpoint_t0 = std::chrono::steady_clock::now();
    backend.checkpoint(s, o.out_dir + "/checkpoint.h5", root, true);
    r.final_checkpoint_wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - checkpoint_t0).count();
  } else {
    r.final_energies = e;
  }
  return r;
}

RunResult run_system(PdSystem& s, const RunOptions& o) {
  const bool restart = !o.restart_file.empty();
  // Ctrl-C from here on ends the run cleanly (checkpoint, outputs, exit 130).
  g_interrupted = false;
  auto previous = std::signal(SIGINT, on_sigint);
  // Only the root writes (the other ranks of a distributed run hold no gathered state).
  std::unique_ptr<ResultsWriter> results;
  std::unique_ptr<HistoryWriter> history;
  if (o.root) {
    std::filesystem::create_directories(o.out_dir);
    // The case as run (its variant and --set overrides applied): reports read values from it.
    if (!s.config.file.empty() && std::filesystem::exists(s.config.file))
      write_text_file(o.out_dir + "/case_as_run.yaml", Section::text_as_loaded(s.config.file));
  }
  const auto header_t0 = std::chrono::steady_clock::now();
  // The root alone opens the writers; a restart's results.h5 of another particle model or
  // format is refused there, and under mpirun that refusal is every rank's (refuse_together):
  // the other ranks would otherwise wait in the loop's first collective.
  refuse_together(o.setup_hooks.distributed, [&] {
    if (o.root && s.config.write_results) results = std::make_unique<ResultsWriter>(s, o.out_dir, restart);
  });
  const double header_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - header_t0).count();
  if (o.root) history = std::make_unique<HistoryWriter>(s, o.out_dir, restart);
  RunResult r;
  if (s.config.quasi_static) {
    const auto t0 = std::chrono::steady_clock::now();
    long long iters = 0;
    if (o.relax) {
      std::tie(iters, r.final_energies) = o.relax(s, o, results.get(), history.get());  // and its output group
    } else {
      iters = relax_to_equilibrium(s, o.progress);
      r.final_energies = measure(s);
    }
    r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    r.steps = iters < 0 ? s.config.adr_max_steps : iters;
    r.status = iters < 0 ? "not_converged" : "converged";
    if (iters < 0) r.message = "ADR did not reach the tolerance within time.adr_max_steps";
    if (history && !o.relax) history->write(s, r.final_energies);
    if (results && !o.relax) results->write(s);
  } else if (o.backend_loop) {
    r = o.backend_loop(s, o, results.get(), history.get());
  } else if (s.f32.active) {
    const std::unique_ptr<StepBackend> cpu32 = make_float32_backend(s);
    r = run_time_loop(s, o, *cpu32, results.get(), history.get());
  } else {
    CpuBackend cpu;
    r = run_time_loop(s, o, cpu, results.get(), history.get());
  }
  std::signal(SIGINT, previous);
  if (results && (r.status == "completed" || r.status == "converged")) results->mark_complete();
  r.results_header_wall_s = header_s;
  return r;
}

RunResult run_case(const CaseConfig& config, const RunOptions& o) {
  if (o.threads > 0) omp_set_num_threads(o.threads);
  const auto t0 = std::chrono::steady_clock::now();
  PdSystem s = setup_system(config, o.setup_hooks);
#if defined(__GLIBC__)
  // The set-up's temporaries back to the system: glibc keeps freed heap pages resident, and
  // once a large block was freed its mmap threshold rises, so later blocks (the stable step's
  // vectors, the temporaries freed before its end) come from the heap and stayed resident
  // through the loop (one process, 41^3 lattice: 10 MB more once the set-up freed its sample
  // counts earlier; docs/parallel.md, Memory). A distributed run trims again when its global
  // system lets go (release_global_for_loop).
  malloc_trim(0);
#endif
  if (!o.restart_file.empty()) read_checkpoint(s, o.restart_file, o.setup_hooks.distributed.rank);
#ifdef BRECCIA_PARALLEL_HDF5
  // A distributed run reads no particle file rows after its set-up: the ranks write
  // results.h5's /particles from their systems' rows (ResultsWriter::write_particles_together)
  // and a lattice's particles.h5 is made again (lattice_model). So they go here, before the
  // writers open their files, not at the loop's start (release_global_for_loop).
  if (!s.distributed_rows.empty()) {
    ParticleModel& pm = s.particles;
    std::vector<double>().swap(pm.position_m);
    std::vector<double>().swap(pm.volume_m3);
    std::vector<double>().swap(pm.spacing_m);
    std::vector<int32_t>().swap(pm.material_id);
  }
#endif
  const double setup_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (o.progress) {
    std::fprintf(stderr,
                 "breccia-solve: %s, %s %dD, %zu particles, %zu bonds (%.1f per particle), horizon %.4g m\n"
                 "  stable step 2/omega_max = %.4e s (Silling-Askari bound %s), dt = %.4e s (safety %.2f)\n"
                 "  set-up %.2f s\n",
                 config.name.c_str(), config.model_name.c_str(), s.dimension, s.whole_n(), s.bond_count(),
                 static_cast<double>(s.bond_count()) / std::max<size_t>(1, s.whole_n()), s.horizon.empty() ? 0.0 : s.horizon[0],
                 s.stable_dt,
                 s.silling_askari_dt > 0 ? (short_number(s.silling_askari_dt) + " s").c_str() : "n/a for LPS", s.dt,
                 config.safety, setup_s);
    std::string phases;
    for (const auto& [name, seconds] : s.setup_phases) {
      char item[96];
      std::snprintf(item, sizeof item, "%s%s %.2f s", phases.empty() ? "" : ", ", name.c_str(), seconds);
      phases += item;
    }
    std::fprintf(stderr, "  set-up phases: %s (stable step: %d force passes over %zu of %zu particles)\n", phases.c_str(),
                 s.stable_step_passes, s.stable_step_particles, s.whole_n());
  }
  // Boundary values in time, sampled over the run now that its length is known, before the
  // writers open their files. Under mpirun each rank samples its system's constraint
  // particles (its window's), and the first refusal in rank order is every rank's, printed once.
  if (!config.quasi_static) {
    // A distributed set-up's global system let go of its reference positions at the stable
    // step's cut: the rank's system (its owned constraint particles, their positions) holds them.
    const PdSystem* held = &s;
    if (!s.distributed_rows.empty() && o.setup_hooks.stable_step_ranks)
      if (const StableStepRanks ranks = o.setup_hooks.stable_step_ranks(); ranks.system) held = ranks.system;
    refuse_together(o.setup_hooks.distributed, [&] {
      if (!held->x0.empty()) check_boundary_fields_over_run(*held, static_cast<double>(total_steps_of(s, o)) * s.dt);
    });
  }
  RunResult r = run_system(s, o);
  if (o.root) write_summary(s, o, r, setup_s);
  return r;
}

}  // namespace breccia::solver
