// LPS's energy surface correction (surface_correction.hpp; docs/theory.md, "Surface correction").
#include "surface_correction.hpp"

#include <algorithm>

namespace breccia::solver {

namespace {
// Particle i's LPS energy density under unit uniaxial strain along each axis, with its bonds'
// weights multiplied by the blended axis factors and its own (unscaled) coefficients c. With
// the weighted sums m = sum w, M_a = sum w n_a^2, Q_a = sum w n_a^4 (w = f omega beta V_j |xi|^2):
// theta_a = d M_a / m and the deviatoric sum is Q_a - M_a^2 / m, so
// W_a = (K_d / 2) theta_a^2 + (c_s / 2m) (Q_a - M_a^2 / m).
void uniaxial_energies(const PdSystem& s, const std::vector<double>& axis_factor, const LpsCoefficients& c, size_t i,
                       double energy[3]) {
  double m = 0.0, second[3] = {0, 0, 0}, fourth[3] = {0, 0, 0};
  for (int64_t k = s.offsets[i]; k < s.offsets[i + 1]; ++k) {
    const int32_t j = s.neighbor[k];
    const double w = ellipsoid_bond_factor(s, axis_factor, i, k) * s.k_own[k] * s.volume[j] * s.xi_len[k] * s.xi_len[k];
    m += w;
    for (int a = 0; a < s.dimension; ++a) {
      const double na = (s.x0[3 * j + a] - s.x0[3 * i + a]) / s.xi_len[k];
      second[a] += w * na * na;
      fourth[a] += w * na * na * na * na;
    }
  }
  for (int a = 0; a < s.dimension; ++a) {
    if (!(m > 0)) {
      energy[a] = 0.0;
      continue;
    }
    const double theta = c.dilatation_factor * second[a] / m;
    energy[a] = lps_bulk_energy(c, theta) + 0.5 * c.shear_term / m * (fourth[a] - second[a] * second[a] / m);
  }
}
}  // namespace

std::vector<double> lps_surface_correction(PdSystem& s, const std::vector<ElasticInput>& elastic,
                                           const DistributedSetup& dist, const DistributedRows& rows) {
  const size_t n = s.n;
  const int dims = s.dimension;
  std::vector<LpsCoefficients> coefficients(elastic.size());
  for (size_t m = 0; m < elastic.size(); ++m) coefficients[m] = lps_coefficients(elastic[m]);
  std::vector<double> axis_factor(3 * n, 1.0), energy(3 * n, 0.0);
  auto measure = [&]() {
#pragma omp parallel for
    for (size_t i = 0; i < n; ++i)
      uniaxial_energies(s, axis_factor, coefficients[s.material[i]], i, &energy[3 * i]);
  };
  measure();
  // Target per material: the mean uniaxial energy of the complete families (the discrete
  // bulk, lattice sums included, as PMB's correction takes); with none complete (a specimen
  // thinner than two horizons), the continuum's (lambda_d + 2 mu) / 2, which LPS's
  // coefficients give for a complete continuous family.
  std::vector<uint8_t> complete(n, 0);
  for (size_t i = 0; i < n; ++i) {
    const double family_volume = s.volume[i] + s.family_volume[i];  // the horizon's ball (disc) holds the own cell too
    const double h = s.horizon[i];
    const double horizon_volume = dims == 3 ? 4.0 / 3.0 * M_PI * h * h * h : M_PI * h * h * s.thickness;
    complete[i] = family_volume >= 0.99 * horizon_volume;
  }
  // Distributed: over every rank's complete families (its own rows), in one process's order.
  MaterialSums bulk = sum_marked_by_material(dist, rows, complete, s.material, energy, dims, elastic.size());
  std::vector<double>& target = bulk.sum;
  const std::vector<int>& count = bulk.count;
  for (size_t m = 0; m < elastic.size(); ++m) {
    if (count[m]) {
      target[m] /= count[m];
    } else {
      const double uniaxial[9] = {1, 0, 0, 0, 0, 0, 0, 0, 0};
      target[m] = classical_energy_density(elastic[m], uniaxial);
    }
  }
  // Fixed-point sweeps on the shape: each axis factor moves by its energy's ratio to the
  // target, then the particle's factors are normalised to a geometric mean of 1 (their common
  // scale cancels in its own family; the coefficient scale below carries the magnitude).
  for (int sweep = 0; sweep < 30; ++sweep) {
#pragma omp parallel for
    for (size_t i = 0; i < n; ++i) {
      double log_mean = 0.0;
      for (int a = 0; a < dims; ++a) {
        // The step is bounded (a factor 2 either way; measured ones stay well inside it) so
        // that a family with next to no bonds along an axis cannot send its factor to inf.
        if (energy[3 * i + a] > 0)
          axis_factor[3 * i + a] *= std::clamp(target[s.material[i]] / energy[3 * i + a], 0.5, 2.0);
        log_mean += std::log(axis_factor[3 * i + a]) / dims;
      }
      for (int a = 0; a < dims; ++a) axis_factor[3 * i + a] /= std::exp(log_mean);
    }
    exchange_owned(dist, rows, axis_factor, 3);  // the ghosts' factors, which their bonds blend
    measure();
  }
  // The coefficient scale makes the mean of the particle's uniaxial energies the target.
  std::vector<double> coefficient_scale(n, 1.0);
  for (size_t i = 0; i < n; ++i) {
    double mean = 0.0;
    for (int a = 0; a < dims; ++a) mean += energy[3 * i + a] / dims;
    if (mean > 0) coefficient_scale[i] = target[s.material[i]] / mean;
  }
  exchange_owned(dist, rows, coefficient_scale, 1);  // the ghosts' LPS coefficients carry it
  scale_bonds_by_axis_factors(s, axis_factor);
  return coefficient_scale;
}

void scale_bonds_by_axis_factors(PdSystem& s, const std::vector<double>& axis_factor) {
  const bool dual = !s.dual_halves_shared;  // shared dual halves are the own ones (pd_system.hpp)
#pragma omp parallel for
  for (size_t i = 0; i < s.n; ++i)
    for (int64_t k = s.offsets[i]; k < s.offsets[i + 1]; ++k) {
      const double f = ellipsoid_bond_factor(s, axis_factor, i, k);
      s.k_own[k] *= f;
      if (dual) s.k_dual[k] *= f;
    }
}

}  // namespace breccia::solver
