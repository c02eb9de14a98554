// The gas load (gas.hpp): a charge's gas in a cavity whose pressure follows the cavity's
// volume along a two-gamma isentrope, enters open cracks and vents through them.
//
// Specimen: a thick-walled cylinder in plane strain (a disc of radius b = 40 mm with a hole of
// radius a = 5 mm, 10 mm thick), meshed by gmsh, LPS with dual horizon on the graded mesh.
// Its hole expands under an internal pressure p by the Lame solution
//   u(a) = p a (1 + nu) / E [ (1 - 2 nu) a^2 + b^2 ] / (b^2 - a^2),
// so a closed gas charge settles where p = P(V0 / V(p)), V(p) = V0 (1 + u(a)/a)^2.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "breccia/common/error.hpp"
#include "breccia/solver/gas.hpp"
#include "helpers.hpp"
#include "reverse_block_exec.hpp"

using namespace breccia;
using namespace breccia::solver;
using namespace breccia::solver::testing;

namespace {

constexpr double kE = 1e9, kNu = 0.25, kA = 5e-3, kB = 40e-3, kThickness = 0.01;
constexpr double kP0 = 20e6, kSwitch = 18e6, kGammaHigh = 3.0, kGammaLow = 1.4;

constexpr const char* kTwoGamma = "gamma_high: 3, gamma_low: 1.4, switch_pressure: 18 MPa";

std::string disc_case(const std::string& gas_extra, const std::string& rest,
                      const std::string& history = "{type: constant, value: 20 MPa}",
                      const std::string& law = kTwoGamma) {
  const std::string file = charge_hole_disc();
  EXPECT_FALSE(file.empty()) << "could not mesh the thick cylinder";
  return "specimen: {particles: " + file + "}\n"
         "model: {type: lps, planar: plane_strain, horizon_factor: 3.015, variable_horizon: true}\n"
         "materials: [{name: rock, density: 2000, youngs_modulus: 1 GPa, poisson_ratio: 0.25}]\n"
         "loads:\n  - {type: gas, surface: charge_hole, history: " + history + ", " + law +
         ", ambient_pressure: 0" + gas_extra + "}\n" + rest;
}

// Two runs of one gas case that must agree bit for bit (two code paths, two thread counts):
// the gas's sums, its front, the entries in its volume, the bonds and the motion. `what` says
// which two runs differ in the messages.
void expect_same_gas_and_motion(const PdSystem& a, const PdSystem& b, const std::string& what) {
  ASSERT_GT(a.gas.crack_volume, 0.0) << "the gas must be in cracks";
  EXPECT_EQ(a.step, b.step) << what;
  EXPECT_EQ(a.gas.volume, b.gas.volume) << what;
  EXPECT_EQ(a.gas.crack_volume, b.gas.crack_volume) << what;
  EXPECT_EQ(a.gas.debris_volume, b.gas.debris_volume) << what;
  EXPECT_EQ(a.gas.work, b.gas.work) << what;
  EXPECT_EQ(a.gas.mass_fraction, b.gas.mass_fraction) << what;
  EXPECT_TRUE(a.gas.arrival == b.gas.arrival) << "the fronts differ: " << what;
  EXPECT_TRUE(a.gas.in_crack == b.gas.in_crack) << "the cracks in the gas's volume differ: " << what;
  EXPECT_TRUE(a.state == b.state) << "the bonds differ: " << what;
  EXPECT_TRUE(a.u == b.u) << "the displacements differ: " << what;
}

// The two-gamma isentrope through (V0, p0), written here independently of gas.hpp.
double isentrope(double v0_over_v) {
  const double rho_switch = std::pow(kSwitch / kP0, 1.0 / kGammaHigh);
  return v0_over_v >= rho_switch ? kP0 * std::pow(v0_over_v, kGammaHigh)
                                 : kSwitch * std::pow(v0_over_v / rho_switch, kGammaLow);
}

// Integral of p dV along it from V0 to V.
double isentrope_work(double v0, double v) {
  const double vs = v0 / std::pow(kSwitch / kP0, 1.0 / kGammaHigh);
  const auto branch = [](double p, double va, double vb, double g) { return p * va / (g - 1) * (1 - std::pow(va / vb, g - 1)); };
  return v <= vs ? branch(kP0, v0, v, kGammaHigh) : branch(kP0, v0, vs, kGammaHigh) + branch(kSwitch, vs, v, kGammaLow);
}

double lame_expansion(double p) {
  const double ua = p * kA * (1 + kNu) / kE * ((1 - 2 * kNu) * kA * kA + kB * kB) / (kB * kB - kA * kA);
  return std::pow(1 + ua / kA, 2);
}

}  // namespace

TEST(Gas, IsentropeIsContinuousAndTakesEachGammaOnItsSide) {
  const GasLaw law{3.0, 1.4, 18e6};
  // At the switch density both branches give the switch pressure.
  const double rho_s = std::pow(18.0 / 20.0, 1.0 / 3.0);
  EXPECT_NEAR(gas_isentrope_pressure(20e6, rho_s * (1 + 1e-12), law), 18e6, 1e-3);
  EXPECT_NEAR(gas_isentrope_pressure(20e6, rho_s * (1 - 1e-12), law), 18e6, 1e-3);
  // Doubling the volume at high pressure divides p by 2^3 (the figure), at low by 2^1.4.
  EXPECT_DOUBLE_EQ(gas_isentrope_pressure(1e9, 0.99, {3.0, 1.3, 1e6}), 1e9 * std::pow(0.99, 3.0));
  EXPECT_NEAR(gas_isentrope_pressure(1e9, 0.5, {3.0, 1.3, 1e6}) / 1e9, 1.0 / 8.0, 1e-15);
  EXPECT_NEAR(gas_isentrope_pressure(1e5, 0.5, law) / 1e5, std::pow(0.5, 1.4), 1e-15);
  // Choked flow factor of a diatomic gas, (2/2.4)^3 = 0.5787 (gas-dynamics tables).
  EXPECT_NEAR(choked_flow_factor(1.4), 0.5787, 1e-4);
}

TEST(Gas, ReferenceVolumeIsTheFacetedHole) {
  PdSystem s = system_from_yaml("gas_v0", disc_case(", crack_entry: false", "time: {steps: 1}\n"));
  ASSERT_TRUE(s.gas.active);
  // The divergence theorem over the 53-gon is exact: its area is n/2 r^2 sin(2 pi / n) for a
  // polygon with vertices on the circle; gmsh's vertices are, to round-off.
  const SurfaceFacets* hole = s.particles.find_surface("charge_hole");
  const double n = static_cast<double>(hole->size());
  const double polygon = 0.5 * n * kA * kA * std::sin(2 * std::numbers::pi / n) * kThickness;
  EXPECT_NEAR(s.gas.reference_volume / polygon, 1.0, 1e-9);
  EXPECT_DOUBLE_EQ(s.gas.pressure, kP0);  // nothing has moved yet: the closed-cavity pressure
}

TEST(Gas, ClosedChargeSettlesWhereTheIsentropeMeetsTheLameExpansion) {
  PdSystem s = system_from_yaml(
      "gas_adr", disc_case(", crack_entry: false", "time: {integrator: adr, adr_tolerance: 1e-6, adr_max_steps: 60000}\n"));
  ASSERT_GT(relax_to_equilibrium(s, false), 0) << "ADR did not converge";
  compute_external(s, 0.0);
  // The analytic equilibrium: bisection of p - P(1 / expansion(p)) on (0, p0].
  double lo = 0.0, hi = kP0;
  for (int it = 0; it < 200; ++it) {
    const double mid = 0.5 * (lo + hi);
    (mid - isentrope(1.0 / lame_expansion(mid)) > 0 ? hi : lo) = mid;
  }
  const double p_exact = 0.5 * (lo + hi);  // 17.75 MPa: the gas lost 11% of its pressure
  // 1 %: the bound; the discrete hole is 3% more compliant than Lame's (surface effect of
  // the horizon at the hole wall), which moves p by 0.4%.
  EXPECT_NEAR(s.gas.pressure / p_exact, 1.0, 0.01) << "p " << s.gas.pressure << " Pa, Lame " << p_exact;
  EXPECT_LT(s.gas.pressure, 0.95 * kP0) << "the expansion must matter in this test";
  EXPECT_LT(s.gas.pressure, kSwitch) << "both branches of the isentrope are crossed";
  // The pressure applied is the law's at the cavity's measured volume (round-off) ...
  EXPECT_NEAR(s.gas.pressure / isentrope(s.gas.reference_volume / s.gas.volume), 1.0, 1e-9);
  // ... and the gas work is its integral of p dV (1%: the bound; the trapezoid over the
  // ADR path is within 1e-5).
  EXPECT_NEAR(s.gas.work / isentrope_work(s.gas.reference_volume, s.gas.volume), 1.0, 0.01);
}

