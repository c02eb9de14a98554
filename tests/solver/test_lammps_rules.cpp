// The modelling choices of LAMMPS PERI offered as options (docs/lammps-peri.md): its family
// edge, its continuum micromodulus, its short-range forces, its break order, and the
// Silling-Askari compressive enhancement; and the fast and general kernel paths against each
// other. Each is checked against a reference derived here
// independently (lattice sums, the documented formula, energy gradients), not against the code.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <numbers>
#include <tuple>

#include "breccia/common/error.hpp"
#include "breccia/solver/outputs.hpp"
#include "breccia/solver/partial_volume_lattice.hpp"
#include "breccia/solver/run.hpp"
#include "helpers.hpp"

using namespace breccia::solver;
using namespace breccia::solver::testing;

namespace {

// LAMMPS's example lattice: 0.5 mm simple cubic, horizon 1.5001 mm (examples/peri).
constexpr double kSpacing = 0.0005, kHorizon = 0.0015001;

std::string cube_deck(const std::string& model_extra, int cells = 9, const std::string& material_extra = "") {
  const double side = cells * kSpacing;
  return "specimen: {lattice: {dimension: 3, box: [0, 0, 0, " + std::to_string(side) + ", " + std::to_string(side) +
         ", " + std::to_string(side) + "], spacing: 0.5 mm}}\n"
         "model: {type: pmb, horizon: 1.5001 mm" + model_extra + "}\n"
         "materials: [{name: m, density: 2200, youngs_modulus: 22.35 GPa, poisson_ratio: 0.25" + material_extra + "}]\n"
         "time: {steps: 1}\n";
}

// LAMMPS's weight of a neighbour at |xi| (FixPeriNeigh / PairPeriPMB vfrac_scale): 1 inside
// delta - lc/2, (delta + lc/2 - |xi|) / lc up to delta, and not a neighbour beyond it.
double lammps_weight(double len) {
  const double half = 0.5 * kSpacing;
  if (len > kHorizon) return 0.0;
  if (std::fabs(len - kHorizon) <= half) return (kHorizon + half - len) / (2.0 * half);
  return 1.0;
}

// The documented law summed here over every other particle: 15 c V (d - r) / delta along
// j -> i with d = min(0.9 |xi|, 1.35 dx), c = 18 K / (pi delta^4) (K of the decks below).
// `pairs` receives how many pairs were inside their reach.
std::array<double, 3> expected_short_range(const PdSystem& s, int64_t i, int& pairs) {
  const double K = 22.35e9 / 1.5;
  const double c = 18.0 * K / (std::numbers::pi * std::pow(kHorizon, 4));
  std::array<double, 3> expected{0, 0, 0};
  pairs = 0;
  for (size_t j = 0; j < s.n; ++j) {
    if (static_cast<int64_t>(j) == i) continue;
    double xi = 0, r = 0, dx[3];
    for (int a = 0; a < 3; ++a) {
      xi += std::pow(s.x0[3 * j + a] - s.x0[3 * i + a], 2);
      dx[a] = s.x0[3 * j + a] + s.u[3 * j + a] - s.x0[3 * i + a] - s.u[3 * i + a];
      r += dx[a] * dx[a];
    }
    xi = std::sqrt(xi);
    r = std::sqrt(r);
    const double d = std::min(0.9 * xi, 1.35 * kSpacing);
    if (r >= d) continue;
    ++pairs;
    for (int a = 0; a < 3; ++a) expected[a] -= 15.0 * c * kSpacing * kSpacing * kSpacing * (d - r) / kHorizon * dx[a] / r;
  }
  return expected;
}

int64_t centre_particle(const PdSystem& s, int cells) {
  const double c = (cells / 2 + 0.5) * kSpacing;  // lattice cell centres at (k + 1/2) dx
  return nearest(s, c, c, c);
}

}  // namespace

TEST(LammpsFamily, IsTheLatticePointsWithinTheHorizonWithLammpsWeights) {
  PdSystem s = system_from_yaml("lammps_family", cube_deck(", partial_volume: lammps, fracture: false"));
  const int64_t i = centre_particle(s, 9);
  // Lattice points with 0 < |n| <= 3.0002 (n integer): 122 (LAMMPS's family of an interior atom).
  int expected = 0;
  for (int a = -4; a <= 4; ++a)
    for (int b = -4; b <= 4; ++b)
      for (int c = -4; c <= 4; ++c)
        if ((a || b || c) && std::sqrt(double(a * a + b * b + c * c)) * kSpacing <= kHorizon) ++expected;
  ASSERT_EQ(expected, 122);
  EXPECT_EQ(s.offsets[i + 1] - s.offsets[i], expected);
  const double cell = kSpacing * kSpacing * kSpacing;
  for (int64_t k = s.offsets[i]; k < s.offsets[i + 1]; ++k)
    EXPECT_NEAR(s.vol_own[k] / cell, lammps_weight(s.xi_len[k]), 1e-12) << "bond of length " << s.xi_len[k];
  // Breccia's own edge reaches a cell's half diagonal beyond delta: more neighbours.
  PdSystem sampled = system_from_yaml("sampled_family", cube_deck(", fracture: false"));
  const int64_t j = centre_particle(sampled, 9);
  EXPECT_GT(sampled.offsets[j + 1] - sampled.offsets[j], expected);
}

