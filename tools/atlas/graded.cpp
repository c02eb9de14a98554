// Stability map, graded particle arrangements (docs/atlas.md): a 2D strip whose right half
// is coarser than its left by a grading ratio r, with the horizon proportional to the local
// spacing (model.variable_horizon: true, dual horizon) or one horizon from the median
// spacing (the default). Measured per run: the smallest local horizon ratio, the strain
// energy of the coarse interior under uniaxial strain against the classical value, the
// ghost force at the resolution change under that (affine) strain, the net force, and a
// dynamic run at the default step. Rows go to docs/atlas/stability_graded.csv.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "atlas.hpp"
#include "measures.hpp"
#include "breccia/common/csv.hpp"
#include "breccia/common/error.hpp"
#include "breccia/common/particle_file.hpp"
#include "breccia/solver/calibration.hpp"
#include "breccia/solver/graded_check.hpp"
#include "breccia/solver/run.hpp"

namespace breccia::atlas {
namespace {

using solver::PdSystem;

std::string graded_strip(const std::string& path, double L, double W, double h, double r) {
  return write_graded_strip(path, L, W, h, r);  // measures.hpp
}

struct GradedRow {
  std::string model;
  double grading = 1;
  bool dual_horizon = false;
  size_t particles = 0, bonds = 0;
  int64_t min_family = 0;
  double min_local_m = 0, coarse_energy_error = 0, fine_energy_error = 0, ghost_force = 0, net_force = 0;
  double reflected = NAN;
  long long steps = 0;
  std::string status, detected_by;
  double energy_ratio = 0;
  std::string message;
};

std::string line_of(const GradedRow& r) {
  char b[512];
  std::snprintf(b, sizeof b, "%s,%.4g,%d,%zu,%zu,%lld,%.4g,%.4g,%.4g,%.4g,%.4g,%.4g,%lld,%s,%s,%.4g,", r.model.c_str(),
                r.grading, r.dual_horizon ? 1 : 0, r.particles, r.bonds, static_cast<long long>(r.min_family),
                r.min_local_m, r.coarse_energy_error, r.fine_energy_error, r.ghost_force, r.net_force, r.reflected, r.steps,
                r.status.c_str(), r.detected_by.c_str(), r.energy_ratio);
  return std::string(b) + message_field(r.message);
}

// Affine strains (uniaxial and shear): the energy of the interiors of both halves against the
// classical density (the worse of the two strains, signed), and the force at the resolution
// change under uniaxial strain in units of sigma_xx / spacing (the unbalanced force density of
// a free surface particle is of that order, so 1 means a ghost force as large as a free
// surface's).
void measure_affine(PdSystem& s, double L, double W, GradedRow& row) {
  const auto& mat = s.config.materials[0];
  const solver::ElasticInput in{2, s.config.planar, mat.youngs_modulus, mat.poisson_ratio, s.thickness};
  double reach = 0;
  for (size_t i = 0; i < s.n; ++i) reach = std::max(reach, s.horizon[i] + 2 * s.half_cell[i]);
  auto worse = [](double a, double b) { return std::isnan(a) || std::fabs(b) > std::fabs(a) ? b : a; };
  row.coarse_energy_error = row.fine_energy_error = NAN;
  const double strain = 1e-4;
  for (int which = 0; which < 2; ++which) {
    double eps[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
    if (which == 0) eps[0] = strain;
    else eps[1] = eps[3] = strain;
    for (size_t i = 0; i < s.n; ++i)
      for (int a = 0; a < 2; ++a) s.u[3 * i + a] = eps[3 * a] * s.x0[3 * i] + eps[3 * a + 1] * s.x0[3 * i + 1];
    s.diagnostics = true;
    solver::cpu_compute_forces(s);
    const double w_classical = solver::classical_energy_density(in, eps);
    const double nu = mat.poisson_ratio, E = mat.youngs_modulus;
    const double sigma_xx = E * (1 - nu) / ((1 + nu) * (1 - 2 * nu)) * strain;  // plane strain, uniaxial strain
    double coarse_sum = 0, fine_sum = 0, ghost = 0, net[2] = {0, 0}, total = 0;
    int coarse_n = 0, fine_n = 0;
    for (size_t i = 0; i < s.n; ++i) {
      const double x = s.x0[3 * i], y = s.x0[3 * i + 1];
      const double own = s.horizon[i] + 2 * s.half_cell[i];
      const bool off_sides = y > own && y < W - own && x > own && x < L - own;
      const double to_change = std::fabs(x - L / 2);
      const double ratio = s.energy_density[i] / w_classical - 1.0;
      if (off_sides && to_change > reach && x > L / 2) {
        coarse_sum += ratio;
        ++coarse_n;
      }
      if (off_sides && to_change > reach && x < L / 2) {
        fine_sum += ratio;
        ++fine_n;
      }
      if (which == 0 && y > reach && y < W - reach && to_change <= reach) {
        const double f = std::hypot(s.force[3 * i], s.force[3 * i + 1]);
        ghost = std::max(ghost, f * 2 * s.half_cell[i] / sigma_xx);
      }
      for (int d = 0; d < 2; ++d) net[d] += s.volume[i] * s.force[3 * i + d];
      total += s.volume[i] * std::hypot(s.force[3 * i], s.force[3 * i + 1]);
    }
    row.coarse_energy_error = worse(row.coarse_energy_error, coarse_n ? coarse_sum / coarse_n : NAN);
    row.fine_energy_error = worse(row.fine_energy_error, fine_n ? fine_sum / fine_n : NAN);
    if (which == 0) {
      row.ghost_force = ghost;
      row.net_force = total > 0 ? std::hypot(net[0], net[1]) / total : 0.0;
    }
  }
  // Back to the reference state, diagnostics included (the run's initial energy reads them).
  std::fill(s.u.begin(), s.u.end(), 0.0);
  if (s.x.size() == s.x0.size()) s.x = s.x0;
  solver::cpu_compute_forces(s);
}

// A right-going P pulse (uniaxial strain: y held) in a long strip with the resolution change
// at L/2 (as tests/solver/test_dual_horizon.cpp): the share of the energy that is left of the
// change once the pulse centre has passed it by four widths, i.e. reflected.
double reflected_energy(const std::string& work_dir, const std::string& model, double r, bool dh, double h) {
  const double L = 0.3, W = 0.004;
  char name[64];
  std::snprintf(name, sizeof name, "/graded_wave_r%g.h5", r);
  const std::string particles = graded_strip(work_dir + name, L, W, h, r);
  PdSystem s = system_from_yaml(
      work_dir, "stability_graded_wave",
      "specimen: {particles: " + particles + "}\nmodel: {type: " + model +
          ", planar: plane_strain, horizon_factor: 3.015, variable_horizon: " + (dh ? "true" : "false") +
          "}\nmaterials: [{name: rock, density: 2600, youngs_modulus: 50 GPa, poisson_ratio: 0.25}]\n"
          "time: {steps: 1, check_stability: false}\n");
  for (auto& f : s.fixed_dof) f |= 2u;
  const double E = 50e9, nu = 0.25, rho = 2600;
  const double cp = std::sqrt(E * (1 - nu) / ((1 + nu) * (1 - 2 * nu)) / rho);
  return reflected_pulse_energy(s, L / 2, 0.07, 0.012, cp);  // measures.hpp
}

}  // namespace

void graded_stability(const SweepPlan& plan, SpecimenMaker& maker, CsvTable& table) {
  const double L = 0.06, W = 0.03, h = 0.5e-3;
  const std::vector<double> gradings = !plan.gradings.empty() ? plan.gradings
                                       : plan.quick            ? std::vector<double>{2, 4}
                                                               : std::vector<double>{1, 1.5, 2, 3, 4, 6};
  for (const auto& model : plan.models) {
    // PMB, LPS and correspondence (its default penalty stabilisation, G = 1); each has its own
    // measured limits in graded_check.hpp.
    if (model != "pmb" && model != "lps" && model != "correspondence") continue;
    for (double r : gradings)
      for (bool dh : {false, true}) {
        GradedRow row;
        row.model = model;
        row.grading = r;
        row.dual_horizon = dh;
        char name[64];
        std::snprintf(name, sizeof name, "graded_r%g", r);
        const std::string particles = graded_strip(maker.work_dir + "/" + name + ".h5", L, W, h, r);
        const std::string yaml = "specimen: {particles: " + particles + "}\nmodel: {type: " + model +
                                 ", planar: plane_strain, horizon_factor: 3.015, variable_horizon: " +
                                 (dh ? "true" : "false") +
                                 "}\nmaterials: [{name: rock, density: 2600, youngs_modulus: 50 GPa, poisson_ratio: 0.25}]\n"
                                 "time: {steps: " + std::string(plan.quick ? "200" : "400") +
                                 ", check_stability: false}\noutput: {every: 1000000, history_every: 5, fields: [damage]}\n";
        try {
          PdSystem s = system_from_yaml(maker.work_dir, "stability_graded", yaml);
          s.config.write_results = false;
          row.particles = s.n;
          row.bonds = s.bond_count();
          row.min_family = s.n ? INT64_MAX : 0;
          for (size_t i = 0; i < s.n; ++i)
            row.min_family = std::min<int64_t>(row.min_family, s.offsets[i + 1] - s.offsets[i]);
          const solver::HorizonGrading g = solver::horizon_grading(s);
          row.min_local_m = g.min_local_ratio;
          row.detected_by = "-";
          try {
            solver::require_graded_horizon(s);
          } catch (const InputError& e) {
            row.detected_by = "start-up horizon-grading check";
            row.message = e.what();
          }
          measure_affine(s, L, W, row);
          for (size_t i = 0; i < s.n; ++i) {  // smooth standing-wave velocity
            const double x = s.x0[3 * i] / L, y = s.x0[3 * i + 1] / W;
            s.v[3 * i] = std::sin(std::numbers::pi * x) * std::cos(std::numbers::pi * y);
            s.v[3 * i + 1] = 0.5 * std::cos(2 * std::numbers::pi * x) * std::sin(std::numbers::pi * y);
          }
          const solver::Energies e0 = solver::measure(s);
          solver::RunOptions o;
          o.out_dir = maker.work_dir + "/stability_run";
          o.progress = false;
          const solver::RunResult r_run = solver::run_system(s, o);
          row.steps = r_run.steps;
          row.status = r_run.status;
          row.energy_ratio = r_run.final_energies.finite
                                 ? (r_run.final_energies.kinetic + r_run.final_energies.strain) / (e0.kinetic + e0.strain)
                                 : INFINITY;
          row.reflected = reflected_energy(maker.work_dir, model, r, dh, h);
          if (r_run.status == "unstable") {
            row.detected_by = (row.detected_by == "-" ? "" : row.detected_by + " + ") +
                              "run-time energy/finite check (run_time_loop)";
            row.message = r_run.message;
          }
        } catch (const InputError& e) {
          row.status = "rejected";
          row.detected_by = "start-up (set-up error)";
          row.message = e.what();
        }
        std::fprintf(stderr,
                     "[atlas] stability graded %s r=%g DH=%d: min local m %.3g, coarse energy %+.3g, fine %+.3g, ghost "
                     "%.3g, net %.2g, reflected %.3g; %s after %lld steps; detected by %s\n",
                     model.c_str(), r, dh ? 1 : 0, row.min_local_m, row.coarse_energy_error, row.fine_energy_error,
                     row.ghost_force, row.net_force, row.reflected, row.status.c_str(), row.steps, row.detected_by.c_str());
        table.add(line_of(row));
      }
  }
}

}  // namespace breccia::atlas