TEST(Gas, DynamicExpansionClosesTheEnergyBalanceWithTheGasWork) {
  // The charge burns up over 20 us (a sudden load costs the Verlet start-up ~1% of the work
  // even with a plain pressure load on this mesh).
  PdSystem s = system_from_yaml("gas_dyn", disc_case(", crack_entry: false", "time: {steps: 400}\n",
                                                     "{type: ramp, value: 20 MPa, ramp_time: 20 us}"));
  for (int k = 0; k < 400; ++k) cpu_step(s);
  const Energies e = measure(s);
  ASSERT_GT(s.gas.work, 0.0);
  // The gas is the only load: the work of its facet forces (the step's trapezoid) is its
  // p dV (1%, the bound) and goes into kinetic and strain energy (1%).
  EXPECT_NEAR(s.external_work / s.gas.work, 1.0, 0.01);
  EXPECT_NEAR((e.kinetic + e.strain) / s.gas.work, 1.0, 0.01);
  EXPECT_LT(s.gas.pressure, 0.98 * kP0) << "the expansion must matter in this test";
}

namespace {

// A disc whose pre-crack joins the hole to the outer face (or not), stepped for 300 us.
PdSystem vent_run(bool precracked) {
  const std::string crack = precracked ? "precracks: [{type: segment, from: [4 mm, 0.01 mm], to: [41 mm, 0.01 mm]}]\n" : "";
  PdSystem s = system_from_yaml(precracked ? "gas_vent" : "gas_novent",
      disc_case(", vent_surfaces: [outer], front_speed: 500 m/s, gas_density: 1000 kg/m3, vent_area: 100 mm2", crack +
                "time: {steps: 1}\n"));
  while (s.time < 300e-6) cpu_step(s);
  return s;
}

}  // namespace

TEST(Gas, APreCrackToTheOuterFaceVentsTheGasAndNoPreCrackKeepsItIn) {
  const PdSystem sealed = vent_run(false);
  EXPECT_FALSE(sealed.gas.vented);
  EXPECT_DOUBLE_EQ(sealed.gas.mass_fraction, 1.0);
  EXPECT_EQ(sealed.gas.crack_volume, 0.0);
  const PdSystem cracked = vent_run(true);
  ASSERT_TRUE(cracked.gas.vented);
  // The front runs 35 mm of crack at 500 m/s: it cannot be there before 70 us.
  EXPECT_GT(cracked.gas.vent_time, 35e-3 / 500.0);
  EXPECT_LT(cracked.gas.vent_time, 300e-6);
  EXPECT_GT(cracked.gas.crack_volume, 0.0) << "the gas fills the pre-crack";
  EXPECT_LT(cracked.gas.mass_fraction, 0.9) << "gas has left through the vent";
  EXPECT_LT(cracked.gas.pressure, 0.5 * sealed.gas.pressure);
}