TEST(LammpsFamily, ContinuumMicromodulusGivesTheLatticeSumsBulkModulus) {
  // With c = 18 K / (pi delta^4) as given (LAMMPS), an interior particle's energy under an
  // isotropic strain e is sum_j 1/4 c w_j V |xi_j| e^2 (w_j LAMMPS's weight), which the
  // lattice sum below evaluates: about 0.900 of the classical 9/2 K e^2 at m = 3.
  const double E = 22.35e9, K = E / (3.0 * (1.0 - 2.0 * 0.25));
  const double c = 18.0 * K / (std::numbers::pi * std::pow(kHorizon, 4));
  const double cell = kSpacing * kSpacing * kSpacing;
  double lattice_sum = 0.0;
  for (int a = -4; a <= 4; ++a)
    for (int b = -4; b <= 4; ++b)
      for (int d = -4; d <= 4; ++d) {
        if (!(a || b || d)) continue;
        const double len = std::sqrt(double(a * a + b * b + d * d)) * kSpacing;
        lattice_sum += 0.25 * c * lammps_weight(len) * cell * len;
      }
  const double ratio = lattice_sum / (4.5 * K);
  EXPECT_NEAR(ratio, 0.9001, 5e-4);  // the value quoted in docs/lammps-peri.md
  const double e = 1e-6;
  const double eps[9] = {e, 0, 0, 0, e, 0, 0, 0, e};
  for (const char* calibration : {"continuum", "discrete"}) {
    PdSystem s = system_from_yaml(std::string("calibration_") + calibration,
                                  cube_deck(std::string(", partial_volume: lammps, fracture: false, pmb_calibration: ") +
                                            calibration));
    impose_affine(s, eps);
    cpu_compute_forces(s);
    const int64_t i = centre_particle(s, 9);
    const double classical = 4.5 * K * e * e;
    // Stretches of an affine field are exact to O(e^2): 1e-5 relative.
    const double expected = std::string(calibration) == "continuum" ? ratio : 1.0;
    EXPECT_NEAR(s.energy_density[i] / classical, expected, 1e-5) << calibration;
  }
}

TEST(ShortRangeForces, AreTheGradientOfTheirEnergyAndCancelInPairs) {
  // Squeeze one particle towards its +x neighbour by 30% of the spacing: its pairs with
  // (1,0,0) and the four (1,+-1,0), (1,0,+-1) neighbours come inside min(0.9 |xi|, 1.35 dx).
  PdSystem s = system_from_yaml("short_range", cube_deck(", fracture: false, short_range_forces: true"));
  PdSystem plain = system_from_yaml("short_range_off", cube_deck(", fracture: false"));
  const int64_t i = centre_particle(s, 9);
  s.u[3 * i] = plain.u[3 * i] = 0.3 * kSpacing;
  cpu_compute_forces(s);
  cpu_compute_forces(plain);
  int pairs = 0;
  const std::array<double, 3> expected = expected_short_range(s, i, pairs);
  EXPECT_EQ(pairs, 5);
  for (int a = 0; a < 3; ++a)
    EXPECT_NEAR(s.force[3 * i + a] - plain.force[3 * i + a], expected[a], 1e-9 * std::fabs(expected[0])) << a;
  // Newton's third law over the body (the pair forces use the pair's mean constant).
  for (int a = 0; a < 3; ++a) {
    double total = 0.0;
    for (size_t j = 0; j < s.n; ++j) total += s.force[3 * j + a] * s.volume[j];
    EXPECT_NEAR(total, 0.0, 1e-9 * std::fabs(expected[0]) * s.volume[i]) << a;
  }
  // The force is minus the gradient of the energy (bond and short-range parts together):
  // central difference of the body's energy in u_x of particle i.
  auto energy = [&](double ux) {
    s.u[3 * i] = ux;
    cpu_compute_forces(s);
    double w = 0.0;
    for (size_t j = 0; j < s.n; ++j) w += s.energy_density[j] * s.volume[j];
    return w;
  };
  const double h = 1e-4 * kSpacing, u0 = 0.3 * kSpacing;
  const double gradient = (energy(u0 + h) - energy(u0 - h)) / (2.0 * h);
  energy(u0);
  EXPECT_NEAR(-gradient, s.force[3 * i] * s.volume[i], 1e-4 * std::fabs(s.force[3 * i] * s.volume[i]));
}

TEST(ShortRangeForces, AContactOfUnequalParticlesIsNoStifferThanEitherKindsOwn) {
  // Two bodies in contact act as springs in series (Johnson, Contact Mechanics, 1985: the
  // effective modulus 1/E* = 1/E1 + 1/E2): a pair of particles with unequal constants
  // k = 15 c / delta (c ~ delta^-4: k ~ delta^-5) repels with the harmonic mean 2 ki kj /
  // (ki + kj). A fine particle (spacing l) against a coarse one (2 l: 8 times its volume, k/32)
  // then feels a spring of 2/33 k x 8 V, about half of what a fine partner gives it (k V);
  // the arithmetic mean gave 4.1 times (k/2 x 33/32 x 8 V), which took its frequency past
  // the bonds' stable step on graded meshes (docs/theory.md, LAMMPS PERI's choices).
  const double k = 3.0e20, volume_fine = 1.25e-10;  // any positive values: the law is linear in both
  const double short_range_k[2] = {k, k / 32.0}, volume[2] = {volume_fine, 8.0 * volume_fine};
  PdViewT<double> p;
  p.n = 2;
  p.short_range_k = short_range_k;
  p.volume = volume;
  p.diagnostics = true;
  const double reach = 1.0e-3, len = 0.9e-3, gap = reach - len;
  // The pair's spring on each end, from the push on it: the force density times its own volume.
  auto spring = [&](int64_t i, int64_t j) {
    double fx = 0, fy = 0, fz = 0, w = 0;
    add_short_range_pair(p, i, j, reach, (i == 0 ? 1.0 : -1.0) * len, 0.0, 0.0, len, fx, fy, fz, w);
    EXPECT_EQ(fy, 0.0);
    return std::fabs(fx) * volume[i] / gap;
  };
  const double fine_on_coarse = spring(0, 1), coarse_on_fine = spring(1, 0);
  EXPECT_DOUBLE_EQ(fine_on_coarse, coarse_on_fine);  // equal and opposite forces
  const double series = 2.0 * k * (k / 32.0) / (k + k / 32.0) * volume[0] * volume[1];
  EXPECT_NEAR(fine_on_coarse, series, 1e-12 * series);
  // Per unit mass of each end (rho cancels): no stiffer than its own kind's contact.
  const double fine_own = k * volume[0] * volume[0], coarse_own = (k / 32.0) * volume[1] * volume[1];
  EXPECT_LT(fine_on_coarse / volume[0], fine_own / volume[0]);
  EXPECT_LT(fine_on_coarse / volume[1], coarse_own / volume[1]);
  // Equal constants: the one constant, bit for bit (a lattice's law, LAMMPS's, unchanged).
  const double same[2] = {k, k};
  p.short_range_k = same;
  const double old_law = 0.5 * (k + k) * volume[1];  // the mean of equal constants, exact
  EXPECT_EQ(spring(0, 1), std::fabs(-old_law * gap / len * len) * volume[0] / gap);
}

