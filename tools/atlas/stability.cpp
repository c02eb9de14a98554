// The measured stability map (docs/atlas.md): where PMB and LPS fail and which run-time
// detector catches each failure.
//  dt_factor:   time step f x the computed stable step 2/omega_max on a small free block with
//               a smooth initial velocity; the run goes through run_system, so the verdict
//               is that of the solver's own instability detector.
//  m_irregular: horizon ratio m on tet-centroid (and, for reference, lattice) particles; the
//               start-up family check, the per-particle energy error under uniaxial strain,
//               and a dynamic run at the default step.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <sstream>

#include "atlas.hpp"
#include "stability_correspondence.hpp"
#include "breccia/common/csv.hpp"
#include "breccia/common/error.hpp"
#include "breccia/solver/family_check.hpp"
#include "breccia/solver/run.hpp"

namespace breccia::atlas {
namespace {

using solver::PdSystem;

struct StabilityRow {
  std::string study, model;
  int dimension = 2;
  std::string kind;
  double m = 0, dt_factor = 0;
  size_t particles = 0, bonds = 0;
  int64_t min_family = 0;
  long long steps = 0;
  std::string status, detected_by;
  double energy_ratio = 0, energy_scatter = 0;
  std::string message;
};

StabilityRow make_row(const std::string& study, const std::string& model, int dimension, const std::string& kind,
                      double m, double dt_factor) {
  StabilityRow r;
  r.study = study;
  r.model = model;
  r.dimension = dimension;
  r.kind = kind;
  r.m = m;
  r.dt_factor = dt_factor;
  return r;
}

std::string line_of(const StabilityRow& r) {
  char b[256];
  std::snprintf(b, sizeof b, "%s,%s,%d,%s,%.4g,%.4g,%zu,%zu,%lld,%lld,", r.study.c_str(), r.model.c_str(),
                r.dimension, r.kind.c_str(), r.m, r.dt_factor, r.particles, r.bonds,
                static_cast<long long>(r.min_family), r.steps);
  char e[96];
  std::snprintf(e, sizeof e, ",%.4g,%.4g,", r.energy_ratio, r.energy_scatter);
  return std::string(b) + r.status + "," + r.detected_by + e + message_field(r.message);
}

// A smooth standing-wave velocity field (as tests/solver/test_dynamics.cpp): energy in long
// wavelengths, so any growth of the short ones is the integrator's doing.
void smooth_velocity(PdSystem& s, double size) {
  for (size_t i = 0; i < s.n; ++i) {
    const double x = s.x0[3 * i] / size, y = s.x0[3 * i + 1] / size;
    s.v[3 * i] = std::sin(std::numbers::pi * x) * std::cos(std::numbers::pi * y);
    s.v[3 * i + 1] = 0.5 * std::cos(2 * std::numbers::pi * x) * std::sin(std::numbers::pi * y);
  }
}

// Runs the system through the solver's own loop; returns the result and fills the row.
void run_dynamics(PdSystem& s, const std::string& out_dir, StabilityRow& row) {
  const solver::Energies e0 = solver::measure(s);
  solver::RunOptions o;
  o.out_dir = out_dir;
  o.progress = false;
  const solver::RunResult r = solver::run_system(s, o);
  row.steps = r.steps;
  row.status = r.status;
  row.detected_by = r.status == "unstable" ? "run-time energy/finite check (run_time_loop)" : "-";
  const double total0 = e0.kinetic + e0.strain;
  const double total = r.final_energies.kinetic + r.final_energies.strain;
  row.energy_ratio = r.final_energies.finite ? total / total0 : INFINITY;
  row.message = r.message;
}

void fill_families(const PdSystem& s, StabilityRow& row) {
  row.particles = s.n;
  row.bonds = s.bond_count();
  row.min_family = s.n ? INT64_MAX : 0;
  for (size_t i = 0; i < s.n; ++i) row.min_family = std::min<int64_t>(row.min_family, s.offsets[i + 1] - s.offsets[i]);
}

}  // namespace

void stability_map(const SweepPlan& plan, SpecimenMaker& maker, CsvTable& table, const std::string& series_csv) {
  // (a) time-step factor: 2D plane strain square 20 mm, dx 1 mm, m 3.
  const std::vector<double> factors = plan.quick
      ? std::vector<double>{0.5, 0.9, 0.98, 1.0, 1.02, 1.1, 1.5}
      : std::vector<double>{0.5, 0.7, 0.9, 0.95, 0.98, 1.0, 1.02, 1.05, 1.1, 1.2, 1.3, 1.5};
  const double side = 0.02, lo[3] = {0, 0, 0}, hi[3] = {side, side, 0};
  for (const auto& kind : plan.kinds)
    for (const auto& model : plan.models)
      for (double f : factors) {
        const Settings st{model, kind, 3.0, 1e-3};
        StabilityRow row = make_row("dt_factor", model, 2, kind, 3.0, f);
        try {
          PdSystem s = system_from_yaml(
              maker.work_dir, "stability_dt",
              maker.specimen_yaml(st, 2, lo, hi) + "model: {type: " + model + ", planar: plane_strain, horizon_factor: " +
                  std::to_string(horizon_factor(3.0)) +
                  "}\nmaterials: [{name: rock, density: 2600, youngs_modulus: 50 GPa, poisson_ratio: 0.25}]\n"
                  "time: {steps: " + std::string(plan.quick ? "1000" : "2000") + ", check_stability: false}\n"
                  "output: {every: 1000000, history_every: 5, fields: [damage]}\n");
          s.config.write_results = false;
          s.dt = f * s.stable_dt;
          smooth_velocity(s, side);
          fill_families(s, row);
          run_dynamics(s, maker.work_dir + "/stability_run", row);
        } catch (const InputError& e) {
          row.status = "rejected";
          row.detected_by = "start-up";
          row.message = e.what();
        }
        std::fprintf(stderr, "[atlas] stability dt %s %s f=%.2f: %s after %lld steps, energy x%.3g\n", model.c_str(),
                     kind.c_str(), f, row.status.c_str(), row.steps, row.energy_ratio);
        table.add(line_of(row));
      }

  // (b) horizon ratio on irregular particles: 3D cube 12 mm, spacing ~1 mm.
  const std::vector<double> ms = plan.quick ? std::vector<double>{1.5, 2.0, 2.5, 3.0, 4.0}
                                            : std::vector<double>{1.5, 1.75, 2.0, 2.25, 2.5, 3.0, 3.5, 4.0};
  const double half = 0.006, blo[3] = {-half, -half, -half}, bhi[3] = {half, half, half};
  for (const auto& kind : plan.kinds)
    for (const auto& model : plan.models)
      for (double m : ms) {
        const Settings st{model, kind, m, 1e-3};
        StabilityRow row = make_row("m_irregular", model, 3, kind, m, 0.8);
        std::string yaml;
        try {
          yaml = maker.specimen_yaml(st, 3, blo, bhi) + "model: {type: " + model + ", horizon_factor: " +
                 std::to_string(horizon_factor(m)) +
                 "}\nmaterials: [{name: rock, density: 2600, youngs_modulus: 50 GPa, poisson_ratio: 0.25}]\n"
                 "time: {steps: " + std::string(plan.quick ? "200" : "400") + ", check_stability: CHECK}\n"
                 "output: {every: 1000000, history_every: 5, fields: [damage]}\n";
          // Built with the start-up checks off, then checked with the solver's own detector,
          // so one set-up gives both the verdict a user would get and the run's behaviour.
          std::string unchecked = yaml;
          unchecked.replace(unchecked.find("CHECK"), 5, "false");
          PdSystem s = system_from_yaml(maker.work_dir, "stability_m", unchecked);
          s.config.write_results = false;
          fill_families(s, row);
          row.energy_scatter = solver::energy_scatter(s).rms;
          try {
            solver::require_resolved_families(s);
            row.detected_by = "-";
          } catch (const InputError& e) {
            row.detected_by = "start-up energy-scatter check";
            row.message = e.what();
          }
          for (size_t i = 0; i < s.n; ++i) {  // smooth velocity about the cube centre
            const double x = (s.x0[3 * i] + half) / (2 * half), y = (s.x0[3 * i + 1] + half) / (2 * half);
            s.v[3 * i] = std::sin(std::numbers::pi * x) * std::cos(std::numbers::pi * y);
            s.v[3 * i + 1] = 0.5 * std::cos(2 * std::numbers::pi * x) * std::sin(std::numbers::pi * y);
          }
          StabilityRow run_row = row;
          run_dynamics(s, maker.work_dir + "/stability_run", run_row);
          row.steps = run_row.steps;
          row.status = run_row.status;
          row.energy_ratio = run_row.energy_ratio;
          if (run_row.status == "unstable") {
            row.detected_by = (row.detected_by == "-" ? "" : row.detected_by + " + ") + run_row.detected_by;
            row.message = run_row.message;
          }
        } catch (const InputError& e) {  // rejected even with the checks off (LPS: no neighbours)
          row.status = "rejected";
          row.detected_by = "start-up (set-up error)";
          row.message = e.what();
        }
        std::fprintf(stderr, "[atlas] stability m %s %s m=%.2f: %s; detected by %s; min family %lld; energy scatter %.3g\n",
                     model.c_str(), kind.c_str(), m, row.status.c_str(), row.detected_by.c_str(),
                     static_cast<long long>(row.min_family), row.energy_scatter);
        table.add(line_of(row));
      }
  // (c) correspondence zero-energy modes on the (m, G) plane (stability_correspondence.cpp).
  if (std::find(plan.models.begin(), plan.models.end(), "correspondence") != plan.models.end())
    stability_correspondence(plan, maker, table, series_csv);
}

}  // namespace breccia::atlas
