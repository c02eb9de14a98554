// Verification of the frictional crack ([MPS harmonics] eqs 9-10; docs/references.md).
// Unit tests of the stick/slip law, crack geometry, and the 1D benchmark recommended in
// benchmarks.md section 8: a plane shear wave through a pre-compressed Coulomb interface
// (Meziane, Norris & Shuvalov 2011, JASA 130:1820, arXiv:1108.1556).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "breccia/mps/case_spec.hpp"
#include "breccia/mps/crack.hpp"
#include "breccia/mps/simulation.hpp"
#include "mps_test_util.hpp"

using namespace breccia::mps;

// --- the law for one pair --------------------------------------------------------------

TEST(MpsFrictionLaw, StickSpringHoldsUntilStaticLimitThenSlidesAtKineticForce) {
  FrictionLaw law{0.6, 0.4, 1e6, 1e7, 100.0, false, false};  // N0 = 100 N: limits 60 N / 40 N
  PairState st;
  // Spring force 1e6 * 5e-5 = 50 N < 60 N: stick, force opposes the relative displacement.
  PairForce f = friction_pair_force(law, 0.0, 5e-5, 1.0, st);
  EXPECT_EQ(st.slipping, 0);
  EXPECT_DOUBLE_EQ(f.tangent_n, -50.0);
  // 1e6 * 6.5e-5 = 65 N > 60 N: slip, kinetic force mu_k N = 40 N, same direction.
  f = friction_pair_force(law, 0.0, 6.5e-5, 1.0, st);
  EXPECT_EQ(st.slipping, 1);
  EXPECT_DOUBLE_EQ(f.tangent_n, -40.0);
  // Still sliding the same way: force stays mu_k N whatever the displacement.
  f = friction_pair_force(law, 0.0, 9e-5, 0.5, st);
  EXPECT_DOUBLE_EQ(f.tangent_n, -40.0);
  // Relative velocity changes sign: back to stick, paper rule: reference = current slide.
  f = friction_pair_force(law, 0.0, 9.1e-5, -0.1, st);
  EXPECT_EQ(st.slipping, 0);
  EXPECT_DOUBLE_EQ(st.stick_reference_m, 9.1e-5);
  EXPECT_DOUBLE_EQ(f.tangent_n, 0.0);
}

TEST(MpsFrictionLaw, ContinuousRestickKeepsTheFrictionForceAcrossTheTransition) {
  FrictionLaw law{0.5, 0.5, 1e6, 1e7, 100.0, false, true};
  PairState st;
  friction_pair_force(law, 0.0, 6e-5, 1.0, st);  // 60 N > 50 N: slip at 50 N
  const PairForce f = friction_pair_force(law, 0.0, 7e-5, -0.1, st);
  EXPECT_EQ(st.slipping, 0);
  EXPECT_NEAR(f.tangent_n, -50.0, 1e-9);  // spring starts at the friction force
}

TEST(MpsFrictionLaw, NormalForceIsThePerturbationOfThePreloadAndClappingFacesOpen) {
  FrictionLaw law{0.5, 0.5, 1e6, 1e7, 100.0, false, false};
  PairState st;
  // Closing by 1e-6 m adds kn * 1e-6 = 10 N of compression: perturbation +10 N on +.
  EXPECT_DOUBLE_EQ(friction_pair_force(law, -1e-6, 0.0, 0.0, st).normal_n, 10.0);
  // Contact-only mode: opening by 2e-5 m would need -100 N: faces held (bilateral).
  EXPECT_DOUBLE_EQ(friction_pair_force(law, 2e-5, 0.0, 0.0, st).normal_n, -200.0);
  EXPECT_EQ(st.open, 0);
  law.clapping = true;  // opened faces: total force 0, perturbation -N0, no friction
  const PairForce f = friction_pair_force(law, 2e-5, 1e-3, 1.0, st);
  EXPECT_DOUBLE_EQ(f.normal_n, -100.0);
  EXPECT_DOUBLE_EQ(f.tangent_n, 0.0);
  EXPECT_EQ(st.open, 1);
}