TEST(ShortRangeForces, ReachParticlesOutsideTheFamily) {
  // A particle carried far across the body (a fragment meeting another) feels the particle it
  // lands next to although they were never in one family; without the option it does not.
  for (bool on : {true, false}) {
    PdSystem s = system_from_yaml(on ? "contact_on" : "contact_off",
                                  cube_deck(std::string(", fracture: false") + (on ? ", short_range_forces: true" : ""), 12));
    const int64_t i = nearest(s, 0.25e-3, 3.25e-3, 3.25e-3), j = nearest(s, 5.25e-3, 3.25e-3, 3.25e-3);
    ASSERT_GT(s.xi_len[s.offsets[i]], 0.0);
    for (int64_t k = s.offsets[i]; k < s.offsets[i + 1]; ++k) ASSERT_NE(s.neighbor[k], j) << "j must be outside i's family";
    // Cut i free of its family's forces: every bond broken; then place it 0.5 dx from j.
    for (int64_t k = s.offsets[i]; k < s.offsets[i + 1]; ++k) s.state[k] = 0;
    s.u[3 * i] = (5.25e-3 - 0.3 * kSpacing) - 0.25e-3;  // 0.3 dx before j, 0.2 dx off its row
    s.u[3 * i + 1] = 0.2 * kSpacing;
    cpu_compute_forces(s);
    // Expected: the documented law over every particle near i's new place (none of them in
    // i's family; its members stayed 4 mm behind).
    int partners = 0;
    const std::array<double, 3> expected = expected_short_range(s, i, partners);
    ASSERT_GE(partners, 1);
    const double scale = std::hypot(expected[0], expected[1], expected[2]);
    for (int a = 0; a < 3; ++a) {
      if (on) EXPECT_NEAR(s.force[3 * i + a], expected[a], 1e-9 * scale) << a;
      else EXPECT_EQ(s.force[3 * i + a], 0.0) << a;
    }
    if (on) EXPECT_LT(expected[0], 0.0);  // pushed back, away from j (nearer than the plane behind)
  }
}

class CompressiveEnhancement : public ::testing::TestWithParam<const char*> {};

TEST_P(CompressiveEnhancement, BreaksBondsAtS0MinusAlphaTimesTheLastStepsSmallestStretch) {
  // Silling & Askari (2005): s0 = s00 - alpha s_min, s_min from the previous step. Squeeze the
  // body along y by 0.4% (s_min = -0.004 everywhere: the y bonds), commit that step, then add
  // a stretch along x of 0.11%: with alpha = 0.25 a bond breaks above 5e-4 + 0.25 x 0.004 =
  // 1.5e-3, and none does; with alpha = 0 every bond stretched past 5e-4 breaks. The count
  // expected is taken from the exact stretches of the affine field (no bond lies within 7%
  // of either threshold, so float32 rounding decides nothing). Float32 and float64 run the
  // same kernels.
  const double s00 = 5e-4, e1 = 1.1e-3, e2 = -4e-3;
  const double delta = kHorizon, K = 22.35e9 / 1.5;
  const double c = 18.0 * K / (std::numbers::pi * std::pow(delta, 4));
  const double G0 = std::numbers::pi * c * s00 * s00 * std::pow(delta, 5) / 10.0;  // s0 = s00 (docs/lammps-peri.md)
  for (double alpha : {0.25, 0.0}) {
    const std::string extra = ", fracture_energy: " + std::to_string(G0);
    PdSystem s = system_from_yaml("alpha_" + std::to_string(alpha),
                                  cube_deck(", partial_volume: lammps, precision: " + std::string(GetParam()) +
                                                ", compressive_enhancement: " + std::to_string(alpha),
                                            9, extra));
    ASSERT_NEAR(s.s0_own[0], s00, 1e-6 * s00);
    const double squeeze[9] = {0, 0, 0, 0, e2, 0, 0, 0, 0};
    impose_affine(s, squeeze);
    commit_min_stretch(s);
    cpu_compute_forces(s);  // no bond stretched: nothing breaks, s_min = e2 recorded
    ASSERT_EQ(measure(s).broken_half_bonds, 0);
    const double both[9] = {e1, 0, 0, 0, e2, 0, 0, 0, 0};
    impose_affine(s, both);
    commit_min_stretch(s);
    cpu_compute_forces(s);
    long long expected = 0;
    for (size_t i = 0; i < s.n; ++i)
      for (int64_t k = s.offsets[i]; k < s.offsets[i + 1]; ++k) {
        const int64_t j = s.neighbor[k];
        double len = 0;
        for (int a = 0; a < 3; ++a) {
          double d = s.x0[3 * j + a] - s.x0[3 * i + a];
          d *= 1.0 + (a == 0 ? e1 : a == 1 ? e2 : 0.0);
          len += d * d;
        }
        const double stretch = std::sqrt(len) / s.xi_len[k] - 1.0;
        if (stretch > s00 - alpha * e2) ++expected;  // every particle has a y bond: s_min = e2
      }
    long long broken = 0;
    for (uint8_t st : s.state) broken += st == 0;
    EXPECT_EQ(broken, expected) << "alpha " << alpha;
    if (alpha > 0) EXPECT_EQ(broken, 0);
    else EXPECT_GT(broken, 0);
  }
}

