// Unit tests (closed-form values) of the J2 return mapping of plasticity.hpp.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "breccia/mps/plasticity.hpp"

using namespace breccia::mps;

namespace {

// Steel-like constants; the claims below hold for any positive moduli.
constexpr double kYoung = 210e9, kPoisson = 0.3;
constexpr double kShear = kYoung / (2 * (1 + kPoisson));
constexpr double kLambda = kYoung * kPoisson / ((1 + kPoisson) * (1 - 2 * kPoisson));
constexpr double kBulk = kLambda + 2.0 * kShear / 3.0;
constexpr double kYield = 240e6;

// Uniaxial strain eps along x (eps_yy = eps_zz = 0), monotonic loading, closed form:
// the deviatoric strain is eps (2/3, -1/3, -1/3), q = |sigma_xx - sigma_yy|; elastic until
// 2 mu eps = sigma_y0, then the plastic multiplier is gamma = (2 mu eps - sigma_y0)/(3 mu + H)
// (plastic strain (gamma, -gamma/2, -gamma/2), so q = 2 mu (eps - 3 gamma/2) = sigma_y0 + H gamma),
// and sigma_xx = K eps + (2/3) q.
double uniaxial_strain_sigma_xx(double eps, double hardening) {
  const double q_elastic = 2.0 * kShear * eps;
  if (q_elastic <= kYield) return (kLambda + 2.0 * kShear) * eps;
  const double gamma = (2.0 * kShear * eps - kYield) / (3.0 * kShear + hardening);
  return kBulk * eps + 2.0 / 3.0 * (kYield + hardening * gamma);
}

// Strain eps_xx changed by `change` in equal increments from the given state (stress and
// equivalent plastic strain), each a Hooke trial and a radial return.
void strain_uniaxially(const VonMisesHardening& m, SymTensor& stress, double change, int increments,
                       double& eq_plastic) {
  for (int k = 0; k < increments; ++k) {
    SymTensor d;
    d.xx = change / increments;
    add_hooke_increment(stress, d, kLambda, kShear);
    radial_return(m, stress, eq_plastic);
  }
}

SymTensor run_uniaxial_strain(const VonMisesHardening& m, double eps_end, int increments, double& eq_plastic) {
  SymTensor stress;
  eq_plastic = 0.0;
  strain_uniaxially(m, stress, eps_end, increments, eq_plastic);
  return stress;
}

}  // namespace

TEST(MpsReturnMapping, UniaxialStrainFollowsClosedFormBilinearCurve) {
  for (const double hardening : {0.0, 2e9, 20e9}) {
    const VonMisesHardening m{kShear, kYield, hardening};
    const double eps_yield = kYield / (2.0 * kShear);
    for (const double eps : {0.5 * eps_yield, 1.0 * eps_yield, 3.0 * eps_yield, 20.0 * eps_yield}) {
      double eq_plastic = 0.0;
      const SymTensor s = run_uniaxial_strain(m, eps, 200, eq_plastic);
      // 1e-9 relative: the path is radial (the deviator keeps its direction), where the
      // backward-Euler return is exact whatever the increment; only rounding remains.
      EXPECT_NEAR(s.xx, uniaxial_strain_sigma_xx(eps, hardening), 1e-9 * std::fabs(s.xx)) << "H " << hardening;
      EXPECT_NEAR(s.yy, s.zz, 1e-9 * std::fabs(s.xx));
      const double gamma = std::max(0.0, (2.0 * kShear * eps - kYield) / (3.0 * kShear + hardening));
      EXPECT_NEAR(eq_plastic, gamma, 1e-9 * eps);
    }
  }
}

TEST(MpsReturnMapping, OneLargeIncrementGivesTheSameStressAsManySmallOnes) {
  // Radial path: the return mapping is exact, so the increment size must not matter.
  const VonMisesHardening m{kShear, kYield, 5e9};
  const double eps = 10.0 * kYield / (2.0 * kShear);
  double e1 = 0.0, e2 = 0.0;
  const SymTensor one = run_uniaxial_strain(m, eps, 1, e1);
  const SymTensor many = run_uniaxial_strain(m, eps, 1000, e2);
  EXPECT_NEAR(one.xx, many.xx, 1e-9 * std::fabs(many.xx));  // rounding only
  EXPECT_NEAR(e1, e2, 1e-9 * e2);
}

