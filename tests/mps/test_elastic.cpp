// Verification of the MPS elastic-wave solver against the isotropic wave speeds
// c_L = sqrt((lambda + 2 mu)/rho), c_T = sqrt(mu/rho) (any elasticity text, e.g. Achenbach
// 1973, ch. 4), the sqrt(2) error of the paper's rotation-free eq. (6) (docs/mps.md,
// "Physics and numerics"), and conservation of the discrete energy in free vibration.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "breccia/mps/case_spec.hpp"
#include "breccia/mps/simulation.hpp"
#include "mps_test_util.hpp"

using namespace breccia::mps;

namespace {

// Steel of [MPS harmonics]: rho 7850, C13 = lambda = 121.1 GPa, C55 = mu = 80.8 GPa.
const double kRho = 7850, kLambda = 121.1e9, kMu = 80.8e9;
const double kCL = std::sqrt((kLambda + 2 * kMu) / kRho), kCT = std::sqrt(kMu / kRho);

// A long strip, periodic across (x), excited on its top face by a Hann-windowed tone
// burst: a plane wave travelling down -y, P (component y) or S (component x).
std::string strip_case(const std::string& equation, const std::string& component, double frequency_hz,
                       double end_s) {
  return test::fill(R"(
specimen:
  lattice: {dimension: 2, box: [0, 0, 2 mm, 200 mm], spacing: 0.25 mm, periodic: [true, false]}
model: {type: mps, equation: ${EQ}}
materials:
  - {name: steel, density: 7850, C13: 121.1 GPa, C55: 80.8 GPa}
boundary:
  - {face: top, components: [${C}], displacement: {amplitude: 1.0e-8, frequency: ${F}, cycles: 3, window: hann}}
time: {end: ${END}}
)",
                    {{"EQ", equation}, {"C", component}, {"F", test::num(frequency_hz)}, {"END", test::num(end_s)}});
}

// Travel time between two receivers 40 mm apart from the peak of their cross-correlation
// (parabolic sub-sample refinement).
double measured_speed(const std::string& yaml, const std::string& field) {
  Simulation a(parse_case_text(yaml));
  Simulation b(parse_case_text(yaml));
  const auto near = test::run_and_record(a, {1e-3, 170e-3, 0}, field);
  const auto far = test::run_and_record(b, {1e-3, 130e-3, 0}, field);
  const size_t n = near.value.size();
  long long best_lag = 0;
  double best = -1e300;
  auto corr = [&](long long lag) {
    double c = 0.0;
    for (size_t k = 0; k < n; ++k) {
      const long long m = static_cast<long long>(k) + lag;
      if (m >= 0 && m < static_cast<long long>(n)) c += near.value[k] * far.value[m];
    }
    return c;
  };
  for (long long lag = 0; lag < static_cast<long long>(n); ++lag) {
    const double c = corr(lag);
    if (c > best) {
      best = c;
      best_lag = lag;
    }
  }
  const double y0 = corr(best_lag - 1), y1 = best, y2 = corr(best_lag + 1);
  const double lag = best_lag + 0.5 * (y0 - y2) / (y0 - 2 * y1 + y2);
  return 40e-3 / (lag * a.dt_s());
}

}  // namespace

TEST(MpsElasticWaves, NavierPWaveTravelsAtTheLongitudinalSpeed) {
  // 1 MHz: lambda_P = 6 mm = 24 spacings. 2%: the lattice's dispersion at 24 points per
  // wavelength (measured ~0.5% slow) plus the cross-correlation's sub-sample resolution.
  const double c = measured_speed(strip_case("navier", "y", 1e6, 20e-6), "displacement_y");
  std::printf("P wave: measured %.1f m/s, c_L %.1f m/s (%+.2f%%)\n", c, kCL, 100 * (c / kCL - 1));
  EXPECT_NEAR(c / kCL, 1.0, 0.02) << "measured " << c << " m/s, c_L " << kCL;
}