INSTANTIATE_TEST_SUITE_P(Precisions, CompressiveEnhancement, ::testing::Values("float64", "float32"));

TEST(BreakCheck, AfterForceLetsABreakingBondPushOnceMore) {
  // One pass at a uniform 0.1% stretch along x (past s0 = 5e-4 for the x bonds): both orders
  // break the same bonds; before_force drops their pull from the pass, after_force keeps it.
  const double s00 = 5e-4, K = 22.35e9 / 1.5;
  const double c = 18.0 * K / (std::numbers::pi * std::pow(kHorizon, 4));
  const double G0 = std::numbers::pi * c * s00 * s00 * std::pow(kHorizon, 5) / 10.0;
  const std::string extra = ", fracture_energy: " + std::to_string(G0);
  PdSystem before = system_from_yaml("break_before", cube_deck(", partial_volume: lammps", 9, extra));
  PdSystem after = system_from_yaml("break_after", cube_deck(", partial_volume: lammps, break_check: after_force", 9, extra));
  PdSystem intact = system_from_yaml("break_none", cube_deck(", partial_volume: lammps, fracture: false", 9, extra));
  const double eps[9] = {1e-3, 0, 0, 0, 0, 0, 0, 0, 0};
  for (PdSystem* s : {&before, &after, &intact}) {
    impose_affine(*s, eps);
    cpu_compute_forces(*s);
  }
  EXPECT_EQ(before.state, after.state);
  EXPECT_GT(measure(before).broken_half_bonds, 0);
  EXPECT_EQ(before.dissipated_energy, after.dissipated_energy);
  // A surface particle at x = max: the unbroken body pulls it back (-x); after_force gives
  // exactly the unbroken body's force this pass, before_force a smaller one.
  const int64_t i = nearest(before, 4.25e-3, 2.25e-3, 2.25e-3);
  EXPECT_EQ(after.force[3 * i], intact.force[3 * i]);
  EXPECT_LT(intact.force[3 * i], 0.0);
  EXPECT_GT(before.force[3 * i], intact.force[3 * i]);
}

TEST(CompressiveEnhancementRestart, WithTheLammpsOptionsIsBitIdentical) {
  // The glass plate of the restart test with every option of this file on: s_min and the
  // short-range contact must come back from the checkpoint exactly.
  std::string deck = kPrecrackedGlassPlateDeck;
  const std::string model = "model: {type: pmb, planar: plane_stress, horizon_factor: 3.015";
  ASSERT_NE(deck.find(model), std::string::npos);
  deck.replace(deck.find(model), model.size(),
               model + ", compressive_enhancement: 0.25, short_range_forces: true, break_check: after_force");
  const CaseConfig config =
      parse_case_file(write_case("alpha_restart", deck + "time: {steps: 400}\noutput: {every: 100, history_every: 20}\n"));
  auto [straight, second] = straight_and_restarted(config, "alpha_restart", 170);
  ASSERT_GT(measure(straight).broken_half_bonds, 0) << "the case should break bonds";
  expect_same_motion(second, straight);
  EXPECT_EQ(second.min_stretch, straight.min_stretch);
}

