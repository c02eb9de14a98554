#include "breccia/solver/calibration.hpp"
#include "breccia/solver/case_config.hpp"

#include <array>
#include <cmath>
#include <numbers>
#include <vector>
#include <algorithm>

namespace breccia::solver {

double gaussian_moment(int k);

double influence_moment(Influence kind, int k) {
  switch (kind) {
    case Influence::Constant: return 1.0 / (k + 1);
    case Influence::Inverse: return 1.0 / k;
    case Influence::Gaussian: {
      // Composite Simpson, 2000 intervals: exact to ~1e-14 for this smooth integrand.
      // Cached: set-up asks for these once per bond.
      static const auto table = [] {
        std::array<double, 8> t{};
        for (int kk = 0; kk < 8; ++kk) t[kk] = gaussian_moment(kk);
        return t;
      }();
      if (k >= 0 && k < 8) return table[k];
      return gaussian_moment(k);
    }
  }
  return 0.0;
}

double gaussian_moment(int k) {
  {
      const int n = 2000;
      double sum = 0.0;
      for (int i = 0; i <= n; ++i) {
        const double q = static_cast<double>(i) / n;
        const double w = (i == 0 || i == n) ? 1.0 : (i % 2 ? 4.0 : 2.0);
        sum += w * std::exp(-q * q) * std::pow(q, k);
      }
      return sum / (3.0 * n);
  }
}

double dimensional_bulk_modulus(const ElasticInput& in) {
  const double E = in.youngs_modulus, nu = in.poisson_ratio;
  if (in.dimension == 3) return E / (3.0 * (1.0 - 2.0 * nu));
  if (in.planar == Planar::PlaneStress) return E / (2.0 * (1.0 - nu));
  return E / (2.0 * (1.0 + nu) * (1.0 - 2.0 * nu));
}

double shear_modulus(const ElasticInput& in) { return in.youngs_modulus / (2.0 * (1.0 + in.poisson_ratio)); }

double pmb_poisson_ratio(int dimension, Planar planar) {
  return (dimension == 2 && planar == Planar::PlaneStress) ? 1.0 / 3.0 : 0.25;
}

namespace {
// int_H omega(|xi|/delta) |xi| dV: 3D 4 pi delta^4 J3; 2D (dV = t dA) 2 pi t delta^3 J2.
double first_moment_integral(const ElasticInput& in, Influence kind, double delta) {
  using std::numbers::pi;
  if (in.dimension == 3) return 4.0 * pi * std::pow(delta, 4) * influence_moment(kind, 3);
  return 2.0 * pi * in.thickness * std::pow(delta, 3) * influence_moment(kind, 2);
}
}  // namespace

double pmb_micromodulus(const ElasticInput& in, Influence kind, double delta) {
  const double d = in.dimension;
  return 2.0 * d * d * dimensional_bulk_modulus(in) / first_moment_integral(in, kind, delta);
}

double pmb_critical_stretch(const ElasticInput& in, Influence kind, double delta, double G0) {
  using std::numbers::pi;
  const double c0 = pmb_micromodulus(in, kind, delta);
  // 3D: G0 = pi/2 c0 s0^2 delta^5 J4;  2D: G0 = t c0 s0^2 delta^4 J3 (docs/theory.md).
  if (in.dimension == 3) return std::sqrt(2.0 * G0 / (pi * c0 * std::pow(delta, 5) * influence_moment(kind, 4)));
  return std::sqrt(G0 / (in.thickness * c0 * std::pow(delta, 4) * influence_moment(kind, 3)));
}

// 3D: G0 = 15 mu delta J5 / (4 J4) s0^2;  2D: G0 = 8 mu delta J4 / (pi J3) s0^2.
LpsCriticalStretch::LpsCriticalStretch(const ElasticInput& in, Influence kind) {
  using std::numbers::pi;
  const double mu = shear_modulus(in);
  const bool three = in.dimension == 3;
  energy_factor_ = three ? 4.0 : pi;
  energy_moment_ = influence_moment(kind, three ? 4 : 3);
  shear_factor_ = (three ? 15.0 : 8.0) * mu;
  shear_moment_ = influence_moment(kind, three ? 5 : 4);
}

double lps_critical_stretch(const ElasticInput& in, Influence kind, double delta, double G0) {
  return LpsCriticalStretch(in, kind)(delta, G0);
}

// Same keeps the expression the set-up has always used (strength x draw / mean), so runs
// without the option stay bit-identical.
double weibull_bond_strength(const MaterialSpec& m, double drawn_g0) {
  switch (m.weibull_strength) {
    case MaterialSpec::WeibullStrength::Sqrt: return m.tensile_strength * std::sqrt(drawn_g0 / m.fracture_energy);
    case MaterialSpec::WeibullStrength::None: return m.tensile_strength;
    case MaterialSpec::WeibullStrength::Same: break;
  }
  return m.tensile_strength * drawn_g0 / m.fracture_energy;
}

double softening_onset_stretch(const ElasticInput& in, double tensile_strength) {
  const double nu = in.poisson_ratio;
  const double E = in.dimension == 2 && in.planar == Planar::PlaneStrain ? in.youngs_modulus / (1.0 - nu * nu)
                                                                          : in.youngs_modulus;
  return tensile_strength / E;
}

// The model at one material point under homogeneous strain diag(ex, el, el) (2D: ex, el),
// written with the family's angular average <.> (the radial parts of the sums cancel for any
// influence function): PMB g(n) = d^2 K_d (1 - D(n)) s(n); LPS g(n) = (1 - D(n)) (a theta +
// b s(n)), theta = d <(1 - D) s>, a = bulk_term - shear_term / d, b = shear_term; the stress is
// <g(n) n (x) n>. s(n) = ex n_x^2 + el (1 - n_x^2). Uniaxial stress: el solves sigma_yy = 0,
// which is linear in el once the damage is fixed, so each strain step iterates (el, damage) to
// a fixed point, the damage never decreasing along the path.
namespace {
// The isotropic family of the continuum: 720 directions, 3D uniform in n_x = cos(angle) on
// [0, 1], 2D uniform in the angle on [0, pi/2]; each of weight 1.
HomogeneousFamily isotropic_family(int dimension) {
  const int nq = 720;
  HomogeneousFamily f;
  for (int q = 0; q < nq; ++q) {
    const double t = (q + 0.5) / nq;
    const double c = dimension == 3 ? t : std::cos(0.5 * std::numbers::pi * t);
    f.axial2.push_back(c * c);
    f.weight.push_back(1.0);
  }
  return f;
}

// sign +1: uniaxial tension (the strain ex grows); -1: uniaxial compression (ex falls), the bonds
// crushing past crush_ratio x onset when crush_ratio > 0. Returns sign x the first peak of sigma_xx.
double homogeneous_uniaxial_peak(const ElasticInput& in, PdModel model, const HomogeneousFamily& family, double onset,
                                 double ultimate, double sign, double crush_ratio) {
  const bool lps = model != PdModel::PMB;
  const LpsCoefficients lc = lps_coefficients(in);
  const double pmb_scale = in.dimension * in.dimension * dimensional_bulk_modulus(in);
  const std::vector<double>& cx2 = family.axial2;
  const std::vector<double>& weight = family.weight;
  const size_t nq = cx2.size();
  std::vector<double> dmg(nq, 0.0), trial(nq);
  double weight_sum = 0.0;
  for (const double w : weight) weight_sum += w;
  // The mean lateral stress is (3D) half of <g (1 - n_x^2)> (the azimuth averages out; a
  // lattice family, symmetric under y <-> z, has sigma_yy = sigma_zz), 2D all of it.
  const double lateral_share = in.dimension == 3 ? 0.5 : 1.0;
  // Stresses for strain (ex, el) and damage D: returns sigma_xx, sets sigma_yy.
  auto stress = [&](double ex, double el, const std::vector<double>& D, double& syy) {
    double theta = 0.0;
    if (lps) {
      for (size_t q = 0; q < nq; ++q) theta += weight[q] * (1.0 - D[q]) * (ex * cx2[q] + el * (1.0 - cx2[q]));
      theta *= lc.dilatation_factor / weight_sum;
    }
    double sxx = 0.0;
    syy = 0.0;
    for (size_t q = 0; q < nq; ++q) {
      const double s = ex * cx2[q] + el * (1.0 - cx2[q]);
      const double g = weight[q] * (1.0 - D[q]) *
                       (lps ? (lc.bulk_term - lc.shear_term / lc.dilatation_factor) * theta + lc.shear_term * s
                            : pmb_scale * s);
      sxx += g * cx2[q];
      syy += g * (1.0 - cx2[q]);
    }
    syy *= lateral_share / weight_sum;
    return sxx / weight_sum;
  };
  // Damage of a bond at stretch s: the tension law, and in compression the crushing law.
  auto law = [&](double s) {
    const double t = softening_damage<double>(s, onset, ultimate);
    if (!(crush_ratio > 0.0) || s >= 0.0) return t;
    return std::max(t, softening_damage<double>(-s, crush_ratio * onset, crush_ratio * ultimate));
  };
  double el = 0.0, peak = 0.0;
  const double step = onset / 400.0;
  const double reach = (sign > 0.0 ? 4.0 : 4.0 * std::max(1.0, crush_ratio)) * ultimate + onset;
  for (double mag = sign > 0.0 ? onset : step; mag < reach; mag += step) {
    const double ex = sign * mag;
    for (int it = 0; it < 100; ++it) {
      for (size_t q = 0; q < nq; ++q)
        trial[q] = std::max(dmg[q], law(ex * cx2[q] + el * (1.0 - cx2[q])));
      double s0y, s1y;
      stress(ex, 0.0, trial, s0y);
      stress(ex, onset, trial, s1y);
      const double next = -s0y * onset / (s1y - s0y);
      const bool settled = std::fabs(next - el) <= 1e-12 * mag;
      el = next;
      if (settled) break;
    }
    for (size_t q = 0; q < nq; ++q)
      dmg[q] = std::max(dmg[q], law(ex * cx2[q] + el * (1.0 - cx2[q])));
    double syy;
    const double sxx = sign * stress(ex, el, dmg, syy);
    if (sxx < peak) break;  // the first maximum: where a bar starts to localise
    peak = sxx;
  }
  return peak;
}
}  // namespace

double homogeneous_tension_peak(const ElasticInput& in, PdModel model, double onset, double ultimate) {
  return homogeneous_uniaxial_peak(in, model, isotropic_family(in.dimension), onset, ultimate, 1.0, 0.0);
}

double homogeneous_compression_peak(const ElasticInput& in, PdModel model, double onset, double ultimate,
                                    double crush_ratio) {
  return homogeneous_uniaxial_peak(in, model, isotropic_family(in.dimension), onset, ultimate, -1.0, crush_ratio);
}

double homogeneous_compression_peak(const ElasticInput& in, PdModel model, const HomogeneousFamily& family,
                                    double onset, double ultimate, double crush_ratio) {
  return homogeneous_uniaxial_peak(in, model, family, onset, ultimate, -1.0, crush_ratio);
}

double calibrated_onset_stretch(const ElasticInput& in, PdModel model, double tensile_strength, double brittle_stretch) {
  // Fixed point of s_t = sigma_t / Phi(s_G^2 / s_t^2), Phi(r) the homogeneous peak per unit
  // onset at ultimate / onset = r (homogeneous_tension_peak is linear in the onset). Phi grows
  // slowly with r (|d ln Phi / d ln s_t| < 0.3), so the iteration contracts.
  double onset = softening_onset_stretch(in, tensile_strength);
  for (int it = 0; it < 60; ++it) {
    if (brittle_stretch < onset) return onset;  // no room for softening: the caller refuses it
    const double ratio = (brittle_stretch / onset) * (brittle_stretch / onset);
    const double next = tensile_strength / (homogeneous_tension_peak(in, model, 1.0, ratio));
    const bool settled = std::fabs(next - onset) <= 1e-7 * onset;
    onset = next;
    if (settled) break;
  }
  return onset;
}

LpsCoefficients lps_coefficients(const ElasticInput& in) {
  const double Kd = dimensional_bulk_modulus(in), mu = shear_modulus(in);
  if (in.dimension == 3) return {3.0, 3.0 * Kd, 15.0 * mu};
  return {2.0, 2.0 * Kd, 8.0 * mu};
}

double classical_energy_density(const ElasticInput& in, const double eps[9]) {
  const double mu = shear_modulus(in);
  const int d = in.dimension;
  double tr = 0.0;
  for (int a = 0; a < d; ++a) tr += eps[4 * a];
  double dev2 = 0.0;  // eps_dev : eps_dev in d dimensions
  for (int a = 0; a < d; ++a)
    for (int b = 0; b < d; ++b) {
      const double e = eps[3 * a + b] - (a == b ? tr / d : 0.0);
      dev2 += e * e;
    }
  return 0.5 * dimensional_bulk_modulus(in) * tr * tr + mu * dev2;
}

}  // namespace breccia::solver