// --- crack geometry --------------------------------------------------------------------

TEST(MpsCrackGeometry, PairsFaceEachOtherAndNoBondCrossesTheCrack) {
  const std::string yaml = R"(
specimen:
  lattice: {dimension: 2, box: [0, 0, 10 mm, 10 mm], spacing: 0.25 mm}
model: {type: mps}
materials:
  - {name: steel, density: 7850, C13: 121.1 GPa, C55: 80.8 GPa}
cracks:
  - {name: c, segment: [[4 mm, 5 mm], [6 mm, 5 mm]], static_friction: 0.5, normal_stress: 1 MPa}
time: {end: 1 us}
)";
  const Simulation sim(parse_case_text(yaml));
  const CrackPairs& c = sim.cracks();
  ASSERT_EQ(c.size(), 8u);  // 2 mm crack / 0.25 mm spacing
  const auto& p = sim.position_m();
  for (size_t k = 0; k < c.size(); ++k) {
    EXPECT_NEAR(p[3 * c.plus[k]], p[3 * c.minus[k]], 1e-12);               // same column
    EXPECT_NEAR(p[3 * c.plus[k] + 1] - p[3 * c.minus[k] + 1], 0.25e-3, 1e-12);  // across the line
  }
  const BondList& b = sim.bonds();
  for (size_t i = 0; i + 1 < b.offset.size(); ++i)
    for (long long k = b.offset[i]; k < b.offset[i + 1]; ++k) {
      const double y0 = p[3 * i + 1], y1 = y0 + b.ry[k];
      const double x_cross = p[3 * i] + b.rx[k] * (5e-3 - y0) / (b.ry[k] == 0 ? 1 : b.ry[k]);
      const bool crosses_line = (y0 - 5e-3) * (y1 - 5e-3) < 0;
      EXPECT_FALSE(crosses_line && x_cross >= 4e-3 && x_cross <= 6e-3) << "bond " << i << " -> " << b.neighbour[k];
    }
}

// --- 1D plane shear wave through a pre-compressed Coulomb interface ---------------------