TEST(LammpsOptions, BadValuesNameTheKey) {
  auto error_of = [](const std::string& extra, const std::string& type = "pmb") {
    std::string deck = cube_deck(extra);
    if (type != "pmb") deck.replace(deck.find("type: pmb"), 9, "type: " + type);
    try {
      parse_case_file(write_case("bad_lammps_option", deck));
    } catch (const breccia::InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error_of(", compressive_enhancement: -0.1").find("model.compressive_enhancement"), std::string::npos);
  EXPECT_NE(error_of(", partial_volume: half").find("model.partial_volume"), std::string::npos);
  EXPECT_NE(error_of(", pmb_calibration: continuum", "lps").find("model.pmb_calibration"), std::string::npos);
  EXPECT_NE(error_of(", break_check: later").find("model.break_check"), std::string::npos);
  EXPECT_NE(error_of(", short_range_forces: true", "correspondence").find("model.short_range_forces"),
            std::string::npos);
}

// The fast kernels (one constant horizon: pmb_symmetric_force_kernel, lps_symmetric_force_
// kernel, the float SIMD loop) and the general force_kernel compute the same forces, breaks
// and diagnostics by different arithmetic; here on the CPU, from one random displacement
// that breaks some bonds. Tolerances: double round-off over ~120 bonds (1e-12 of the largest
// force), float's (2e-5); the breaks are identical (no stretch lies within rounding of s0 in
// this field, checked by the equal counts).
class FastAndGeneralPaths : public ::testing::TestWithParam<std::tuple<std::string, std::string>> {};

TEST_P(FastAndGeneralPaths, AgreeOnForcesBreaksAndDiagnostics) {
  const auto [model, precision] = GetParam();
  const std::string deck =
      "specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.004, 0.004, 0.004], spacing: 0.5 mm}}\n"
      "model: {type: " + std::string(model) + ", horizon_factor: 3.015, precision: " + precision + "}\n"
      "materials: [{name: m, density: 2200, youngs_modulus: 22.35 GPa, poisson_ratio: 0.25, fracture_energy: 2}]\n"
      "time: {steps: 1}\n";
  PdSystem fast = system_from_yaml(std::string("fast_") + model + precision, deck);
  PdSystem general = system_from_yaml(std::string("general_") + model + precision, deck);
  ASSERT_TRUE(fast.symmetric_halves);
  general.symmetric_halves = false;  // the same system through force_kernel's general loop
  SplitMixUniform uniform{12345};
  for (size_t k = 0; k < 3 * fast.n; ++k) fast.u[k] = general.u[k] = 2e-3 * 0.5e-3 * uniform();  // strains ~4e-3
  for (bool diagnostics : {false, true}) {
    fast.diagnostics = general.diagnostics = diagnostics;
    cpu_compute_forces(fast);
    cpu_compute_forces(general);
  }
  long long broken_fast = 0, broken_general = 0;
  for (size_t k = 0; k < fast.state.size(); ++k) {
    broken_fast += fast.state[k] == 0;
    broken_general += general.state[k] != (kOwnIntact | kDualIntact);
  }
  ASSERT_GT(broken_fast, 0) << "the field should break some bonds";
  EXPECT_EQ(broken_fast, broken_general);
  double fmax = 0.0;
  for (double f : general.force) fmax = std::max(fmax, std::fabs(f));
  const double tol = std::string(precision) == "float32" ? 2e-5 : 1e-12;
  for (size_t k = 0; k < fast.force.size(); ++k) ASSERT_NEAR(fast.force[k], general.force[k], tol * fmax) << k;
  double wmax = 0.0;
  for (double w : general.energy_density) wmax = std::max(wmax, std::fabs(w));
  for (size_t i = 0; i < fast.n; ++i) {
    ASSERT_NEAR(fast.energy_density[i], general.energy_density[i], tol * wmax) << i;
    ASSERT_NEAR(fast.damage[i], general.damage[i], 1e-12) << i;
  }
  EXPECT_NEAR(fast.dissipated_energy, general.dissipated_energy, tol * 10 * general.dissipated_energy);
}

// Strings, named by model and precision: with const char* values ctest's names printed the
// strings' addresses, which change from build to build (and filters by name with them).
INSTANTIATE_TEST_SUITE_P(Models, FastAndGeneralPaths,
                         ::testing::Combine(::testing::Values(std::string("pmb"), std::string("lps")),
                                            ::testing::Values(std::string("float64"), std::string("float32"))),
                         [](const auto& info) { return std::get<0>(info.param) + "_" + std::get<1>(info.param); });

namespace {
// A uniform number in [0, 1) from one SplitMix64 step of z: the partial-volume tests' cases.
double split_mix_uniform(uint64_t& z) {
  z += 0x9E3779B97F4A7C15ull;
  uint64_t x = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return double((x ^ (x >> 31)) >> 11) / 9007199254740992.0;
}
}  // namespace

TEST(PartialVolume, PositiveTestEqualsTheQuadratureWithoutRunningIt) {
  // The families' counting pass asks only "beta > 0"; its shortcut must agree with the
  // quadrature exactly, edge cases included (points on the sphere, 2D and 3D).
  uint64_t z = 7;
  auto uniform = [&z] { return split_mix_uniform(z); };
  int positive = 0, checked = 0;
  for (int dimension : {2, 3})
    for (int k = 0; k < 200000; ++k) {
      const double h = 0.3 + uniform(), delta = 3.0;
      double xi[3] = {(uniform() - 0.5) * 9.0, (uniform() - 0.5) * 9.0, dimension == 3 ? (uniform() - 0.5) * 9.0 : 0.0};
      if (k % 7 == 0) {  // on a lattice: sample points land exactly on the horizon
        for (int a = 0; a < dimension; ++a) xi[a] = std::round(xi[a] * 2.0) / 2.0;
      }
      const bool quadrature = partial_volume_sampled(xi, delta, k % 7 == 0 ? 0.5 : h, dimension) > 0.0;
      ASSERT_EQ(partial_volume_sampled_positive(xi, delta, k % 7 == 0 ? 0.5 : h, dimension), quadrature)
          << xi[0] << " " << xi[1] << " " << xi[2] << " h " << h;
      positive += quadrature;
      ++checked;
    }
  EXPECT_GT(positive, checked / 10);
  EXPECT_LT(positive, checked);
}

namespace {
// The plain quadrature: every sample point tested, the squares summed in the same order as
// partial_volume_samples_inside's.
int plain_sample_count(const double xi[3], double horizon, double half, int dimension) {
  constexpr int n = 6;
  const double h = 2.0 * half / n;
  int inside = 0;
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b)
      for (int c = 0; c < (dimension == 3 ? n : 1); ++c) {
        const double px = xi[0] - half + (a + 0.5) * h;
        const double py = xi[1] - half + (b + 0.5) * h;
        const double pz = dimension == 3 ? xi[2] - half + (c + 0.5) * h : xi[2];
        inside += (px * px + py * py + pz * pz <= horizon * horizon);
      }
  return inside;
}
}  // namespace