TEST(MpsElasticWaves, NavierSWaveTravelsAtTheShearSpeed) {
  // 0.5 MHz: lambda_T = 6.4 mm = 26 spacings; same 2% budget as the P wave.
  const double c = measured_speed(strip_case("navier", "x", 0.5e6, 35e-6), "displacement_x");
  std::printf("S wave: measured %.1f m/s, c_T %.1f m/s (%+.2f%%)\n", c, kCT, 100 * (c / kCT - 1));
  EXPECT_NEAR(c / kCT, 1.0, 0.02) << "measured " << c << " m/s, c_T " << kCT;
}

TEST(MpsElasticWaves, RotationFreeFormOfThePaperMakesShearWavesSqrt2TooFast) {
  // Eq. (6) has 2 C55 lap u where the Navier equation has C55 lap u + (lambda + mu) grad div u;
  // for a shear wave div u = 0, so c = sqrt(2 C55 / rho) = sqrt(2) c_T (docs/mps.md).
  const double c = measured_speed(strip_case("rotation_free", "x", 0.5e6, 30e-6), "displacement_x");
  std::printf("rotation-free S wave: measured %.1f m/s = %.3f c_T (sqrt 2 = 1.414)\n", c, c / kCT);
  EXPECT_NEAR(c / (std::sqrt(2.0) * kCT), 1.0, 0.03) << "measured " << c << " m/s";
  EXPECT_GT(c / kCT, 1.3);  // clearly not the physical shear speed
  // ...while its P wave is right: C13 + 2 C55 = lambda + 2 mu.
  const double cp = measured_speed(strip_case("rotation_free", "y", 1e6, 20e-6), "displacement_y");
  EXPECT_NEAR(cp / kCL, 1.0, 0.02);
}

namespace {

std::string free_block_case(const std::string& integrator, const std::string& equation, double safety) {
  return test::fill(R"(
specimen:
  lattice: {dimension: 2, box: [0, 0, 20 mm, 15 mm], spacing: 0.5 mm}
model: {type: mps, equation: ${EQ}, integrator: ${INT}}
materials:
  - {name: steel, density: 7850, C13: 121.1 GPa, C55: 80.8 GPa}
initial:
  displacement: {center: [8 mm, 6 mm], width: 2 mm, amplitude: [1.0e-6, -0.5e-6]}
time: {end: 40 us, safety: ${S}}
)",
                    {{"EQ", equation}, {"INT", integrator}, {"S", test::num(safety)}});
}

// Largest |E(t) - E(0)| / E(0) over the run, E = kinetic + elastic (discrete potential).
double energy_error(const std::string& yaml) {
  Simulation sim(parse_case_text(yaml));
  const double e0 = sim.kinetic_energy_j() + sim.elastic_energy_j();
  double worst = 0.0;
  const long long steps = static_cast<long long>(sim.spec().end_time_s / sim.dt_s());
  for (long long s = 0; s < steps; ++s) {
    sim.step();
    if (s % 10 == 0) worst = std::max(worst, std::abs(sim.kinetic_energy_j() + sim.elastic_energy_j() - e0) / e0);
  }
  return worst;
}

}  // namespace

TEST(MpsElasticWaves, FreeVibrationConservesEnergyWithVelocityVerlet) {
  // Free block, free surfaces, 40 us (about 12 P-wave transits). The force is minus the
  // gradient of the discrete energy (adjoint gradient in grad div), so velocity Verlet keeps
  // E(u^k, v^k) within an O((omega dt)^2) band without drift. The Gaussian start excites
  // modes up to the grid scale (omega dt ~ 0.6 at CFL 0.5): 2% band; halving dt must
  // shrink it about 4x (second order), which a drifting, non-conservative force would not (2.5: the
  // O((omega dt)^4) terms at omega dt ~ 0.6 pull the ratio below 4; first order gives 2).
  for (const char* eq : {"navier", "rotation_free"}) {
    const double err = energy_error(free_block_case("velocity_verlet", eq, 0.5));
    const double err_half = energy_error(free_block_case("velocity_verlet", eq, 0.25));
    EXPECT_LT(err, 0.02) << eq;
    EXPECT_GT(err / err_half, 2.5) << eq << ": " << err << " vs " << err_half;
  }
}