namespace {

// Rigid-in-stick Coulomb interface between identical half-spaces, normal incidence, mu_s =
// mu_k = mu: the interface slips while the incident stress exceeds mu sigma0 and re-sticks
// when it falls back (the slip rate is 2 (tau_i - tau) / Z), so the transmitted stress is the
// incident sine clipped at +-mu sigma0 (the rigid-plastic limit of Meziane et al. 2011; our
// assumption: stick is rigid, i.e. interface stiffness >> omega Z).
// Fourier sine coefficient n (odd) of A sin(theta) clipped at x A, per unit A:
double clipped_sine_coefficient(double x, int n) {
  if (x >= 1.0) return n == 1 ? 1.0 : 0.0;
  const double t0 = std::asin(x);
  if (n == 1) return (4.0 / std::numbers::pi) * (0.5 * (t0 - 0.5 * std::sin(2 * t0)) + x * std::cos(t0));
  return (4.0 / std::numbers::pi) *
         (0.5 * (std::sin((n - 1) * t0) / (n - 1) - std::sin((n + 1) * t0) / (n + 1)) + x * std::cos(n * t0) / n);
}

struct Harmonics {
  double h1 = 0, h2 = 0, h3 = 0, h5 = 0;
};

constexpr double kFrequency = 0.5e6, kPeriod = 2e-6, kAmplitude = 1e-8;
const double kImpedanceS = 7850 * std::sqrt(80.8e9 / 7850);                      // rho c_T
const double kImpedanceP = 7850 * std::sqrt((121.1e9 + 2 * 80.8e9) / 7850);       // rho c_L
const double kIncidentShearStress = kImpedanceS * kAmplitude * 2 * std::numbers::pi * kFrequency;

// Strip 2 mm wide (periodic), 90 mm long; 10-cycle burst on the top face; interface across
// the whole width at y = 50 mm; receiver 5 mm below it. Lock-in over cycles 3..8 at the
// receiver, away from the burst's start and end transients. 40 mm between source and
// interface: the wave reflected by the interface and again by the displacement-driven top
// face needs 25 us to come back, after the analysis window (a shorter cavity makes a
// Fabry-Perot build-up that biases the amplitudes).
Harmonics interface_run(const std::string& component, const std::string& crack_yaml) {
  const std::string yaml = test::fill(R"(
specimen:
  lattice: {dimension: 2, box: [0, 0, 2 mm, 90 mm], spacing: 0.25 mm, periodic: [true, false]}
model: {type: mps, integrator: velocity_verlet}
materials:
  - {name: steel, density: 7850, C13: 121.1 GPa, C55: 80.8 GPa}
cracks: ${CRACKS}
boundary:
  - {face: top, components: [${C}], displacement: {amplitude: ${A}, frequency: ${F}, cycles: 10}}
time: {end: 31 us}
)",
                                      {{"CRACKS", crack_yaml}, {"C", component}, {"A", test::num(kAmplitude)},
                                       {"F", test::num(kFrequency)}});
  Simulation sim(parse_case_text(yaml));
  const std::string field = std::string("velocity_") + component;
  const auto tr = test::run_and_record(sim, {1e-3, 45e-3, 0}, field);
  const double speed = component == "x" ? std::sqrt(80.8e9 / 7850) : std::sqrt((121.1e9 + 2 * 80.8e9) / 7850);
  const double arrival = 45e-3 / speed;
  const double t0 = arrival + 3 * kPeriod, t1 = arrival + 8 * kPeriod;
  Harmonics h;
  h.h1 = test::harmonic_amplitude(tr, kFrequency, 1, t0, t1);
  h.h2 = test::harmonic_amplitude(tr, kFrequency, 2, t0, t1);
  h.h3 = test::harmonic_amplitude(tr, kFrequency, 3, t0, t1);
  h.h5 = test::harmonic_amplitude(tr, kFrequency, 5, t0, t1);
  return h;
}

std::string friction_crack(double mu_s, double mu_k, double sigma0, const std::string& restick,
                           const std::string& mode = "sliding") {
  return "[{segment: [[0, 50 mm], [2 mm, 50 mm]], static_friction: " + test::num(mu_s) +
         ", kinetic_friction: " + test::num(mu_k) + ", normal_stress: " + test::num(sigma0) + ", restick: " + restick +
         ", mode: " + mode + "}]";
}

}  // namespace