TEST(PartialVolume, SampleCountEqualsThePointByPointQuadrature) {
  // partial_volume_samples_inside squares each axis's 6 sample coordinates once and decides
  // whole rows of z samples by their smallest and largest square; the count must equal the
  // plain quadrature's (every point tested, the squares summed in the same order) exactly,
  // points on the sphere included, or the bond coefficients would change.
  const auto brute_force = plain_sample_count;
  uint64_t z = 11;
  auto uniform = [&z] { return split_mix_uniform(z); };
  int partial = 0;
  for (int dimension : {2, 3})
    for (int k = 0; k < 200000; ++k) {
      const bool lattice = k % 5 == 0;  // sample points land exactly on the horizon
      const double half = lattice ? 0.5 : 0.15 + 0.5 * uniform(), delta = 3.0;
      double xi[3] = {(uniform() - 0.5) * 9.0, (uniform() - 0.5) * 9.0, dimension == 3 ? (uniform() - 0.5) * 9.0 : 0.0};
      if (lattice)
        for (int a = 0; a < dimension; ++a) xi[a] = std::round(xi[a] * 2.0) / 2.0;
      // The early accept and reject by the cell's half diagonal are the plain quadrature's
      // too (partial_volume_sampled's definition): compare past them only.
      const double len = std::sqrt(xi[0] * xi[0] + xi[1] * xi[1] + xi[2] * xi[2]);
      const double reach = half * (dimension == 3 ? std::sqrt(3.0) : std::sqrt(2.0));
      if (len + reach <= delta || len - reach >= delta) continue;
      const int expected = brute_force(xi, delta, half, dimension);
      ASSERT_EQ(partial_volume_samples_inside(xi, delta, half, dimension), expected)
          << xi[0] << " " << xi[1] << " " << xi[2] << " half " << half << " dimension " << dimension;
      partial += expected > 0 && expected < partial_volume_sample_total(dimension);
    }
  EXPECT_GT(partial, 50000);  // the cases a row shortcut cannot settle alone are exercised

  // The per-thread memo of counts stands aside after a window of 4,096 full counts with few
  // hits and tries again later (partial_volume.cpp): a stream of distinct offsets (a graded
  // mesh) puts it to rest, then a few lattice offsets asked over and over (a lattice) are
  // looked up again. Every count on the way must be the quadrature's, whichever path gave it.
  const double lattice_offsets[4][3] = {{2.5, 1.0, 0.5}, {2.0, 2.0, 0.5}, {3.0, 0.0, 0.5}, {1.5, 2.5, 0.0}};
  for (int k = 0; k < 40 * 4096; ++k) {
    double xi[3] = {2.2 + 0.6 * uniform(), 0.8 + 0.4 * uniform(), 0.3 + 0.4 * uniform()};
    const double* x = k < 12 * 4096 ? xi : lattice_offsets[k % 4];
    ASSERT_EQ(partial_volume_samples_inside(x, 3.0, 0.5, 3), brute_force(x, 3.0, 0.5, 3)) << "call " << k;
  }
}

TEST(PartialVolume, PairCountsEqualTheTwoCountsOfItsEntries) {
  // partial_volume_pair_samples_inside (the set-up's count pass) forms the offset's length once
  // for both ends of a pair; each count must be partial_volume_samples_inside's for its entry,
  // (i -> j) at xi with i's horizon and j's cell and (j -> i) at -xi with j's horizon and i's
  // cell, and so the point-by-point quadrature's. Two horizons and two cells that differ (a
  // graded mesh), offsets over the half diagonal's early accept and reject and the samples' box,
  // lattice offsets among them (samples exactly on the sphere).
  uint64_t z = 23;
  auto uniform = [&z] { return split_mix_uniform(z); };
  int differ = 0, partial = 0;
  for (int dimension : {2, 3})
    for (int k = 0; k < 100000; ++k) {
      const bool lattice = k % 5 == 0;
      const double half_i = lattice ? 0.5 : 0.25 + 0.5 * uniform(), half_j = lattice ? 0.5 : 0.25 + 0.5 * uniform();
      const double horizon_i = lattice ? 3.0 : 6.0 * half_i * (0.9 + 0.2 * uniform());
      const double horizon_j = lattice ? 3.0 : 6.0 * half_j * (0.9 + 0.2 * uniform());
      double xi[3];
      for (int a = 0; a < 3; ++a)
        xi[a] = lattice ? std::floor(uniform() * 9.0) - 4.0 : (uniform() - 0.5) * 2.4 * std::max(horizon_i, horizon_j);
      if (dimension == 2) xi[2] = 0.0;
      const double xm[3] = {-xi[0], -xi[1], -xi[2]};
      int own = -1, reverse = -1;
      partial_volume_pair_samples_inside(xi, horizon_i, half_j, horizon_j, half_i, dimension, own, reverse);
      const int own_alone = partial_volume_samples_inside(xi, horizon_i, half_j, dimension);
      const int reverse_alone = partial_volume_samples_inside(xm, horizon_j, half_i, dimension);
      ASSERT_EQ(own, own_alone) << "case " << k << " dimension " << dimension;
      ASSERT_EQ(reverse, reverse_alone) << "case " << k << " dimension " << dimension;
      if (k % 50 == 0) {  // and the quadrature's, point by point (a sample of the cases)
        ASSERT_EQ(own, plain_sample_count(xi, horizon_i, half_j, dimension)) << "case " << k;
        ASSERT_EQ(reverse, plain_sample_count(xm, horizon_j, half_i, dimension)) << "case " << k;
      }
      differ += own != reverse;
      partial += own > 0 && own < partial_volume_sample_total(dimension);
    }
  // The two ends' counts differ often, so a horizon or a cell taken from the wrong end fails
  // (checked: either swap fails at the first case). (A reverse counted at +xi instead of -xi
  // is not caught: the mirrored cell's count equals it except on knife edges.)
  EXPECT_GT(differ, 20000);
  EXPECT_GT(partial, 20000);  // the full count is exercised, not only the early answers
}

