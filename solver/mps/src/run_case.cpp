#include "breccia/mps/run_case.hpp"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>

#include "breccia/common/error.hpp"
#include "breccia/common/json_file.hpp"
#include "breccia/common/output_file.hpp"
#include "breccia/common/progress.hpp"
#include "breccia/common/step_count.hpp"
#include "breccia/common/yaml_input.hpp"
#include "breccia/mps/case_spec.hpp"
#include "breccia/mps/results_output.hpp"
#include "breccia/mps/simulation.hpp"
#include "breccia/mps/solid_case.hpp"

namespace breccia::mps {
namespace {

std::string fmt(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
}

template <class Model>
double particle_steps_per_s(const Model& sim, double loop_s) {
  return loop_s > 0 ? sim.size() * static_cast<double>(sim.steps()) / loop_s : 0.0;
}

// The last keys of summary.json, both formulations: threads, backend, wall and loop time,
// and the rate.
template <class Model>
void add_timing(Json& j, const Model& sim, double wall_s, double loop_s) {
  j["threads"] = omp_get_max_threads();
  j["backend"] = sim.backend_description();
  j["wall_time_s"] = json_number(wall_s);
  j["step_loop_s"] = json_number(loop_s);
  j["particle_steps_per_s"] = json_number(particle_steps_per_s(sim, loop_s));
}

template <class Model>
void report_timing(const Model& sim, double wall_s, double loop_s, const std::string& out_dir, bool quiet) {
  if (quiet) return;
  std::fprintf(stderr, "mps: %lld steps in %.2f s (%.3g particle-steps/s); outputs in %s\n", sim.steps(), wall_s,
               particle_steps_per_s(sim, loop_s), out_dir.c_str());
}

// The time loop both formulations share. results.h5 is written into its temporary file and
// committed only after the last output, so a run stopped by an error leaves no file that
// reads as complete. `after_step` collects per-step maxima; `hint` says what to change when
// the velocities turn non-finite. Returns the loop's wall time in seconds.
template <class Model, class AfterStep>
double run_time_loop(Model& sim, const CaseSpec& spec, const std::string& case_file, const std::string& out_dir,
                     const std::string& content_id, long long total_steps, OutputFile& results,
                     const std::function<void()>& record, AfterStep after_step, const char* hint) {
  const auto loop_start = std::chrono::steady_clock::now();
  std::function<void()> write_xdmf;
  {
    MpsResultsWriter writer(results.temp_path().string(), out_dir, spec, case_file, content_id, sim);
    writer.write(sim);
    record();
    Progress progress("mps", total_steps, spec.progress ? 5.0 : 1e300);
    for (long long s = 1; s <= total_steps; ++s) {
      sim.step();
      if (s % spec.history_every == 0) record();
      after_step();
      if (spec.snapshot_every > 0 && s % spec.snapshot_every == 0 && s != total_steps) writer.write(sim);
      if ((s % 100 == 0 || s == total_steps) && !std::isfinite(sim.kinetic_energy_j()))
        throw RunError("mps: velocities became non-finite at step " + std::to_string(s) + " (" + hint + ")");
      progress.update(s, "t=" + fmt(sim.time_s()) + " s");
    }
    if (total_steps > 0) writer.write(sim);  // with no step the start is the end: one group at t = 0
    writer.mark_complete();
    write_xdmf = writer.xdmf_writer();
    if (spec.progress) progress.finish("t=" + fmt(sim.time_s()) + " s");
  }
  results.commit();
  write_xdmf();  // (results.xdmf names results.h5: written once that is there)
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - loop_start).count();
}

// Once the case is built (both formulations): the steps to run, to time.end (steps_to_reach
// refuses a unit slip) or to --steps (max_steps >= 0) if that comes first, and the case as run
// (its variant and --set overrides applied; reports read values from it), written only now
// so that a case refused while it was built leaves the folder's earlier one in place.
long long begin_run(const CaseSpec& spec, double dt_s, const std::string& case_file, const std::string& out_dir,
                    long long max_steps) {
  long long total_steps = steps_to_reach(spec.end_time_s, dt_s, case_file, "time.end");
  if (std::filesystem::exists(case_file))
    write_text_file(std::filesystem::path(out_dir) / "case_as_run.yaml", Section::text_as_loaded(case_file));
  return max_steps >= 0 ? std::min(total_steps, max_steps) : total_steps;
}

// The stress formulation (solid.hpp): same files, with stress and plastic strain in the
// snapshots and the energy terms of the stress solid in history.csv.
int run_solid(const CaseSpec& spec, const std::string& case_file, const std::string& out_dir,
              std::unique_ptr<SolidStepDevice> (*device)(const Solid&), long long max_steps, bool quiet) {
  const auto wall_start = std::chrono::steady_clock::now();
  std::string content_id;
  Solid sim = make_solid(spec, &content_id);
  if (device) sim.attach_device(device(sim));
  if (spec.progress) std::fprintf(stderr, "mps: backend %s\n", sim.backend_description().c_str());
  const long long total_steps = begin_run(spec, sim.dt_s(), case_file, out_dir, max_steps);
  if (!quiet)
    std::fprintf(stderr,
               "mps (stress): %zu particles, %zu bonds, %dD; spacing %.4g m, re %.3g spacing; c_L %.1f m/s; dt %.4g s "
               "(safety %.2f x spacing / c_L); %lld steps; plasticity %s; pressure force %s; hourglass %.3g\n",
               sim.size(), sim.bonds().size(), sim.dimension(), sim.spacing_m(), spec.re_over_spacing,
               sim.p_wave_speed(), sim.dt_s(), spec.safety, total_steps, sim.law().plastic ? "von Mises" : "none",
               spec.repulsive_pressure ? "repulsive" : "conservative", spec.hourglass);
  if (sim.law().viscous_time_s > 0.0 && !quiet)
    std::fprintf(stderr,
                 "mps (stress): material damping %.3g at %.4g Hz (beta %.4g s); the step above includes its "
                 "stability factor %.4f\n",
                 spec.material.damping_ratio, spec.material.damping_frequency_hz, sim.law().viscous_time_s,
                 damped_step_factor(sim.law().viscous_time_s, sim.p_wave_speed(), sim.spacing_m()));
  std::vector<int> probe_particle;
  for (const auto& p : spec.probes) probe_particle.push_back(sim.nearest_particle(p.position_m));
  const std::filesystem::path dir(out_dir);
  OutputFile results(dir / "results.h5");
  std::ostringstream history;
  history << "time_s";
  for (const auto& p : spec.probes) history << "," << p.name << "_" << p.field;
  if (sim.law().plastic) history << ",plastic_fraction";
  if (sim.fracture()) history << ",failed_particles,cut_bonds,max_separation_stress_Pa";
  if (spec.energy) history << ",kinetic_energy_J,stress_work_J,hourglass_energy_J,contact_energy_J,gravity_energy_J";
  // Contact (docs/mps.md, "Contact"): particle pairs in contact, friction dissipation, free rigid bodies.
  const bool frictional = std::any_of(spec.rigid_bodies.begin(), spec.rigid_bodies.end(),
                                      [](const RigidBodySpec& r) { return r.friction.static_friction > 0; }) ||
                          (spec.floor && spec.floor->friction.static_friction > 0) ||
                          (spec.particle_contact && spec.particle_contact->friction.static_friction > 0);
  std::vector<size_t> free_bodies;
  for (size_t k = 0; k < sim.contact().polygon_count(); ++k)
    if (!sim.contact().polygon(k).fixed) free_bodies.push_back(k);
  if (sim.contact().particle_contact()) history << ",contact_pairs";
  if (spec.energy && frictional) history << ",friction_dissipation_J";
  // Normal dashpots (a polygon's restitution < 1): the energy they removed.
  const bool damped = sim.contact().damped();
  if (spec.energy && damped) history << ",contact_damping_J";
  // Material damping (materials[0].damping_ratio): the energy its viscous stress dissipated.
  const bool viscous = sim.law().viscous_time_s > 0.0;
  if (spec.energy && viscous) history << ",material_damping_J";
  for (size_t k : free_bodies) {
    const std::string& name = sim.contact().polygon(k).name;
    history << "," << name << "_x_m," << name << "_y_m," << name << "_angle_rad";
  }
  // Ground motion: where the floor is (its offset along the motion's direction) and, with the
  // energy columns, the work the moving obstacles have put in.
  const bool floor_moves = spec.floor && spec.floor->motion;
  if (floor_moves) history << ",floor_displacement_m,floor_velocity_m_s";
  // The floor's reaction along its normal: the impact force (computed on the host only).
  const bool floor_force = spec.floor && !device;
  if (floor_force) history << ",floor_force_N";
  const bool ground = sim.contact().moving_obstacles();
  if (spec.energy && ground) history << ",ground_work_J";
  history << "\n";
  auto record = [&]() {
    history << fmt(sim.time_s());
    for (size_t k = 0; k < probe_particle.size(); ++k) history << "," << fmt(sim.sample(probe_particle[k], spec.probes[k].field));
    if (sim.law().plastic) history << "," << fmt(sim.plastic_fraction());
    if (const FractureModel* fr = sim.fracture())
      history << "," << fr->failed_particles() << "," << fr->cut_bonds() << "," << fmt(fr->max_separation_pa());
    if (spec.energy)
      history << "," << fmt(sim.kinetic_energy_j()) << "," << fmt(sim.stress_work_j()) << ","
              << fmt(sim.hourglass_energy_j()) << "," << fmt(sim.floor_energy_j()) << "," << fmt(sim.gravity_energy_j());
    if (sim.contact().particle_contact()) history << "," << sim.contact().contact_pairs();
    if (spec.energy && frictional) history << "," << fmt(sim.friction_dissipation_j());
    if (spec.energy && damped) history << "," << fmt(sim.contact().contact_damping_j());
    if (spec.energy && viscous) history << "," << fmt(sim.material_damping_j());
    for (size_t k : free_bodies) {
      const auto c = sim.contact().polygon_centroid_m(k);
      history << "," << fmt(c[0]) << "," << fmt(c[1]) << "," << fmt(sim.contact().polygon_angle_rad(k));
    }
    if (floor_moves) {
      const HalfSpace& h = sim.contact().half_spaces().front();
      const auto& d = h.motion->direction;
      history << "," << fmt(h.offset_m[0] * d[0] + h.offset_m[1] * d[1] + h.offset_m[2] * d[2]) << ","
              << fmt(h.velocity_m_s[0] * d[0] + h.velocity_m_s[1] * d[1] + h.velocity_m_s[2] * d[2]);
    }
    if (floor_force) {
      const HalfSpace& h = sim.contact().half_spaces().front();
      const auto& r = sim.contact().plane_reaction_n(0);
      history << "," << fmt(-(r[0] * h.normal[0] + r[1] * h.normal[1] + r[2] * h.normal[2]));
    }
    if (spec.energy && ground) history << "," << fmt(sim.contact().ground_work_j());
    history << "\n";
  };
  int max_substeps = 1;  // squeezed bonds split a step (Solid::substeps); summary.json says how far
  const double loop_s = run_time_loop(
      sim, spec, case_file, out_dir, content_id, total_steps, results, record,
      [&] { max_substeps = std::max(max_substeps, sim.substeps()); },
      "time step above the stability limit? lower time.safety");
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  write_text_file(dir / "history.csv", history.str());
  double max_plastic = 0.0;
  for (double e : sim.eq_plastic_strain()) max_plastic = std::max(max_plastic, e);
  // Doubles through json_number: null where not finite (json_file.hpp).
  Json j;
  j["model"] = "mps";
  j["formulation"] = "stress";
  j["case_file"] = case_file;
  j["dimension"] = sim.dimension();
  j["particles"] = sim.size();
  j["bonds"] = sim.bonds().size();
  j["spacing_m"] = json_number(sim.spacing_m());
  j["re_over_spacing"] = json_number(spec.re_over_spacing);
  j["pressure_force"] = spec.repulsive_pressure ? "repulsive" : "conservative";
  j["hourglass"] = json_number(spec.hourglass);
  j["plastic"] = sim.law().plastic;
  j["steps"] = sim.steps();
  j["dt_s"] = json_number(sim.dt_s());
  j["max_substeps"] = max_substeps;
  j["end_time_s"] = json_number(sim.time_s());
  j["p_wave_speed_m_s"] = json_number(sim.p_wave_speed());
  j["kinetic_energy_j"] = json_number(sim.kinetic_energy_j());
  j["stress_work_j"] = json_number(sim.stress_work_j());
  j["max_eq_plastic_strain"] = json_number(max_plastic);
  j["plastic_fraction"] = json_number(sim.plastic_fraction());
  j["fracture"] = sim.fracture() != nullptr;
  j["failed_particles"] = sim.fracture() ? sim.fracture()->failed_particles() : 0;
  j["cut_bonds"] = sim.fracture() ? sim.fracture()->cut_bonds() : 0;
  j["detached_particles"] = sim.fracture() ? sim.fracture()->detached_particles() : 0;
  j["fragments_min10"] =
      sim.fracture() ? FractureModel::fragment_count(FractureModel::fragment_labels(sim.bonds()), 10) : 1;
  j["bodies"] = spec.bodies ? spec.bodies->shapes.size() : 1;
  j["rigid_bodies"] = spec.rigid_bodies.size();
  j["contact_pairs"] = sim.contact().contact_pairs();
  j["friction_dissipation_j"] = json_number(sim.friction_dissipation_j());
  if (damped) j["contact_damping_j"] = json_number(sim.contact().contact_damping_j());
  if (viscous) {
    j["damping_ratio"] = json_number(spec.material.damping_ratio);
    j["damping_frequency_hz"] = json_number(spec.material.damping_frequency_hz);
    j["material_damping_j"] = json_number(sim.material_damping_j());
  }
  add_timing(j, sim, wall_s, loop_s);
  write_json_file(dir / "summary.json", j);
  report_timing(sim, wall_s, loop_s, out_dir, quiet);
  return 0;
}

}  // namespace