// Found in review (2026-12-08). An initial displacement of the wall entered the first step's
// volume change as gas work no force did (gas_work_J 2 % above external_work_J): refused. Under
// dynamic relaxation the outflow needs time, so open stemming and vent surfaces did nothing
// (the gas kept its mass): refused. A gas that cannot vent reports no outflow area (history.csv
// showed the mouth's).
TEST(Gas, InputTheGasCannotHonourIsRefusedAndAClosedGasHasNoVentArea) {
  const auto fails_with = [](const std::string& yaml, const std::string& needle) {
    try {
      system_from_yaml("gas_refused", yaml);
      ADD_FAILURE() << "accepted: " << needle;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  fails_with(disc_case(", crack_entry: false", "initial: [{type: displacement, value: [1e-5, 0]}]\ntime: {steps: 1}\n"),
             "initial[0].type");
  const std::string adr = "time: {integrator: adr, adr_tolerance: 1e-6, adr_max_steps: 100}\n";
  fails_with(disc_case(", stemming: open, gas_density: 1000, vent_area: 1 mm2", adr), "loads[0].stemming");
  fails_with(disc_case(", vent_surfaces: [outer], gas_density: 1000, vent_area: 1 mm2", adr), "loads[0].vent_surfaces");
  // Keys nothing would read: an outflow area for a gas that cannot vent, a front speed for one
  // that enters no crack.
  fails_with(disc_case(", crack_entry: false, vent_area: 1 mm2", "time: {steps: 1}\n"), "loads[0].vent_area");
  fails_with(disc_case(", crack_entry: false, front_speed: 500 m/s", "time: {steps: 1}\n"), "loads[0].front_speed");
  const PdSystem velocity = system_from_yaml("gas_initial_velocity",
                                             disc_case(", crack_entry: false", "initial: [{type: velocity, value: [1, 0]}]\ntime: {steps: 1}\n"));
  EXPECT_TRUE(velocity.gas.active);
  EXPECT_EQ(velocity.gas.outflow_area(), 0.0) << "a closed gas without vent surfaces cannot vent";
}

TEST(Gas, BadInputNamesTheField) {
  const auto fails_with = [](const std::string& extra, const std::string& needle) {
    try {
      system_from_yaml("gas_bad", disc_case(extra, "time: {steps: 1}\n"));
      ADD_FAILURE() << "accepted: " << extra;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  fails_with(", gamma_low: 1", "loads[0].gamma_low");
  fails_with(", stemming: open", "loads[0].gas_density");                     // venting needs the gas density
  fails_with(", stemming: open, gas_density: 1000", "loads[0].vent_area");    // a closed hole has no mouth
  fails_with(", vent_surfaces: [nowhere], gas_density: 1000, vent_area: 1 mm2", "loads[0].vent_surfaces[0]");
  fails_with(", stemming: ajar", "loads[0].stemming");
  fails_with(", crack_pass_every: 0", "loads[0].crack_pass_every");
  fails_with(", crack_pass_every: 2.5", "loads[0].crack_pass_every");
  fails_with(", crack_entry: false, crack_pass_every: 4", "loads[0].crack_pass_every");
  fails_with(", crack_pass_tolerance: 2", "loads[0].crack_pass_tolerance");
  // Found in review (2026-12-08): a vent surface named twice doubled the outflow; the gas's
  // own wall can never vent (its particles are reached at the start, never by the front).
  fails_with(", vent_surfaces: [outer, outer], gas_density: 1000, vent_area: 1 mm2", "loads[0].vent_surfaces[1]");
  fails_with(", vent_surfaces: [charge_hole], gas_density: 1000, vent_area: 1 mm2", "the gas's own surface");
  // A charge's gauge pressure below zero was no load at all, run without a word.
  for (const auto& [history, key] : std::vector<std::pair<std::string, std::string>>{
           {"{type: constant, value: -20 MPa}", "loads[0].history.value"},
           {"{type: double_exponential, peak: -1 GPa, rise_time: 140 us, ratio: 1.5}", "loads[0].history.peak"}})
    try {
      system_from_yaml("gas_bad_history", disc_case("", "time: {steps: 1}\n", history));
      ADD_FAILURE() << "accepted: " << history;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("gauge pressure"), std::string::npos) << e.what();
    }
}

namespace {

// A venting run stopped half way and restarted from its checkpoint ends where the run that
// went straight through ends (gas_extra: more keys of the gas load).
void expect_gas_restart_bit_for_bit(const std::string& gas_extra) {
  const std::string deck = disc_case(", vent_surfaces: [outer], front_speed: 500 m/s, gas_density: 1000 kg/m3, "
                                     "vent_area: 100 mm2" + gas_extra,
                                     "precracks: [{type: segment, from: [4 mm, 0.01 mm], to: [41 mm, 0.01 mm]}]\n"
                                     "time: {steps: 1}\n");
  PdSystem straight = system_from_yaml("gas_restart_a", deck);
  for (int k = 0; k < 300; ++k) cpu_step(straight);
  PdSystem first = system_from_yaml("gas_restart_b", deck);
  for (int k = 0; k < 150; ++k) cpu_step(first);
  ASSERT_TRUE(first.gas.crack_volume > 0.0) << "the front is in the crack at the checkpoint";
  const std::string cp = process_temp_dir() + "/gas_checkpoint.h5";
  write_checkpoint(first, cp);
  PdSystem resumed = system_from_yaml("gas_restart_c", deck);
  read_checkpoint(resumed, cp);
  for (int k = 0; k < 150; ++k) cpu_step(resumed);
  EXPECT_EQ(resumed.u, straight.u);
  EXPECT_EQ(resumed.v, straight.v);
  EXPECT_EQ(resumed.gas.pressure, straight.gas.pressure);
  EXPECT_EQ(resumed.gas.work, straight.gas.work);
  EXPECT_EQ(resumed.gas.mass_fraction, straight.gas.mass_fraction);
  EXPECT_EQ(resumed.gas.arrival, straight.gas.arrival);
  EXPECT_EQ(resumed.gas.vented, straight.gas.vented);
}

}  // namespace

TEST(Gas, ARestartContinuesTheGasBitForBit) {
  // The gas's scalars, front and frozen wall shares travel with the checkpoint.
  expect_gas_restart_bit_for_bit("");
}

TEST(Gas, ARestartBetweenCrackPassesContinuesTheGasBitForBit) {
  // With sparse crack passes the checkpoint also keeps the push vectors the volume follows
  // between passes, the count to the next pass and its interval.
  expect_gas_restart_bit_for_bit(", crack_pass_every: 8, crack_pass_tolerance: 0.01");
}

namespace {

// A JWL set of a liquid explosive's size (nitromethane's A, B, R1, R2 as docs/theory.md
// quotes them; omega and C as there); the test checks the implementation, not the set.
constexpr double kJwlA = 209.2e9, kJwlB = 5.689e9, kJwlC = 0.8e9, kJwlR1 = 4.4, kJwlR2 = 1.2, kJwlOmega = 0.3;
constexpr const char* kJwl = "eos: jwl, jwl: {A: 209.2 GPa, B: 5.689 GPa, C: 0.8 GPa, R1: 4.4, R2: 1.2, omega: 0.3, "
                             "explosive_density: 1128 kg/m3}, gas_density: 1128 kg/m3";

// The JWL principal isentrope and its integral, written here independently of gas_law.hpp.
double jwl(double v) {
  return kJwlA * std::exp(-kJwlR1 * v) + kJwlB * std::exp(-kJwlR2 * v) + kJwlC * std::pow(v, -(1 + kJwlOmega));
}
double jwl_integral(double v) {  // an antiderivative of jwl(v) dv
  return -kJwlA / kJwlR1 * std::exp(-kJwlR1 * v) - kJwlB / kJwlR2 * std::exp(-kJwlR2 * v) -
         kJwlC / kJwlOmega * std::pow(v, -kJwlOmega);
}

}  // namespace

TEST(Gas, ARestartBetweenTolerantCrackPassesContinuesTheGasBitForBit) {
  expect_gas_restart_bit_for_bit(", crack_pass_every: 8, crack_pass_new_crack: tolerance");
}

TEST(Gas, BadCrackPassNewCrackNamesTheField) {
  try {
    system_from_yaml("gas_bad", disc_case(", crack_pass_new_crack: later", "time: {steps: 1}\n"));
    ADD_FAILURE() << "accepted crack_pass_new_crack: later";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("loads[0].crack_pass_new_crack"), std::string::npos) << e.what();
  }
}

TEST(Gas, JwlIsentropeIsTheScaledPrincipalIsentrope) {
  GasLaw law;
  law.kind = GasLaw::Kind::Jwl;
  law.jwl_a = kJwlA, law.jwl_b = kJwlB, law.jwl_c = kJwlC, law.jwl_r1 = kJwlR1, law.jwl_r2 = kJwlR2;
  law.jwl_omega = kJwlOmega;
  law.jwl_v_ref = 1.25;  // a hole 80% full of explosive
  for (double rho : {1.3, 1.0, 0.7, 0.3, 0.05, 0.01}) {
    // Through (1, p_ref), along jwl(v) with v = v_ref / rho (round-off).
    EXPECT_NEAR(gas_isentrope_pressure(20e6, rho, law) / (20e6 * jwl(1.25 / rho) / jwl(1.25)), 1.0, 1e-12) << rho;
    // The local exponent is -dln p/dln V: a central difference (1e-5 relative: its error).
    const double h = 1e-4;
    const double slope = -(std::log(gas_isentrope_pressure(1e9, rho / (1 + h), law)) -
                           std::log(gas_isentrope_pressure(1e9, rho / (1 - h), law))) /
                         (std::log(1 + h) - std::log(1 - h));
    EXPECT_NEAR(gas_local_gamma(1e9, rho, law) / slope, 1.0, 1e-5) << rho;
  }
  // Far out the C term is all that is left: an ideal gas with gamma = 1 + omega.
  EXPECT_NEAR(gas_local_gamma(1e5, 1e-4, law), 1 + kJwlOmega, 1e-9);
}

namespace {
// The escape speed by its definition, the Riemann invariant integral of c d(ln rho) from
// zero density up to rho along the isentrope through (1, p_ref) (Courant & Friedrichs 1948),
// by the trapezoid over 60 e-folds of density below rho (2e5 intervals), closed below by the
// last law's ideal-gas tail 2 c / (gamma - 1). Written here without gas_escape_speed.
double escape_by_quadrature(double p_ref, double rho, double rho_kg, const GasLaw& law) {
  const auto c = [&](double r) {
    const double pr = gas_isentrope_pressure(p_ref, r, law);
    return std::sqrt(gas_local_gamma(pr, r, law) * pr / (rho_kg * r / rho));
  };
  const int n = 200000;
  const double h = 60.0 / n, bottom = rho * std::exp(-60.0);
  double sum = 0.5 * (c(bottom) + c(rho));
  for (int i = 1; i < n; ++i) sum += c(bottom * std::exp(i * h));
  const double pb = gas_isentrope_pressure(p_ref, bottom, law);
  return sum * h + 2.0 * c(bottom) / (gas_local_gamma(pb, bottom, law) - 1.0);
}
}  // namespace

TEST(Gas, TheFrontsEscapeSpeedIsTheRiemannIntegralDownTheWholeIsentrope) {
  // The concrete case's law (gamma 3 above 0.1 GPa, 1.3 below) at its wall's peak state,
  // 235 MPa at 0.944 of the nitromethane density 1128 kg/m3: 2 c / (gamma - 1) with the
  // local gamma gives c = 814 m/s; the whole isentrope, 202 m/s above the switch and
  // 2 c_switch / 0.3 = 2,687 m/s below it. Against the quadrature: 1e-5 (its error).
  const GasLaw law{3.0, 1.3, 0.1e9};
  const double rho_kg = 1128.0 * 0.944, p_ref = 235e6 / std::pow(0.944, 3.0);
  const double p = gas_isentrope_pressure(p_ref, 0.944, law);
  const double u = gas_escape_speed(p, rho_kg, 0.944, law);
  EXPECT_NEAR(u / escape_by_quadrature(p_ref, 0.944, rho_kg, law), 1.0, 1e-5);
  EXPECT_NEAR(u, 2889.0, 2.0);  // the figures above, rounded to 1 m/s each
  EXPECT_GT(u / std::sqrt(3.0 * p / rho_kg), 3.4);  // 3.5 times the local-gamma figure
  // Below the switch it is 2 c / (gamma_low - 1) exactly, and it is continuous at the switch.
  const double c_low = std::sqrt(1.3 * 50e6 / 500.0);
  EXPECT_DOUBLE_EQ(gas_escape_speed(50e6, 500.0, 0.5, law), 2 * c_low / 0.3);
  EXPECT_NEAR(gas_escape_speed(0.1e9 * (1 + 1e-12), 700.0, 0.6, law) / gas_escape_speed(0.1e9 * (1 - 1e-12), 700.0, 0.6, law),
              1.0, 1e-9);
  // JWL: with the C term alone an ideal gas of gamma 1 + omega, 2 c / omega (round-off);
  // the full set against the quadrature (1e-5; Simpson's own error is below 1e-8).
  GasLaw jwl;
  jwl.kind = GasLaw::Kind::Jwl;
  jwl.jwl_c = kJwlC, jwl.jwl_omega = kJwlOmega, jwl.jwl_v_ref = 1.25;
  const double pc = gas_isentrope_pressure(1e9, 0.8, jwl);
  EXPECT_NEAR(gas_escape_speed(pc, 900.0, 0.8, jwl) / (2 * std::sqrt((1 + kJwlOmega) * pc / 900.0) / kJwlOmega), 1.0, 1e-12);
  jwl.jwl_a = kJwlA, jwl.jwl_b = kJwlB, jwl.jwl_r1 = kJwlR1, jwl.jwl_r2 = kJwlR2;
  for (double rho : {1.2, 0.8, 0.3, 0.02}) {
    const double pj = gas_isentrope_pressure(1e9, rho, jwl);
    EXPECT_NEAR(gas_escape_speed(pj, 1128.0 * rho, rho, jwl) / escape_by_quadrature(1e9, rho, 1128.0 * rho, jwl), 1.0, 1e-5)
        << rho;
  }
}

TEST(Gas, AJwlChargeFollowsTheJwlIsentropeAndItsWorkIsTheIntegral) {
  // A closed JWL charge (the hole full of explosive: v = V / V0) suddenly at 20 MPa expands
  // the disc for 200 steps (a dynamic run: the ADR settle of the two-gamma test takes
  // minutes). The pressure is the scaled principal isentrope at the cavity's volume, and
  // the gas work is its analytic integral p0 / p_s(1) V0 [P(v) - P(1)] whatever path the
  // oscillating volume took.
  PdSystem s = system_from_yaml("gas_jwl", disc_case(", crack_entry: false", "time: {steps: 200}\n",
                                                      "{type: constant, value: 20 MPa}", kJwl));
  ASSERT_EQ(s.gas.law.kind, GasLaw::Kind::Jwl);
  for (int k = 0; k < 200; ++k) cpu_step(s);
  const double v = s.gas.volume / s.gas.reference_volume;
  ASSERT_GT(v, 1.002) << "the expansion must matter in this test";
  EXPECT_NEAR(s.gas.pressure / (kP0 * jwl(v) / jwl(1.0)), 1.0, 1e-9);  // round-off
  // 1%: the bound for the work; the trapezoid over 200 steps is far closer.
  const double work = kP0 / jwl(1.0) * s.gas.reference_volume * (jwl_integral(v) - jwl_integral(1.0));
  EXPECT_NEAR(s.gas.work / work, 1.0, 0.01);
  EXPECT_NEAR(s.external_work / s.gas.work, 1.0, 0.01);
}

TEST(Gas, VentAreaFromTheCrackOpeningIsOpeningTimesTraceLength) {
  // The pre-cracked disc opened rigidly by delta across the crack's plane, with the gas
  // everywhere: the crack reaches the outer face along the disc's thickness, so its mouth
  // there is delta x 10 mm, and the crack (5 to 40 mm long) holds delta x 35 mm x 10 mm.
  PdSystem s = system_from_yaml(
      "gas_vent_area",
      disc_case(", vent_surfaces: [outer], front_speed: 500 m/s, gas_density: 1000 kg/m3, vent_area: crack_opening",
                "precracks: [{type: segment, from: [4 mm, 0.01 mm], to: [41 mm, 0.01 mm]}]\ntime: {steps: 1}\n"));
  ASSERT_TRUE(s.gas.vent_crack_opening);
  const double delta = 1e-5;
  for (size_t i = 0; i < s.n; ++i) {
    if (s.gas.arrival[i] > 0.0) s.gas.arrival[i] = 1e-9;  // reached through the crack
    s.u[3 * i + 1] = s.x0[3 * i + 1] > 1e-5 ? 0.5 * delta : -0.5 * delta;
  }
  s.gas.arrival_next = s.gas.arrival;
  compute_external(s, 0.0);
  ASSERT_TRUE(s.gas.vented);
  // Tolerances: 10% on the mouth (one layer of surface particles, whose truncated families
  // the kappa factor corrects only on average), 5% on the volume (the hole's chords and the
  // crack's ends at the hole and the rim).
  EXPECT_NEAR(s.gas.crack_vent_area / (delta * kThickness), 1.0, 0.10);
  EXPECT_NEAR(s.gas.crack_volume / (delta * (kB - kA) * kThickness), 1.0, 0.05);
  EXPECT_DOUBLE_EQ(s.gas.outflow_area(), s.gas.crack_vent_area) << "a closed hole: the cracks are the only vent";
  // Opened twice as far, the mouth doubles: the law is linear in the openings, and a pair's
  // opening is linear in delta up to a term of order delta / |xi| (2% at most here, for the
  // shortest pairs across the crack).
  const double first = s.gas.crack_vent_area;
  for (size_t i = 0; i < s.n; ++i) s.u[3 * i + 1] *= 2.0;
  compute_external(s, 0.0);
  EXPECT_NEAR(s.gas.crack_vent_area / first, 2.0, 0.02);
}

namespace {

// The disc given a fracture energy (gas_extra: more keys of the gas load).
std::string cracking_disc(const std::string& gas_extra) {
  std::string deck = disc_case(", gas_density: 1000 kg/m3" + gas_extra, "time: {steps: 1}\n");
  const std::string plain = "poisson_ratio: 0.25}";
  deck.replace(deck.find(plain), plain.size(), "poisson_ratio: 0.25, fracture_energy: 2 J/m2}");
  return deck;
}

// Sparse crack passes (crack_pass_every, gas.hpp GasCrackDrift): at most 8 steps apart,
// the interval doubling while a pass finds under a quarter of 1% of the volume missed.
constexpr const char* kSparsePasses = ", crack_pass_every: 8, crack_pass_tolerance: 0.01";

}  // namespace

TEST(Gas, ACrackingChargeDoesTheWorkOfItsForces) {
  // The disc given a fracture energy: the closed charge breaks bonds at the hole and the gas
  // follows the cracks. Crack that joins the gas's volume (reached by the front, or broken
  // between wetted particles) is a free expansion; the work counts only the motion's dV, so
  // it equals the work of the facet and crack forces (the step's trapezoid).
  PdSystem s = system_from_yaml("gas_cracking", cracking_disc(""));
  while (s.time < 40e-6) cpu_step(s);
  ASSERT_GT(s.gas.crack_volume, 0.05 * (s.gas.volume - s.gas.reference_volume)) << "the gas must be in cracks";
  // 1%: the bound (the first step of each joining entry is counted by the trapezoid
  // only, half a step's opening).
  EXPECT_NEAR(s.external_work / s.gas.work, 1.0, 0.01);
}

namespace {

void expect_same_on_one_and_two_threads(const std::string& gas_extra) {
  const std::string deck = cracking_disc(gas_extra);
  const int threads_before = omp_get_max_threads();
  const auto run = [&](int threads) {
    omp_set_num_threads(threads);
    PdSystem s = system_from_yaml("gas_threads", deck);
    while (s.time < 20e-6) cpu_step(s);
    return s;
  };
  const PdSystem one = run(1), two = run(2);
  omp_set_num_threads(threads_before);
  expect_same_gas_and_motion(one, two, "1 and 2 threads");
}

}  // namespace

TEST(Gas, TheCrackingChargeMovesTheSameOnOneAndTwoThreads) {
  // The gas's sums over particles are taken in fixed blocks added in a fixed order
  // (gas_fixed_order_sum), so its volume, and the motion its pressure drives, are the same bit
  // for bit on any thread count (the force passes are per particle). A per-thread sum would
  // differ at round-off, and the motion with it.
  expect_same_on_one_and_two_threads("");
}

TEST(Gas, SparseCrackPassesMoveTheSameOnOneAndTwoThreads) {
  // The check between passes (GasCrackChange) is a fixed-order sum, so it too is thread-count free.
  expect_same_on_one_and_two_threads(kSparsePasses);
}

namespace {

// The cracking disc to 40 us with every-step passes (exact) and with passes up to 8 steps
// apart at the default tolerance (sparse); `widest`: the longest interval the sparse run took.
void run_exact_and_sparse_passes(PdSystem& exact, PdSystem& sparse, int& widest) {
  widest = 1;
  while (exact.time < 40e-6) cpu_step(exact);
  while (sparse.time < 40e-6) {
    cpu_step(sparse);
    widest = std::max(widest, sparse.gas.crack_pass_interval);
  }
  std::printf("sparse / every-step passes at 40 us: work %.6f, volume %.6f, crack volume %.6f; sparse external / gas "
              "work %.6f\n",
              sparse.gas.work / exact.gas.work, sparse.gas.volume / exact.gas.volume,
              sparse.gas.crack_volume / exact.gas.crack_volume, sparse.external_work / sparse.gas.work);
}

}  // namespace

TEST(Gas, SparseCrackPassesKeepTheWorkOfTheForces) {
  // Between passes the volume follows the particles along the last pass's push vectors, the
  // same vectors the crack forces act along, so the gas work stays the work of its forces;
  // at a pass the work counts the old push at the step's start and the new one at its end,
  // as the trapezoid does; the volume the drift missed (new crack, second-order drift) is a
  // free expansion. The interval must actually grow here. (Since the check between passes,
  // GasCrackChange, bonds next to the gas break at every step of this disc, so every step is
  // a pass: the drift itself is not exercised here; measured 54 passes in 54 steps.)
  PdSystem exact = system_from_yaml("gas_exact_passes", cracking_disc(""));
  // The default tolerance (1e-3 of the cavity's volume missed at a pass).
  PdSystem sparse = system_from_yaml("gas_sparse_passes", cracking_disc(", crack_pass_every: 8"));
  int widest = 1;
  run_exact_and_sparse_passes(exact, sparse, widest);
  ASSERT_GT(sparse.gas.crack_volume, 0.05 * (sparse.gas.volume - sparse.gas.reference_volume));
  EXPECT_GE(widest, 2) << "the passes never spread out";
  // 1%: the bound, as for the every-step passes (ACrackingChargeDoesTheWorkOfItsForces).
  // Measured 1.0128 before the pass's work counted the new push at the step's end.
  EXPECT_NEAR(sparse.external_work / sparse.gas.work, 1.0, 0.01);
}

// Since a particle that has lost every bond is debris (AParticleThatHasLostEveryBondIsDebris...)
// the sparse passes gave 0.969 of the every-step passes' gas work and 0.972 of their volume here
// at 40 us: with nothing in the crack yet a pass missed nothing, the interval doubled, and the
// pass that found the first crack open (2.26 us) came a step late; on this disc breaking into
// grains that step grew to 3-4 % (traced step by step, every 2 at tolerance 1e-12: 0.958 /
// 0.960, particles 3.5 mm apart at 37.6 us). Now a step between passes checks whether the exact
// pass would change which entries are in the volume (GasCrackChange: the front can advance, a
// bond next to the gas broke, a wetted particle became debris) and forces it then: 0.9995 /
// 1.000000 (the work differs only by the pass's trapezoid along the old and new push vectors).
// On this disc bonds next to the gas break at every one of its 54 steps, so every step is a
// pass (the interval still grows to 8, but no drift step is taken): this checks that the
// sparse route finds each change when the every-step route does, not the drift in between.
TEST(Gas, SparseCrackPassesGiveTheEveryStepPassesAnswer) {
  PdSystem exact = system_from_yaml("gas_exact_passes", cracking_disc(""));
  PdSystem sparse = system_from_yaml("gas_sparse_passes", cracking_disc(", crack_pass_every: 8"));
  int widest = 1;
  run_exact_and_sparse_passes(exact, sparse, widest);
  // 1% on the work and the volume: a pass puts back at most about 1e-3 of the volume, so each
  // pass's pressure jump is under 0.3% (gamma 3).
  EXPECT_NEAR(sparse.gas.work / exact.gas.work, 1.0, 0.01);
  EXPECT_NEAR(sparse.gas.volume / exact.gas.volume, 1.0, 0.01);
}

// The regime the sparse passes are for: a crack that the gas fills and that then only moves.
// The pre-cracked disc of APreCrackToTheOuterFace... (no fracture: no bond breaks), the front
// running the pre-crack at 500 m/s to the outer face and venting there, to 300 us: the steps
// where the front advances are passes (GasCrackChange), the others follow the drift. The
// drift must be taken (else nothing is tested), and the answer is the every-step passes'
// within 1% (the bound of the disc above: each pass puts back at most about 1e-3 of the
// volume, a pressure jump under 0.3%).
TEST(Gas, SparseCrackPassesFollowAFilledCrackAsEveryStepPassesDo) {
  const auto deck = [](const std::string& extra) {
    return disc_case(", vent_surfaces: [outer], front_speed: 500 m/s, gas_density: 1000 kg/m3, vent_area: 100 mm2" +
                         extra,
                     "precracks: [{type: segment, from: [4 mm, 0.01 mm], to: [41 mm, 0.01 mm]}]\ntime: {steps: 1}\n");
  };
  PdSystem exact = system_from_yaml("gas_filled_exact", deck(""));
  PdSystem sparse = system_from_yaml("gas_filled_sparse", deck(", crack_pass_every: 8"));
  int drift_steps = 0, steps = 0, widest = 1;
  while (exact.time < 300e-6) cpu_step(exact);
  while (sparse.time < 300e-6) {
    cpu_step(sparse);
    ++steps;
    // a pass sets the countdown to the interval less one; a step between passes lowers it
    drift_steps += sparse.gas.crack_pass_countdown < sparse.gas.crack_pass_interval - 1;
    widest = std::max(widest, sparse.gas.crack_pass_interval);
  }
  std::printf("filled crack, sparse / every-step passes at 300 us: work %.6f, volume %.6f, crack volume %.6f, mass "
              "%.6f; %d of %d steps between passes, widest interval %d\n",
              sparse.gas.work / exact.gas.work, sparse.gas.volume / exact.gas.volume,
              sparse.gas.crack_volume / exact.gas.crack_volume, sparse.gas.mass_fraction / exact.gas.mass_fraction,
              drift_steps, steps, widest);
  ASSERT_TRUE(exact.gas.vented && sparse.gas.vented) << "the front must reach the vent";
  ASSERT_GT(drift_steps, steps / 4) << "the passes must spread out";
  EXPECT_NEAR(sparse.gas.work / exact.gas.work, 1.0, 0.01);
  EXPECT_NEAR(sparse.gas.volume / exact.gas.volume, 1.0, 0.01);
  EXPECT_NEAR(sparse.gas.mass_fraction / exact.gas.mass_fraction, 1.0, 0.01);
  EXPECT_EQ(sparse.gas.vent_time, exact.gas.vent_time) << "the front reaches the vent at the every-step passes' step";
}

// crack_pass_new_crack: tolerance (no check between passes once the gas is in cracks; the new
// crack a pass finds counts against the tolerance with the drift's error): on the cracking
// disc, where bonds next to the gas break at every step, the new crack each pass finds keeps
// the interval short, and the answer is the every-step passes' within the 1% of the disc
// above (each pass's pressure jump under about gamma x 1e-3).
TEST(Gas, SparsePassesWithNewCrackWithinTheToleranceGiveTheEveryStepPassesAnswer) {
  PdSystem exact = system_from_yaml("gas_exact_passes", cracking_disc(""));
  PdSystem sparse =
      system_from_yaml("gas_tolerant_passes", cracking_disc(", crack_pass_every: 8, crack_pass_new_crack: tolerance"));
  int widest = 1;
  run_exact_and_sparse_passes(exact, sparse, widest);
  ASSERT_GT(sparse.gas.crack_volume, 0.05 * (sparse.gas.volume - sparse.gas.reference_volume));
  EXPECT_NEAR(sparse.gas.work / exact.gas.work, 1.0, 0.01);
  EXPECT_NEAR(sparse.gas.volume / exact.gas.volume, 1.0, 0.01);
  // 1%: the bound on the work of the forces (SparseCrackPassesKeepTheWorkOfTheForces).
  EXPECT_NEAR(sparse.external_work / sparse.gas.work, 1.0, 0.01);
}

// The same on the filled, venting pre-crack (no bond breaks): the passes spread out while
// the front runs (one hop per pass; the lag counts as new crack at the next pass) and the
// answer stays within the 1% of the at_once passes above.
TEST(Gas, SparsePassesWithNewCrackWithinTheToleranceFollowAFilledCrack) {
  const auto deck = [](const std::string& extra) {
    return disc_case(", vent_surfaces: [outer], front_speed: 500 m/s, gas_density: 1000 kg/m3, vent_area: 100 mm2" +
                         extra,
                     "precracks: [{type: segment, from: [4 mm, 0.01 mm], to: [41 mm, 0.01 mm]}]\ntime: {steps: 1}\n");
  };
  PdSystem exact = system_from_yaml("gas_filled_exact", deck(""));
  PdSystem sparse = system_from_yaml("gas_filled_tolerant", deck(", crack_pass_every: 8, crack_pass_new_crack: tolerance"));
  int drift_steps = 0, steps = 0;
  while (exact.time < 300e-6) cpu_step(exact);
  while (sparse.time < 300e-6) {
    cpu_step(sparse);
    ++steps;
    drift_steps += sparse.gas.crack_pass_countdown < sparse.gas.crack_pass_interval - 1;
  }
  std::printf("filled crack, tolerant / every-step passes at 300 us: work %.6f, volume %.6f, mass %.6f; vent %.3g / "
              "%.3g us; %d of %d steps between passes\n",
              sparse.gas.work / exact.gas.work, sparse.gas.volume / exact.gas.volume,
              sparse.gas.mass_fraction / exact.gas.mass_fraction, 1e6 * sparse.gas.vent_time, 1e6 * exact.gas.vent_time,
              drift_steps, steps);
  ASSERT_TRUE(exact.gas.vented && sparse.gas.vented) << "the front must reach the vent";
  ASSERT_GT(drift_steps, steps / 4) << "the passes must spread out";
  EXPECT_NEAR(sparse.gas.work / exact.gas.work, 1.0, 0.01);
  EXPECT_NEAR(sparse.gas.volume / exact.gas.volume, 1.0, 0.01);
  EXPECT_NEAR(sparse.gas.mass_fraction / exact.gas.mass_fraction, 1.0, 0.01);
}

namespace {

void expect_device_path_as_host(const std::string& gas_extra) {
  const std::string deck = cracking_disc(gas_extra);
  PdSystem host = system_from_yaml("gas_host_path", deck);
  PdSystem device = system_from_yaml("gas_device_path", deck);
  while (host.time < 20e-6) cpu_step(host);
  while (device.step < host.step) {
    ReverseBlockExec exec(device);
    StepArrays<double> a = cpu_step_arrays(device);
    pd_step(exec, a, device);
  }
  expect_same_gas_and_motion(host, device, "the host and the device path");
}

}  // namespace

TEST(Gas, TheDevicePathMovesTheCrackingChargeAsTheHostBitForBit) {
  // The CUDA backend runs the gas's passes from the same source on the device path of
  // GasBuffers: a thread per particle for the front and for each particle's terms, the blocks
  // folded after. ReverseBlockExec takes that path on the host, launching every loop in
  // reverse: the same additions in the same order, so the gas and the motion it drives are
  // the OpenMP step's bit for bit (the energy reductions differ in order, not compared).
  expect_device_path_as_host("");
}

TEST(Gas, TheDevicePathTakesTheSparseCrackPassesAsTheHostBitForBit) {
  expect_device_path_as_host(kSparsePasses);
}

TEST(Gas, BadJwlAndVentAreaInputNamesTheField) {
  const auto fails_with = [](const std::string& extra, const std::string& law, const std::string& needle) {
    try {
      system_from_yaml("gas_bad_jwl", disc_case(extra, "time: {steps: 1}\n", "{type: constant, value: 20 MPa}", law));
      ADD_FAILURE() << "accepted: " << extra << " " << law;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  fails_with("", "eos: jwl, gas_density: 1128", "loads[0].jwl");                         // the block is required
  fails_with("", "eos: jwl, gamma_high: 3, jwl: {A: 1 GPa}", "loads[0].gamma_high");     // two-gamma keys refused
  fails_with("", "eos: jwl, jwl: {A: 1 GPa, B: 1 GPa, C: 1 GPa, R1: 4, R2: 1, omega: 0.3, explosive_density: 1000}",
             "loads[0].gas_density");                                                    // v_ref needs it
  fails_with("", "eos: jwl, gas_density: 1128, jwl: {A: -1 GPa, B: 1 GPa, C: 1 GPa, R1: 4, R2: 1, omega: 0.3, "
             "explosive_density: 1000}", "loads[0].jwl.A");
  fails_with(", gas_density: 1000, vent_area: crack_opening", kTwoGamma, "loads[0].vent_area");  // no vent surfaces
  fails_with("", "eos: two_gamma, jwl: {A: 1 GPa}", "loads[0].jwl");
}

namespace {

// What the gas does with debris: the wetted particles that have lost every bond, computed
// here from the bonds' state and the entries the gas follows (in_crack), not from gas.hpp's
// own bookkeeping of them.
struct Debris {
  std::vector<int64_t> particles;  // wetted, no intact bond left
  double crack_share = 0;          // of the crack volume: the open entries in it with a debris end
  double max_displacement = 0;     // [m] the debris particles' largest |u|
  double kinetic = 0;              // [J] their kinetic energy
};

Debris measure_debris(const PdSystem& s) {
  Debris out;
  const GasState& g = s.gas;
  std::vector<uint8_t> loose(s.n, 0);
  for (size_t i = 0; i < s.n; ++i) {
    bool intact = false;
    for (int64_t k = s.offsets[i]; k < s.offsets[i + 1]; ++k) intact = intact || s.state[k] != 0;
    loose[i] = !intact;
    if (!loose[i] || !(g.arrival[i] < 1e300)) continue;
    out.particles.push_back(static_cast<int64_t>(i));
    double u2 = 0, v2 = 0;
    for (int d = 0; d < 3; ++d) u2 += s.u[3 * i + d] * s.u[3 * i + d], v2 += s.v[3 * i + d] * s.v[3 * i + d];
    out.max_displacement = std::max(out.max_displacement, std::sqrt(u2));
    out.kinetic += 0.5 * s.density[i] * s.volume[i] * v2;
  }
  // Each entry's share 1/2 a_k e_k, a_k = (kappa_i + kappa_j)/2 V_i V_j (gas.hpp's header).
  double debris = 0;
  for (size_t i = 0; i < s.n; ++i)
    for (int64_t k = s.offsets[i]; k < s.offsets[i + 1]; ++k) {
      const int64_t j = s.neighbor[k];
      if (!g.in_crack[k] || !(loose[i] || loose[j])) continue;
      double len2 = 0;
      for (int d = 0; d < 3; ++d) {
        const double dx = s.x0[3 * j + d] + s.u[3 * j + d] - s.x0[3 * i + d] - s.u[3 * i + d];
        len2 += dx * dx;
      }
      const double e = std::sqrt(len2) - s.xi_len[k];
      const double a = 0.5 * (g.kappa_volume[2 * i] + g.kappa_volume[2 * j]) * s.volume[i] * s.volume[j];
      if (e > 0) debris += 0.5 * a * e;
    }
  out.crack_share = g.crack_volume > 0 ? debris / g.crack_volume : 0.0;
  return out;
}

}  // namespace

TEST(Gas, AParticleThatHasLostEveryBondIsDebrisTheGasNeitherPushesNorFollows) {
  // The cracking disc (ACrackingChargeDoesTheWorkOfItsForces) run on until wall particles
  // have lost every bond. A crack is a gap between faces of the solid; a loose grain's
  // entries measure how far it has flown, so the gas must not push it (its velocity stays
  // what it was when it came loose) nor count its entries' growing openings as crack volume
  // (docs/theory.md "Debris"). Before, a loose grain kept the crack force -p dV/dy and flew
  // through the solid, its openings adding to the cavity.
  PdSystem s = system_from_yaml("gas_debris", cracking_disc(""));
  while (s.time < 60e-6) cpu_step(s);
  const Debris first = measure_debris(s);
  // A grain that came loose in the last step's bond pass is found at the next step's crack
  // pass; the force it had before still gives the half kick of the step after (velocity Verlet).
  cpu_step(s);
  cpu_step(s);
  std::vector<double> v0;
  for (int64_t i : first.particles)
    for (int d = 0; d < 3; ++d) v0.push_back(s.v[3 * i + d]);
  const double t0 = s.time;
  while (s.time < t0 + 40e-6) cpu_step(s);
  const Debris last = measure_debris(s);
  // crack share: the openings now of the entries with a loose end that the gas followed,
  // over the crack volume (before, they were in it; now their shares are frozen).
  std::printf("debris at %.0f us: %zu particles, crack share %.4f; at %.0f us: %zu, crack share %.4f of %.4g m3, "
              "largest |u| %.3g mm, kinetic %.4g J of the gas work %.4g J\n",
              t0 * 1e6, first.particles.size(), first.crack_share, s.time * 1e6, last.particles.size(), last.crack_share,
              s.gas.crack_volume, last.max_displacement * 1e3, last.kinetic, s.gas.work);
  ASSERT_GE(first.particles.size(), 3u) << "the test needs loose grains";
  // Exact: a grain with no bond takes no bond force, the wall's pressure skips it
  // (SurfaceLoads) and no other load acts, so the gas's push is the only force that could
  // change its velocity.
  double worst = 0, scale = 0;
  for (size_t q = 0; q < first.particles.size(); ++q)
    for (int d = 0; d < 3; ++d) {
      worst = std::max(worst, std::fabs(s.v[3 * first.particles[q] + d] - v0[3 * q + d]));
      scale = std::max(scale, std::fabs(v0[3 * q + d]));
    }
  EXPECT_EQ(worst, 0.0) << "a loose grain was accelerated (largest velocity " << scale << " m/s)";
  // 1%: the bound on the gas work against the work of its forces (as above); the
  // frozen entries leave the work as a wall particle that leaves the wall does.
  EXPECT_NEAR(s.external_work / s.gas.work, 1.0, 0.01);
}

TEST(Gas, TheChunkedCrackPassSumsAsTheOneEntryLoopBitForBit) {
  // GasCrackSum's host pass picks the entries in the crack branch-free in chunks of
  // kBondChunk, computes their openings as a batch and adds their terms in entry order; the
  // CUDA build runs one entry at a time. Here rows of 150 entries (three chunks) mix every
  // kind of entry at random: in the crack already, joining (open, partner wetted), open to a
  // dry partner, intact on one or both halves, half missing, opening or closing, leaving (an
  // end that has lost every bond: debris) or frozen since an earlier pass. The sums and
  // each particle's push must be the one-entry loop's, written out below from the formulas
  // (gas.hpp's header), bit for bit, and the entries marked the same.
  constexpr int n = 151;
  std::vector<double> x0(3 * n), u(3 * n), u_before(3 * n), position(3 * n), kappa_volume(2 * n), vent(n, 0.0);
  std::vector<double> arrival(n), arrival_next(n), push(3 * n, 0.0);
  std::vector<uint8_t> front_done(n, 0), attached(n, 1);
  std::vector<int64_t> offsets(n + 1, 0);
  std::vector<int32_t> neighbor;
  std::vector<double> xi_len;
  std::vector<uint8_t> state, halves, in_crack;
  uint64_t seed = 12345;
  const auto rnd = [&seed] {  // uniform in [0, 1), a fixed sequence
    seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<double>(seed >> 11) * 0x1.0p-53;
  };
  for (int i = 0; i < n; ++i) {
    for (int d = 0; d < 3; ++d) {
      x0[3 * i + d] = rnd();
      u_before[3 * i + d] = 0.02 * (rnd() - 0.5);
      u[3 * i + d] = u_before[3 * i + d] + 0.01 * (rnd() - 0.5);
      position[3 * i + d] = x0[3 * i + d] + u[3 * i + d];
    }
    kappa_volume[2 * i] = 1.0 + rnd();
    kappa_volume[2 * i + 1] = 1e-3 * (1.0 + rnd());
    arrival_next[i] = rnd() < 0.7 ? 1e-6 * rnd() : std::numeric_limits<double>::infinity();
    arrival[i] = arrival_next[i];
    if (rnd() < 0.2) vent[i] = rnd();
    if (rnd() < 0.1) attached[i] = 0;  // debris (gas_debris_entry)
  }
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      if (j == i) continue;
      neighbor.push_back(j);
      double r2 = 0.0;
      for (int d = 0; d < 3; ++d) r2 += (x0[3 * j + d] - x0[3 * i + d]) * (x0[3 * j + d] - x0[3 * i + d]);
      xi_len.push_back(std::sqrt(r2));
      const uint8_t have = static_cast<uint8_t>(1 + static_cast<int>(3 * rnd()));  // own, dual or both
      const uint8_t st = static_cast<uint8_t>(have & static_cast<int>(4 * rnd()));
      halves.push_back(have);
      state.push_back(st);
      const double r = rnd();  // in the crack (1), frozen there (2) or not yet (0)
      in_crack.push_back((st & have) == 0 && r < 0.5 ? (r < 0.05 ? 2 : 1) : 0);
    }
    offsets[i + 1] = static_cast<int64_t>(neighbor.size());
  }
  std::vector<uint8_t> in_crack_ref = in_crack;

  PdView p;
  p.n = n;
  p.u = u.data();
  p.offsets = offsets.data();
  p.neighbor = neighbor.data();
  p.xi_len = xi_len.data();
  p.state = state.data();
  GasView g;
  g.arrival = arrival.data();
  g.arrival_next = arrival_next.data();
  g.kappa_volume = kappa_volume.data();
  g.vent_area = vent.data();
  g.halves = halves.data();
  g.position = position.data();
  g.push = push.data();
  g.front_done = front_done.data();
  g.in_crack = in_crack.data();
  g.attached = attached.data();
  const GasCrackSum<double> pass{p, g, u_before.data()};

  int64_t joined_entries = 0, summed_entries = 0, left_entries = 0;
  for (int i = 0; i < n; ++i) {
    const GasSums got = pass(i);
    // The one-entry loop.
    double volume = 0.0, before = 0.0, joined = 0.0, left = 0.0, frozen = 0.0, density = 0.0, pv[3] = {0.0, 0.0, 0.0};
    const bool wet = arrival_next[i] < 1e300;
    if (wet) {
      const double vi = kappa_volume[2 * i + 1];
      for (int64_t k = offsets[i]; k < offsets[i + 1]; ++k) {
        const int j = neighbor[k];
        if (in_crack_ref[k] == 2) continue;  // frozen at an earlier pass
        const bool counted = in_crack_ref[k] == 1;
        const bool debris = !attached[i] || !attached[j];
        const bool leaves = counted && debris;
        if (leaves) {
          in_crack_ref[k] = 2;
          ++left_entries;
        }
        if (!counted) {
          if (debris) continue;
          if ((state[k] & halves[k]) != 0 || !(arrival_next[j] < 1e300)) continue;
          in_crack_ref[k] = 1;
          ++joined_entries;
        }
        ++summed_entries;
        double dv[3], len2 = 0.0;
        for (int d = 0; d < 3; ++d) dv[d] = position[3 * j + d] - position[3 * i + d];
        len2 = dv[0] * dv[0] + dv[1] * dv[1] + dv[2] * dv[2];
        const double len = std::sqrt(len2);
        const double e = len - xi_len[k];
        if (!(e > 0.0)) continue;
        double unit[3];
        for (int d = 0; d < 3; ++d) unit[d] = len > 0 ? dv[d] / len : 0.0;
        const double a = 0.5 * (kappa_volume[2 * i] + kappa_volume[2 * j]) * kappa_volume[2 * j + 1];
        const double share = a * vi * e * 0.5;
        volume += share;
        double dot = 0.0;
        for (int d = 0; d < 3; ++d) dot += unit[d] * (u[3 * i + d] - u_before[3 * i + d]);
        const double moved = vi * a * dot;
        if (leaves) {  // its share frozen in the volume; its last force over this step's motion
          before += share + moved;
          left += -moved;
          frozen += share;
          continue;  // pushes no more
        }
        if (counted) before += share;
        else joined -= moved;
        density += a * e * 0.5;
        for (int d = 0; d < 3; ++d) pv[d] += a * unit[d];
      }
    }
    const bool vents = wet && vent[i] > 0.0 && arrival_next[i] > 0.0;
    ASSERT_EQ(got.volume, volume) << "particle " << i;
    EXPECT_EQ(got.volume_before, before) << "particle " << i;
    EXPECT_EQ(got.joined, joined) << "particle " << i;
    EXPECT_EQ(got.left, left) << "particle " << i;
    EXPECT_EQ(got.frozen, frozen) << "particle " << i;
    EXPECT_EQ(got.vents, vents ? 1.0 : 0.0) << "particle " << i;
    EXPECT_EQ(got.vent_area, vents ? density * vent[i] : 0.0) << "particle " << i;
    if (wet)
      for (int d = 0; d < 3; ++d) EXPECT_EQ(push[3 * i + d], pv[d]) << "particle " << i << ", component " << d;
    EXPECT_EQ(arrival[i], arrival_next[i]) << "the front's commit";
  }
  EXPECT_TRUE(in_crack == in_crack_ref) << "the entries marked in the crack differ";
  // Something of each kind was exercised.
  EXPECT_GT(joined_entries, 1000);
  EXPECT_GT(summed_entries - joined_entries, 1000);
  EXPECT_GT(left_entries, 200);  // 435 with this seed
}

namespace {

// Steps one system with the settled chunks (GasView::row_mark, chunk_live: a chunk of a row
// none of whose inputs changed since the last pass reads only in_crack) and one without them
// (row_mark and chunk_live emptied: every crack pass picks every entry in full, entry_mode on
// each, as before the settled chunks) to `end`, and expects the same front, the same entries
// in the volume, the same gas and the same motion bit for bit. Returns the share of the
// chunks the first system's passes visited that they could take as settled (the row not
// marked before the pass, the same intact halves at the pass as at the last).
double expect_settled_rows_as_full_picks(const std::string& name, const std::string& deck, double end) {
  PdSystem settled = system_from_yaml(name + "_settled", deck);
  PdSystem full = system_from_yaml(name + "_full", deck);
  if (settled.gas.row_mark.empty() || settled.gas.chunk_live.empty()) {
    ADD_FAILURE() << "the host run has no settled chunks";
    return 0.0;
  }
  full.gas.row_mark.clear();
  full.gas.chunk_live.clear();
  int64_t taken = 0, visited = 0, passes = 0, steps = 0;
  while (settled.time < end) {
    const std::vector<uint8_t> mark = settled.gas.row_mark, live = settled.gas.chunk_live;
    cpu_step(settled);
    // a pass sets the countdown to the interval less one; a step between passes lowers it
    ++steps;
    if (settled.gas.crack_pass_countdown < settled.gas.crack_pass_interval - 1) continue;
    ++passes;
    for (size_t i = 0; i < settled.n; ++i) {
      if (!(settled.gas.arrival[i] < 1e300)) continue;
      for (int64_t base = settled.offsets[i]; base < settled.offsets[i + 1]; base += kBondChunk) {
        ++visited;
        taken += mark[i] == 0 && live[base] == settled.gas.chunk_live[base];
      }
    }
  }
  while (full.time < end) cpu_step(full);
  expect_same_gas_and_motion(settled, full, "settled chunks and full picks");
  const double share = visited > 0 ? static_cast<double>(taken) / static_cast<double>(visited) : 0.0;
  std::printf("%s: %lld of %lld visited chunks settled (%.3f), %lld passes in %lld steps\n", name.c_str(),
              static_cast<long long>(taken), static_cast<long long>(visited), share, static_cast<long long>(passes),
              static_cast<long long>(steps));
  return share;
}

}  // namespace

TEST(Gas, SettledRowsGiveTheFullPicksAnswerBitForBitOnABreakingDisc) {
  // The cracking disc to 80 us: bonds break next to the gas at every step, the front runs
  // into the new crack, and wall particles lose every bond (debris: their rows and their
  // partners' leave the volume), so every way a row is marked is taken. A good share of the
  // chunks must be settled (about half here), else the test would not test the settled path.
  const double share = expect_settled_rows_as_full_picks("gas_settled_breaking", cracking_disc(""), 80e-6);
  EXPECT_GT(share, 0.3);
}

TEST(Gas, SettledRowsGiveTheFullPicksAnswerBitForBitOnAVentingCrack) {
  // The pre-cracked disc (no fracture: no bond breaks), the front running the pre-crack at
  // 500 m/s to the outer face and venting there, to 300 us: rows are marked only by the front.
  const std::string deck =
      disc_case(", vent_surfaces: [outer], front_speed: 500 m/s, gas_density: 1000 kg/m3, vent_area: 100 mm2",
                "precracks: [{type: segment, from: [4 mm, 0.01 mm], to: [41 mm, 0.01 mm]}]\ntime: {steps: 1}\n");
  const double share = expect_settled_rows_as_full_picks("gas_settled_venting", deck, 300e-6);
  EXPECT_GT(share, 0.5);
}

TEST(Gas, SettledRowsGiveTheFullPicksAnswerBitForBitBetweenSparsePasses) {
  // Passes up to 8 steps apart that tolerate new crack (no pass forced where a bond next to
  // the gas breaks) with a tolerance wide enough that they spread out on this breaking disc:
  // the halves broken at the steps between passes are found by the chunks' sums of intact
  // halves at the next pass.
  const double share = expect_settled_rows_as_full_picks(
      "gas_settled_sparse",
      cracking_disc(", crack_pass_every: 8, crack_pass_new_crack: tolerance, crack_pass_tolerance: 0.5"), 80e-6);
  EXPECT_GT(share, 0.2);
}