TEST(PartialVolume, KnifeEdgeCountsEqualThePointByPointQuadrature) {
  // The count on the sphere: xi placed so that one sample's squared distance lies on it
  // (horizon 3, r^2 = 9 exactly), then moved 0-3 ulp either way along xi's largest axis, the
  // sample the nearest to the centre on every axis (k even: the samples' box's "wholly
  // outside" edge) or the farthest (k odd: "wholly inside"), 3D and 2D. Every count, whichever
  // body of count_every_sample the CPU runs (partial_volume.cpp), must be the plain
  // quadrature's exactly; the test fails if the box's "wholly outside" is decided on >= (a
  // sample on the sphere is inside: the quadrature's is <=).
  SplitMixUniform uniform{37};  // in [0, 1)
  const double delta = 3.0;
  int on_sphere = 0, partial = 0, per_axis[3] = {0, 0, 0};
  for (int dimension : {3, 2})
    for (int k = 0; k < 60000; ++k) {
      const int axis = dimension == 3 ? k % 3 : k % 2;  // xi's largest component
      const double half = 0.15 + 0.5 * uniform(), h = 2.0 * half / 6;
      int index[3];
      double p[3], xi[3] = {0.0, 0.0, 0.0};
      for (int d = 0; d < 3; ++d) {
        index[d] = static_cast<int>(6.0 * uniform());
        if (d == axis || (d == 2 && dimension == 2)) continue;
        xi[d] = (uniform() - 0.5) * 2.4;
        // The sample nearest the centre on this axis (k even) or the farthest (k odd).
        double best = k % 2 == 0 ? INFINITY : -1.0;
        for (int a = 0; a < 6; ++a) {
          const double q = xi[d] - half + (a + 0.5) * h;  // the sample's coordinate, as the count forms it
          if (k % 2 == 0 ? q * q < best : q * q > best) {
            best = q * q;
            index[d] = a;
          }
        }
        p[d] = xi[d] - half + (index[d] + 0.5) * h;
      }
      if (dimension == 2) p[2] = 0.0;
      double rest = 0.0;
      for (int d = 0; d < 3; ++d)
        if (d != axis) rest += p[d] * p[d];
      const double pe = (uniform() < 0.5 ? -1.0 : 1.0) * std::sqrt(delta * delta - rest);
      // Along xi's axis too the sample nearest the centre (k even) or the farthest (k odd):
      // every sample of the cell lies on pe's side of it (|pe| > 2.4, half cells under 0.65).
      index[axis] = ((pe > 0) == (k % 2 == 0)) ? 0 : 5;
      xi[axis] = pe + half - (index[axis] + 0.5) * h;
      const int ulps = static_cast<int>(7.0 * uniform()) - 3;
      for (int u = 0; u < std::abs(ulps); ++u) xi[axis] = std::nextafter(xi[axis], ulps > 0 ? 10.0 : -10.0);
      const double len = std::sqrt(xi[0] * xi[0] + xi[1] * xi[1] + xi[2] * xi[2]);
      const double reach = half * (dimension == 3 ? std::sqrt(3.0) : std::sqrt(2.0));
      if (len + reach <= delta || len - reach >= delta) continue;  // the definition's own early decisions
      const int expected = plain_sample_count(xi, delta, half, dimension);
      ASSERT_EQ(partial_volume_samples_inside(xi, delta, half, dimension), expected)
          << xi[0] << " " << xi[1] << " " << xi[2] << " half " << half << " dimension " << dimension;
      double s[3];
      for (int d = 0; d < 3; ++d) s[d] = xi[d] - half + (index[d] + 0.5) * h;
      if (dimension == 2) s[2] = xi[2];
      on_sphere += s[0] * s[0] + s[1] * s[1] + s[2] * s[2] == delta * delta;
      partial += expected > 0 && expected < partial_volume_sample_total(dimension);
      ++per_axis[axis];
    }
  EXPECT_GT(on_sphere, 5000) << "samples exactly on the sphere";
  EXPECT_GT(partial, 30000);
  for (int n : per_axis) EXPECT_GT(n, 10000);
}