TEST(MpsElasticWaves, FreeVibrationEnergyOfSymplecticEulerStaysBounded) {
  // Symplectic Euler conserves a shadow energy; E(u^k, v^k) differs from it by O(omega dt):
  // a bounded band (5% at CFL 0.5) that halves with dt (first order: ratio ~2).
  const double err = energy_error(free_block_case("symplectic_euler", "navier", 0.5));
  const double err_half = energy_error(free_block_case("symplectic_euler", "navier", 0.25));
  EXPECT_LT(err, 0.05);
  EXPECT_GT(err / err_half, 1.6) << err << " vs " << err_half;
}

TEST(MpsElasticWaves, PrintedStabilityLimitSeparatesStableFromUnstableSteps) {
  // The spectral limit 2/omega_max (power iteration) must be above the CFL step it
  // accompanies, and really be the limit: 0.95x runs bounded, 1.1x blows up.
  const std::string base = free_block_case("symplectic_euler", "navier", 0.5);
  const Simulation probe(parse_case_text(base));
  EXPECT_GT(probe.spectral_dt_limit_s(), probe.cfl_dt_s());
  auto grows = [&](double factor) {
    std::string yaml = base;
    const auto pos = yaml.find("safety: 0.5");
    yaml.replace(pos, 11, "dt: " + test::num(factor * probe.spectral_dt_limit_s()));
    Simulation sim(parse_case_text(yaml));
    const double e0 = sim.kinetic_energy_j() + sim.elastic_energy_j();
    for (int s = 0; s < 3000; ++s) sim.step();
    return (sim.kinetic_energy_j() + sim.elastic_energy_j()) / e0;
  };
  EXPECT_LT(grows(0.95), 1.5);
  EXPECT_FALSE(grows(1.1) < 1e3);  // NaN (overflow) also counts as blown up
}

// A uniform initial velocity (initial.velocity, both formulations) moves a free body rigidly:
// after t every particle is displaced v0 t, still at v0, and the kinetic energy is
// 1/2 m v0^2 throughout. The displacement formulation ignored the key (u = v = 0).
TEST(MpsElasticWaves, AUniformInitialVelocityTranslatesAFreeBody) {
  Simulation sim(parse_case_text(R"(
specimen:
  lattice: {dimension: 2, box: [0, 0, 10 mm, 5 mm], spacing: 0.5 mm}
model: {type: mps, equation: navier}
materials: [{name: steel, density: 7850, C13: 121.1 GPa, C55: 80.8 GPa}]
initial: {velocity: [1 m/s, -0.5 m/s]}
time: {end: 10 us}
)",
                                 "translate.yaml"));
  double mass = 0.0;
  for (size_t i = 0; i < sim.size(); ++i) mass += 7850.0 * sim.volume_m3()[i];
  const double expected = 0.5 * mass * (1.0 + 0.25);
  EXPECT_NEAR(sim.kinetic_energy_j(), expected, 1e-12 * expected);
  while (sim.time_s() < 10e-6 * (1 - 1e-12)) sim.step();
  const double t = sim.time_s();
  for (size_t i = 0; i < sim.size(); ++i) {
    EXPECT_NEAR(sim.displacement(0)[i], 1.0 * t, 1e-12 * t);
    EXPECT_NEAR(sim.displacement(1)[i], -0.5 * t, 1e-12 * t);
    EXPECT_NEAR(sim.velocity(0)[i], 1.0, 1e-12);
  }
  EXPECT_NEAR(sim.kinetic_energy_j(), expected, 1e-12 * expected);
}