TEST(MpsFrictionInterface, ShearWaveHarmonicsFollowTheClippedSineOfCoulombFriction) {
  // Sweep x = mu sigma0 / tau_incident (tau_incident = rho c_T u0 omega = 0.79 MPa).
  const Harmonics intact = interface_run("x", "[]");
  const double mu = 0.5;
  std::printf("incident shear stress %.4g Pa; intact: V1 %.4g m/s, V3/V1 %.2e\n", kIncidentShearStress, intact.h1,
              intact.h3 / intact.h1);
  double previous_ratio = 0.0;
  for (double x : {1.5, 0.8, 0.6, 0.4, 0.25}) {
    const Harmonics h = interface_run("x", friction_crack(mu, mu, x * kIncidentShearStress / mu, "continuous"));
    const double b1 = clipped_sine_coefficient(x, 1), b3 = clipped_sine_coefficient(x, 3), b5 = clipped_sine_coefficient(x, 5);
    const double r3 = h.h3 / h.h1;
    std::printf("x = %.2f: V1/V1_intact %.4f (theory %.4f); V3/V1 %.4f (theory %.4f); V5/V1 %.4f (theory %.4f); V2/V1 %.2e\n",
                x, h.h1 / intact.h1, b1, r3, b3 / b1, h.h5 / h.h1, std::abs(b5) / b1, h.h2 / h.h1);
    if (x >= 1.0) {
      // Below the slip threshold the interface sticks and stays linear: no harmonics. 0.005:
      // ten times the intact run's floor (start transient of the burst, 4e-4) and 15x below
      // the smallest slipping value.
      EXPECT_LT(r3, 0.005);
      EXPECT_NEAR(h.h1 / intact.h1, 1.0, 0.01);  // sticking crack ~ invisible (stiffness factor 1)
      continue;
    }
    // Transmitted fundamental and 3rd-harmonic ratio against the clipped sine. 15% on the
    // ratio: the analytic model has a rigid stick and a sharp stick/slip switch, the lattice
    // has a finite interface stiffness and disperses the 3rd harmonic (13 points per
    // wavelength at 1.5 MHz); measured deviations are 2-9%. 3% on V1 for the same reasons.
    EXPECT_NEAR(r3, b3 / b1, 0.15 * b3 / b1) << "x = " << x;
    EXPECT_NEAR(h.h1 / intact.h1, b1, 0.03) << "x = " << x;
    // The published trend: the harmonic ratio grows as the amplitude parameter
    // tau_incident / (mu sigma0) = 1/x grows.
    EXPECT_GT(r3, previous_ratio) << "x = " << x;
    previous_ratio = r3;
    // Coulomb friction is odd in the shear stress: no even harmonics. 1.5%: twice the largest
    // residual measured (burst transients), ten times below the clapping 2f level below.
    EXPECT_LT(h.h2 / h.h1, 0.015) << "x = " << x;
  }
}

TEST(MpsFrictionInterface, PaperRestickRuleAlsoGivesOddHarmonicsOnly) {
  // Paper rule: at re-stick the spring restarts from zero force, so the transmitted stress
  // dips after every slip episode. Still odd in the stress: 3rd harmonic present, no 2nd.
  const double x = 0.5;
  const Harmonics h = interface_run("x", friction_crack(0.5, 0.5, x * kIncidentShearStress / 0.5, "paper"));
  std::printf("paper rule, x = %.2f: V3/V1 %.4f (clipped sine %.4f); V5/V1 %.4f; V2/V1 %.2e\n", x, h.h3 / h.h1,
              clipped_sine_coefficient(x, 3) / clipped_sine_coefficient(x, 1), h.h5 / h.h1, h.h2 / h.h1);
  EXPECT_GT(h.h3 / h.h1, 0.05);
  // 3%: the reset makes each cycle's force depend on where the previous slip ended, so the
  // first half-cycles differ from later ones (measured 1.8%); still 20x below clapping.
  EXPECT_LT(h.h2 / h.h1, 0.03);
}

TEST(MpsFrictionInterface, ClappingInterfaceUnderPWaveMakesSecondHarmonic) {
  // A P wave whose tensile half exceeds the pre-compression opens the faces (clapping):
  // the transmitted stress is clipped on the tensile side only, an even distortion, so 2f
  // appears (Richardson 1979). sigma0 = 0.5 x incident P stress.
  const double sigma_incident = kImpedanceP * kAmplitude * 2 * std::numbers::pi * kFrequency;
  const Harmonics clap = interface_run("y", friction_crack(0.5, 0.5, 0.5 * sigma_incident, "continuous", "clapping"));
  std::printf("clapping, sigma0 = 0.5 sigma_i: V2/V1 %.4f V3/V1 %.4f\n", clap.h2 / clap.h1, clap.h3 / clap.h1);
  // 0.15: ten times the sliding case's bound on 2f (one-sided clipping at half the
  // amplitude gives a 2f ratio of order 0.2-0.3 for a half-wave-clipped sine).
  EXPECT_GT(clap.h2 / clap.h1, 0.15);
}