TEST(PartialVolume, CountsLookedUpByRoundedOffsetEqualTheQuadrature) {
  // The memo keys a count by x_j - x_i rounded to 2^-30 horizons and keeps it only where no
  // sample lies within reach of the sphere (partial_volume.cpp): offsets of one lattice
  // offset that differ in their last bits, or by up to 0.4 grid steps, must get the
  // quadrature's count whichever of them was counted first. With half cell 0.5 the samples
  // of integer offsets lie at odd twelfths; at horizon sqrt(35^2 + 7^2 + 5^2) / 12 (3D) or
  // sqrt(35^2 + 11^2) / 12 (2D) some lie on the sphere, to rounding, so their counts change
  // with the last bits (never kept); at 3.015 none is near it (kept and looked up).
  SplitMixUniform centred{29};  // in [-0.5, 0.5)
  int differing = 0;  // jittered offsets whose count differs from their lattice offset's
  for (int dimension : {3, 2})
    for (double delta : {std::sqrt(dimension == 3 ? 1299.0 : 1346.0) / 12.0, 3.015})
      for (int pass = 0; pass < 3; ++pass)
        for (int a = -4; a <= 4; ++a)
          for (int b = -4; b <= 4; ++b)
            for (int c = (dimension == 3 ? -4 : 0); c <= (dimension == 3 ? 4 : 0); ++c) {
              const double base[3] = {double(a), double(b), double(c)};
              if (base[0] * base[0] + base[1] * base[1] + base[2] * base[2] == 0.0) continue;
              const int exact = plain_sample_count(base, delta, 0.5, dimension);
              for (int copy = 0; copy < 4; ++copy) {
                double xi[3];
                for (int axis = 0; axis < 3; ++axis) {
                  xi[axis] = base[axis];
                  if (axis == 2 && dimension != 3) continue;
                  if (copy % 2 == 0) {  // a few ulp either way, as x_j - x_i rounds on a lattice
                    const int ulps = static_cast<int>((centred() + 0.5) * 7.0) - 3;
                    for (int u = 0; u < std::abs(ulps); ++u) xi[axis] = std::nextafter(xi[axis], ulps > 0 ? 10.0 : -10.0);
                  } else {  // up to 0.4 grid steps
                    xi[axis] += centred() * 0.8 * 0x1p-30 * delta;
                  }
                }
                const int expected = plain_sample_count(xi, delta, 0.5, dimension);
                differing += expected != exact;
                ASSERT_EQ(partial_volume_samples_inside(xi, delta, 0.5, dimension), expected)
                    << xi[0] << " " << xi[1] << " " << xi[2] << " horizon " << delta << " dimension " << dimension;
              }
            }
  EXPECT_GT(differing, 0) << "the on-sphere offsets must include counts that the last bits change";
}

TEST(PartialVolume, LatticeTableCountsEqualTheQuadrature) {
  // A uniform lattice's set-up looks each candidate's count and its reverse's up by the integer
  // offset (LatticeSampleCounts, partial_volume.cpp), kept only where no sample lies within
  // reach of the sphere for offsets within 2^-24 spacings. Offsets a few ulp off a lattice
  // offset (x_j - x_i rounds so), up to 0.9 and 2 tolerances off it, and anywhere between
  // lattice offsets must get the plain quadrature's counts at xi and at -xi, exactly. At the
  // on-sphere horizons (sqrt(35^2 + 7^2 + 5^2) / 12 spacings in 3D, sqrt(35^2 + 11^2) / 12 in
  // 2D, some samples on the sphere to rounding) the last bits change some counts, which the
  // table must not have kept: the test fails when its margin check is removed. Spacing 1
  // and 0.5 mm (the benchmark's), at positions far from the origin too.
  SplitMixUniform centred{31};  // in [-0.5, 0.5)
  int differing = 0, checked = 0;
  for (int dimension : {3, 2})
    for (double spacing : {1.0, 0.0005})
      for (double factor : {std::sqrt(dimension == 3 ? 1299.0 : 1346.0) / 12.0, 3.015}) {
        const double half = 0.5 * spacing, delta = factor * spacing;
        const LatticeSampleCounts table(delta, half, dimension);
        const double tolerance = LatticeSampleCounts::kLatticeTolerance * spacing;
        for (int a = -5; a <= 5; ++a)
          for (int b = -5; b <= 5; ++b)
            for (int c = (dimension == 3 ? -5 : 0); c <= (dimension == 3 ? 5 : 0); ++c) {
              const double base[3] = {a * spacing, b * spacing, c * spacing};
              const int exact = plain_sample_count(base, delta, half, dimension);
              for (int copy = 0; copy < 5; ++copy) {
                double xi[3];
                for (int axis = 0; axis < 3; ++axis) {
                  xi[axis] = base[axis];
                  if (axis == 2 && dimension != 3) continue;
                  if (copy == 0) {  // a difference of two positions 1000 spacings out
                    const double origin = (1000.0 + centred()) * spacing;
                    xi[axis] = (origin + base[axis]) - origin;
                  } else if (copy == 1) {  // a few ulp either way
                    const int ulps = static_cast<int>((centred() + 0.5) * 7.0) - 3;
                    for (int u = 0; u < std::abs(ulps); ++u) xi[axis] = std::nextafter(xi[axis], ulps > 0 ? 1e9 : -1e9);
                  } else if (copy == 2) {
                    xi[axis] += 1.8 * centred() * tolerance;  // within the tolerance
                  } else if (copy == 3) {
                    xi[axis] += 4.0 * centred() * tolerance;  // partly beyond it: asked per call
                  } else {
                    xi[axis] += centred() * spacing;  // between lattice offsets
                  }
                }
                const double xm[3] = {-xi[0], -xi[1], -xi[2]};
                const int expected = plain_sample_count(xi, delta, half, dimension);
                differing += copy < 3 && expected != exact;
                int own = -1, reverse = -1;
                table.counts(xi, own, reverse);
                ASSERT_EQ(own, expected) << xi[0] << " " << xi[1] << " " << xi[2] << " horizon " << delta
                                         << " dimension " << dimension;
                ASSERT_EQ(reverse, plain_sample_count(xm, delta, half, dimension))
                    << xi[0] << " " << xi[1] << " " << xi[2] << " horizon " << delta << " dimension " << dimension;
                ++checked;
              }
            }
      }
  EXPECT_GT(differing, 0) << "the on-sphere offsets must include counts that the last bits change";
  EXPECT_GT(checked, 20000);
}