TEST(MpsReturnMapping, PartialUnloadingIsElasticAndFollowsTheElasticSlope) {
  const double hardening = 2e9;
  const VonMisesHardening m{kShear, kYield, hardening};
  const double eps_yield = kYield / (2.0 * kShear);
  const double eps_max = 3.0 * eps_yield;
  // Unloading changes q by 2 mu d eps; reverse yield needs a change of 2 (sigma_y0 + H gamma),
  // so taking back 1.5 eps_yield (q drops by 1.5 sigma_y0) stays elastic.
  const double eps_back = 1.5 * eps_yield;
  double eq_plastic = 0.0;
  SymTensor s = run_uniaxial_strain(m, eps_max, 100, eq_plastic);
  const double plastic_after_loading = eq_plastic;
  strain_uniaxially(m, s, -eps_back, 100, eq_plastic);
  EXPECT_EQ(eq_plastic, plastic_after_loading);  // no plastic flow on unloading
  const double expected = uniaxial_strain_sigma_xx(eps_max, hardening) - (kLambda + 2.0 * kShear) * eps_back;
  EXPECT_NEAR(s.xx, expected, 1e-9 * kYield);  // rounding only
}

TEST(MpsReturnMapping, FullUnloadingYieldsInReverseAtTheHardenedYieldStress) {
  // From eps_max = 3 eps_yield back to 0: q must fall by 3 sigma_y0 > 2 (sigma_y0 + H gamma),
  // so the material yields again in compression, ending on the surface q = sigma_y0 + H eps_p
  // (isotropic hardening: the accumulated plastic strain counts in both directions).
  const VonMisesHardening m{kShear, kYield, 2e9};
  const double eps_max = 3.0 * kYield / (2.0 * kShear);
  double eq_plastic = 0.0;
  SymTensor s = run_uniaxial_strain(m, eps_max, 100, eq_plastic);
  const double after_loading = eq_plastic;
  strain_uniaxially(m, s, -eps_max, 100, eq_plastic);
  EXPECT_GT(eq_plastic, after_loading);
  EXPECT_LT(s.xx - s.yy, 0.0);  // compressive deviator after reverse yield
  EXPECT_NEAR(von_mises_stress(s), m.yield_stress_at(eq_plastic), 1e-9 * kYield);  // rounding only
}

TEST(MpsReturnMapping, ReturnedStressLiesOnTheHardenedYieldSurfaceWithUnchangedPressureAndDirection) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> component(-2e9, 2e9);
  const VonMisesHardening m{kShear, kYield, 3e9};
  int plastic_cases = 0;
  for (int trial = 0; trial < 200; ++trial) {
    SymTensor s{component(rng), component(rng), component(rng), component(rng), component(rng), component(rng)};
    const SymTensor trial_stress = s;
    double eq_plastic = 0.01 * (trial % 5);
    const double before = eq_plastic;
    const double delta = radial_return(m, s, eq_plastic);
    if (delta == 0.0) {
      EXPECT_LE(von_mises_stress(trial_stress), m.yield_stress_at(before));
      continue;
    }
    ++plastic_cases;
    // 1e-12 relative: the return is closed-form, so consistency holds to rounding.
    EXPECT_NEAR(von_mises_stress(s), m.yield_stress_at(eq_plastic), 1e-12 * von_mises_stress(trial_stress));
    EXPECT_NEAR(pressure_of(s), pressure_of(trial_stress), 1e-12 * std::fabs(component.max()));
    // Radial: the deviator is a positive multiple of the trial deviator (here the shear components).
    const double ratio = von_mises_stress(s) / von_mises_stress(trial_stress);
    EXPECT_NEAR(s.xy, ratio * trial_stress.xy, 1e-9 * std::fabs(trial_stress.xy) + 1.0);
    EXPECT_NEAR(s.yz, ratio * trial_stress.yz, 1e-9 * std::fabs(trial_stress.yz) + 1.0);
    // Backward Euler: delta_gamma = f_trial / (3 mu + H).
    EXPECT_NEAR(delta, (von_mises_stress(trial_stress) - m.yield_stress_at(before)) / (3 * kShear + m.hardening_modulus_pa),
                1e-12);
  }
  EXPECT_GT(plastic_cases, 150);  // the sampled stresses are mostly far outside the surface
}
