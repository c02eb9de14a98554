#include "breccia/solver/family_check.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

#include "breccia/common/error.hpp"
#include "breccia/solver/calibration.hpp"
#include "breccia/solver/exec_openmp.hpp"

namespace breccia::solver {

EnergyScatter energy_scatter(PdSystem& s, const DistributedSetup& d, const DistributedRows& rows) {
  EnergyScatter out;
  const size_t n = s.n;
  // A lattice's interior families are all alike: nothing to scatter, and a small block's
  // truncated families would read as scatter. Only mesh-derived particles are irregular.
  if (s.particles.nodes_per_cell == 0) return out;
  // A family is complete when its partial volumes fill 95 % of the horizon: on a lattice
  // a whole family fills 92 % (m = 1.5), 97 % (m = 2) and 98.5 % (m = 2.5) of it, measured, so
  // the rule admits whole irregular families at m >= 2 while a family cut by a surface by more
  // than a thin cap is left out. A specimen too small to hold such families is not judged.
  // (Read before the strain pass: fracture is off there, so it changes no bond state.)
  std::vector<double> fill(n, -1.0);
#pragma omp parallel for schedule(dynamic, 1024)
  for (size_t i = 0; i < n; ++i) {
    double family_volume = 0.0;
    bool one_material = true;
    for (int64_t k = s.offsets[i]; k < s.offsets[i + 1]; ++k) {
      if (s.state[k] == 0) continue;
      family_volume += s.own_volume(k);
      one_material = one_material && s.material[s.neighbor[k]] == s.material[i];
    }
    const double h = s.horizon[i];
    const double horizon_volume = s.dimension == 3 ? 4.0 / 3.0 * M_PI * h * h * h : M_PI * h * h * s.thickness;
    if (one_material) fill[i] = family_volume / horizon_volume;
  }
  const double complete_fill = 0.95;
  // Linear response: a small strain with fracture off (as estimate_max_frequency), bond
  // states and the dissipated energy restored afterwards.
  const double strain = 1e-6;
  // The bond states and dissipated energies are saved before a force pass only: the energy-only
  // rows (cpu_energy_density_on_rows) write positions, dilatation and energy densities alone.
  std::vector<uint8_t> state_saved;
  std::vector<double> dissipated_saved;
  bool saved = false;
  const auto save = [&] {
    state_saved = s.state;
    dissipated_saved = s.dissipated;
    saved = true;
  };
  const bool fracture = s.config.fracture, diagnostics = s.diagnostics;
  const double dissipated = s.dissipated_energy;
  s.config.fracture = false;
  s.diagnostics = true;
  std::fill(s.u.begin(), s.u.end(), 0.0);
  for (size_t i = 0; i < n; ++i) s.u[3 * i] = strain * s.x0[3 * i];
  // Only the sampled particles' energy densities are read, and each reads its own row alone
  // (its bonds and, LPS, its own dilatation): one process passes over those rows only (the
  // same kernels on the same inputs: the whole pass's energies, bit for bit), which skips
  // the rows of the surface layers, interfaces and cracks: 19 % of the full concrete case's
  // rows, 35 % of its demo's.
  const bool rows_only = !rows.active && !s.f32.active && s.short_range_k.empty() &&
                         (s.config.model == PdModel::PMB || s.config.model == PdModel::LPS);
  {
    const DamageHiddenWhileUndamaged undamaged(s);  // the unbroken dilatation loop: the same bits
    if (rows_only) {
      std::vector<int64_t> sampled_rows;
      for (size_t i = 0; i < n; ++i)
        if (fill[i] >= complete_fill) sampled_rows.push_back(static_cast<int64_t>(i));
      // Only the energy densities where the general loop's pass would give them (the same
      // bits without its forces: cpu_energy_density_on_rows), else that pass on the rows.
      if (!cpu_energy_density_on_rows(s, sampled_rows)) {
        save();
        cpu_compute_forces_on_rows(s, sampled_rows, sampled_rows);
      }
    } else {
      save();
      cpu_compute_forces(s);
    }
  }
  s.config.fracture = fracture;
  s.diagnostics = diagnostics;
  s.dissipated_energy = dissipated;
  if (saved) {
    s.state = state_saved;
    s.dissipated = dissipated_saved;
  }
  const std::vector<double> energy(s.energy_density);
  std::fill(s.u.begin(), s.u.end(), 0.0);
  if (s.x.size() == s.x0.size()) s.x = s.x0;
  std::fill(s.force.begin(), s.force.end(), 0.0);
  std::fill(s.energy_density.begin(), s.energy_density.end(), 0.0);
  std::fill(s.damage.begin(), s.damage.end(), 0.0);
  std::fill(s.max_stretch.begin(), s.max_stretch.end(), 0.0);
  std::fill(s.dilatation.begin(), s.dilatation.end(), 0.0);
  const double eps[9] = {strain, 0, 0, 0, 0, 0, 0, 0, 0};
  // A distributed set-up's rows outside the rank's range are empty here (fill 0): each rank
  // samples its own particles.
  std::vector<int64_t> sampled;  // in index order, with their ratios
  std::vector<double> ratio;
  for (size_t i = 0; i < n; ++i) {
    if (fill[i] < complete_fill) continue;
    const MaterialSpec& m = s.config.materials[s.material[i]];
    const ElasticInput in{s.dimension, s.config.planar, m.youngs_modulus, m.poisson_ratio, s.thickness};
    sampled.push_back(static_cast<int64_t>(i));
    ratio.push_back(energy[i] / classical_energy_density(in, eps));
  }
  if (rows.active) {  // every rank's, in rank order: the ranks own consecutive index ranges
    if (!s.window_global.empty())  // a window system's local indices to internal ones
      for (int64_t& i : sampled) i = s.window_global[static_cast<size_t>(i)];
    sampled = concat_over_ranks(d, sampled);
    ratio = concat_over_ranks(d, ratio);
  }
  double sum = 0.0;
  for (const double r : ratio) sum += r;
  out.sampled = ratio.size();
  // Scatter about the mean, not about 1: a lattice's mean offset at small m is a calibration
  // error shared by every particle (the atlas measures it), not a random stiffness.
  const double mean = out.sampled ? sum / out.sampled : 1.0;
  double sum2 = 0.0;
  for (size_t q = 0; q < ratio.size(); ++q) {
    const double deviation = ratio[q] / mean - 1.0;
    sum2 += deviation * deviation;
    if (std::fabs(deviation) > out.worst) {
      out.worst = std::fabs(deviation);
      out.worst_particle = sampled[q];
    }
  }
  out.rms = out.sampled ? std::sqrt(sum2 / out.sampled) : 0.0;
  return out;
}

void require_resolved_families(PdSystem& s, const DistributedSetup& d, const DistributedRows& rows) {
  const EnergyScatter e = energy_scatter(s, d, rows);
  if (e.sampled < kMinScatterSample || e.rms <= kMaxEnergyScatter) return;
  // The worst particle's file index, position and horizon: a distributed set-up's ranks take
  // them from the first rank whose window holds it (every rank then says the same).
  const int64_t i = s.window_global.empty() ? e.worst_particle : s.system_index(e.worst_particle);
  const bool held = i < static_cast<int64_t>(s.n) &&
                    (s.window_global.empty() || s.window_global[static_cast<size_t>(i)] == e.worst_particle);
  std::vector<double> worst;  // file index (exact as a double), position, horizon
  if (held)
    worst = {static_cast<double>(s.original_index[i]), s.x0[3 * i], s.x0[3 * i + 1], s.x0[3 * i + 2], s.horizon[i]};
  if (rows.active) worst = concat_over_ranks(d, worst);
  if (worst.size() < 5) throw std::logic_error("energy scatter: no rank holds the worst particle");
  std::ostringstream found;
  found << "per-particle strain energy under uniaxial strain scatters by " << 100.0 * e.rms << " % RMS over "
        << e.sampled << " particles with complete families (limit " << 100.0 * kMaxEnergyScatter
        << " %) about its mean; worst is particle " << static_cast<int64_t>(worst[0]) << " at (" << worst[1] << ", "
        << worst[2] << ", " << worst[3] << "), off by " << 100.0 * e.worst << " %: the horizon (" << worst[4]
        << " m) is too small for this particle arrangement";
  throw InputError(s.config.file, "model.horizon_factor", found.str(),
                   "a larger horizon_factor (tet-centroid particles: 2.5 or more keeps the scatter at 7-8 %; docs/atlas.md), "
                   "or time.check_stability: false to run anyway");
}

}  // namespace breccia::solver