int run_case(const std::string& case_file, const std::string& out_dir, int threads) {
  RunCaseOptions options;
  options.threads = threads;
  return run_case(case_file, out_dir, options);
}

int run_case(const std::string& case_file, const std::string& out_dir, const RunCaseOptions& options) {
  CaseSpec spec = load_case(case_file);
  if (options.quiet) spec.progress = false;
  const bool quiet = options.quiet;
  if (options.threads > 0) omp_set_num_threads(options.threads);
  // The stress formulation's launcher runs a subset of its features (docs/cuda.md, "MPS").
  auto solid_device = options.solid_device;
  if (spec.formulation == Formulation::Stress && solid_device)
    if (const auto refusal = solid_device_refusal(spec)) {
      if (!options.cpu_when_refused) throw InputError(case_file, refusal->field, refusal->got, refusal->expected);
      if (spec.progress)
        std::fprintf(stderr, "note: %s is not run by the CUDA launcher of the stress formulation; running on the CPU\n",
                     refusal->field.c_str());
      solid_device = nullptr;
    }
  if (spec.formulation == Formulation::Stress && options.device && !options.solid_device)
    throw InputError(case_file, "model.formulation", "stress with a device for the displacement formulation only",
                     "formulation: displacement, or --backend cpu");
  std::filesystem::create_directories(out_dir);
  if (spec.formulation == Formulation::Stress) return run_solid(spec, case_file, out_dir, solid_device, options.max_steps, quiet);
  const auto wall_start = std::chrono::steady_clock::now();

  Simulation sim(spec);
  if (options.device) sim.attach_device(options.device(sim));
  if (spec.progress) std::fprintf(stderr, "mps: backend %s\n", sim.backend_description().c_str());
  const MaterialSpec& m = spec.material;
  const long long total_steps = begin_run(spec, sim.dt_s(), case_file, out_dir, options.max_steps);
  if (!quiet)
    std::fprintf(stderr,
               "mps: %zu particles, %zu bonds, %zu crack pairs; spacing %.4g m, re %.3g spacing, n0 %.6g, lambda %.6g m^2\n"
               "mps: c_L %.1f m/s, c_T %.1f m/s; dt %.4g s (CFL dt %.4g s = safety %.2f x spacing / c_max; "
               "spectral stability limit %.4g s); CFL number c_L dt / spacing = %.3f; %lld steps\n",
               sim.size(), sim.bonds().size(), sim.cracks().size(), sim.spacing_m(), spec.re_over_spacing,
               sim.normalisation().number_density_n0, sim.normalisation().laplacian_lambda_m2, m.p_wave_speed(),
               m.s_wave_speed(), sim.dt_s(), sim.cfl_dt_s(), spec.safety, sim.spectral_dt_limit_s(),
               m.p_wave_speed() * sim.dt_s() / sim.spacing_m(), total_steps);
  if (sim.dt_s() > sim.spectral_dt_limit_s() && !quiet)
    std::fprintf(stderr, "mps: warning: dt %.4g s exceeds the stability limit %.4g s\n", sim.dt_s(),
                 sim.spectral_dt_limit_s());

  std::vector<int> probe_particle;
  for (const auto& p : spec.probes) probe_particle.push_back(sim.nearest_particle(p.position_m));

  const std::filesystem::path dir(out_dir);
  OutputFile results(dir / "results.h5");
  std::ostringstream history;
  {
    history << "time_s";
    for (const auto& p : spec.probes) history << "," << p.name << "_" << p.field;
    if (!sim.cracks().plus.empty()) history << ",slipping_fraction,open_fraction";
    if (spec.energy) history << ",kinetic_energy_J,elastic_energy_J";
    history << "\n";
  }
  auto record = [&]() {
    history << fmt(sim.time_s());
    for (size_t k = 0; k < probe_particle.size(); ++k) history << "," << fmt(sim.sample(probe_particle[k], spec.probes[k].field));
    if (!sim.cracks().plus.empty()) history << "," << fmt(sim.slipping_fraction()) << "," << fmt(sim.open_fraction());
    if (spec.energy) history << "," << fmt(sim.kinetic_energy_j()) << "," << fmt(sim.elastic_energy_j());
    history << "\n";
  };

  double max_slip = 0.0, max_open = 0.0;
  const double loop_s = run_time_loop(
      sim, spec, case_file, out_dir, sim.particles_content_id(), total_steps, results, record,
      [&] {
        max_slip = std::max(max_slip, sim.slipping_fraction());
        max_open = std::max(max_open, sim.open_fraction());
      },
      "time step above the stability limit?");
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  write_text_file(dir / "history.csv", history.str());

  Json j;
  j["model"] = "mps";
  j["case_file"] = case_file;
  j["dimension"] = sim.dimension();
  j["particles"] = sim.size();
  j["bonds"] = sim.bonds().size();
  j["crack_pairs"] = sim.cracks().size();
  j["spacing_m"] = json_number(sim.spacing_m());
  j["re_over_spacing"] = json_number(spec.re_over_spacing);
  j["equation"] = spec.equation == Equation::Navier ? "navier" : "rotation_free";
  j["integrator"] = spec.integrator == Integrator::SymplecticEuler ? "symplectic_euler" : "velocity_verlet";
  j["steps"] = sim.steps();
  j["dt_s"] = json_number(sim.dt_s());
  j["cfl_dt_s"] = json_number(sim.cfl_dt_s());
  j["spectral_dt_limit_s"] = json_number(sim.spectral_dt_limit_s());
  j["end_time_s"] = json_number(sim.time_s());
  j["p_wave_speed_m_s"] = json_number(m.p_wave_speed());
  j["s_wave_speed_m_s"] = json_number(m.s_wave_speed());
  j["max_slipping_fraction"] = json_number(max_slip);
  j["max_open_fraction"] = json_number(max_open);
  add_timing(j, sim, wall_s, loop_s);
  write_json_file(dir / "summary.json", j);
  report_timing(sim, wall_s, loop_s, out_dir, quiet);
  return 0;
}

}  // namespace breccia::mps
