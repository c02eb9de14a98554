// Correspondence zero-energy modes, measured (docs/atlas.md, "Correspondence"). An impact —
// one column of a free 2D plane-strain square (20 mm, dx 1 mm) starting at 5 m/s, a velocity
// jump at the particle scale that feeds every wavelength — runs for a fixed number of steps
// at each (m, G). Every 5 steps the solver's own instability check (instability_message,
// which holds the zero-energy detector) is asked for its verdict, but the run goes on to the
// end so the growth itself is recorded: the ratio R = non-affine energy (unit penalty) /
// (kinetic + strain energy). The first step at which the check fires is the row's verdict.
#include "stability_correspondence.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <sstream>

#include "breccia/common/csv.hpp"
#include "breccia/common/error.hpp"
#include "breccia/common/output_file.hpp"
#include "breccia/solver/correspondence.hpp"
#include "breccia/solver/run.hpp"

namespace breccia::atlas {
namespace {

std::string number(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.4g", v);
  return b;
}

}  // namespace

void stability_correspondence(const SweepPlan& plan, SpecimenMaker& maker, CsvTable& table,
                              const std::string& series_csv) {
  const std::vector<double> ms = plan.quick ? std::vector<double>{2.0, 3.0, 4.0} : std::vector<double>{2.0, 3.0, 4.0, 5.0};
  const std::vector<double> gs = plan.quick ? std::vector<double>{0.0, 0.01, 0.1, 1.0}
                                            : std::vector<double>{0.0, 0.003, 0.01, 0.03, 0.1, 0.3, 1.0, 3.0};
  const long long steps = plan.quick ? 400 : 1000;
  const int every = 5;
  std::ostringstream series;
  series << "scenario,m,G,step,time_s,nonaffine_ratio,kinetic_J,strain_J\n";
  for (const std::string scenario : {"impact", "noise"})
  for (double m : ms)
    for (double G : gs) {
      const std::string stab = G > 0 ? "{type: penalty, coefficient: " + number(G) + "}" : "{type: none}";
      const std::string model = G > 0 ? "corr_penalty_G" + number(G) : "corr_none";
      std::string status = "stable", detected_by = "-", message;
      long long tripped_at = -1, ran = 0;
      double max_ratio = 0.0, energy_ratio = 0.0;
      size_t particles = 0, bonds = 0;
      int64_t min_family = 0;
      try {
        solver::PdSystem s = system_from_yaml(
            maker.work_dir, "stability_corr",
            "specimen: {lattice: {dimension: 2, box: [0, 0, 0.02, 0.02], spacing: 1 mm, thickness: 1 mm}}\n"
            "model: {type: correspondence, planar: plane_strain, horizon_factor: " + std::to_string(horizon_factor(m)) +
                ", stabilisation: " + stab + "}\n"
                "materials: [{name: rock, density: 2600, youngs_modulus: 50 GPa, poisson_ratio: 0.25}]\n"
                "initial: [{type: velocity, set: xmin, value: [5, 0, 0]}]\n"
                "time: {steps: " + std::to_string(steps) + "}\n");
        if (scenario == "noise") {
          // Random velocities (uniform, +-1 m/s per component, fixed seed): every mode gets
          // energy, the zero-energy ones too, as round-off and contact do in a long run.
          std::mt19937_64 rng(20071);
          std::uniform_real_distribution<double> uni(-1.0, 1.0);
          for (size_t i = 0; i < s.n; ++i)
            for (int d = 0; d < 2; ++d) s.v[3 * i + d] = uni(rng);
        }
        particles = s.n;
        bonds = s.bond_count();
        min_family = INT64_MAX;
        for (size_t i = 0; i < s.n; ++i) min_family = std::min<int64_t>(min_family, s.offsets[i + 1] - s.offsets[i]);
        solver::cpu_compute_forces(s);
        const solver::Energies e0 = solver::measure(s);
        const double total0 = e0.kinetic + e0.strain;
        for (long long k = 1; k <= steps; ++k) {
          s.diagnostics = k % every == 0;
          solver::cpu_step(s);
          s.diagnostics = true;
          if (k % every) continue;
          const solver::Energies e = solver::measure(s);
          const double ratio = solver::nonaffine_energy(s) / std::max(e.kinetic + e.strain, 1e-300);
          max_ratio = std::max(max_ratio, ratio);
          energy_ratio = (e.kinetic + e.strain) / total0;
          ran = k;
          series << scenario << "," << number(m) << "," << number(G) << "," << k << "," << number(s.time) << ","
                 << number(ratio) << "," << number(e.kinetic) << "," << number(e.strain) << "\n";
          const std::string verdict = solver::instability_message(s, e, total0);
          if (tripped_at < 0 && !verdict.empty()) {
            tripped_at = k;
            status = "unstable";
            detected_by = "run-time zero-energy-mode check (zero_energy_mode_message)";
            message = verdict;
          }
          if (!e.finite) break;
        }
      } catch (const InputError& e) {
        status = "rejected";
        detected_by = "start-up";
        message = e.what();
      }
      // Shared stability.csv columns; min_family and steps as the other studies, steps = the
      // step the detector fired at (or the steps run), energy_scatter = the largest R seen.
      char b[256];
      std::snprintf(b, sizeof b, "zero_energy_%s,%s,2,lattice,%.4g,0.8,%zu,%zu,%lld,%lld,", scenario.c_str(), model.c_str(), m, particles,
                    bonds, static_cast<long long>(min_family), tripped_at > 0 ? tripped_at : ran);
      table.add(std::string(b) + status + "," + detected_by + "," + number(energy_ratio) + "," + number(max_ratio) + "," +
                csv_plain_field(message));
      std::fprintf(stderr, "[atlas] correspondence %s m=%.1f G=%g: %s%s, max non-affine ratio %.3g, energy x%.3g\n", scenario.c_str(), m, G,
                   status.c_str(), tripped_at > 0 ? (" at step " + std::to_string(tripped_at)).c_str() : "", max_ratio,
                   energy_ratio);
    }
  write_text_file(series_csv, series.str());
}

}  // namespace breccia::atlas
