// Correspondence (non-ordinary state-based) PD, docs/theory.md: the affine patch test (exact
// St Venant-Kirchhoff stress, no interior force) and a rigid rotation (no stress at all), with
// and without stabilisation, the P-wave speed, and the
// zero-energy modes: provoked without stabilisation, the run-time detector must stop the run
// and say so; with the penalty the same impact runs to the end.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <numbers>
#include <random>
#include <string>

#include "breccia/common/error.hpp"
#include "breccia/solver/calibration.hpp"
#include "breccia/solver/correspondence.hpp"
#include "breccia/solver/run.hpp"
#include "helpers.hpp"
#include "measures.hpp"

using namespace breccia::solver;
using namespace breccia::solver::testing;

namespace {

std::string stabilisation_yaml(const std::string& type) {
  return type == "none" ? "{type: none}" : "{type: penalty, coefficient: 1}";
}

// A one-step correspondence system on `specimen` (a YAML line), horizon 3.015 spacings, the
// stabilisation `type` and a rock of Young's modulus E and Poisson's ratio nu; `planar` is the
// model's `planar: ...,` entry (2D) or empty.
PdSystem correspondence_system(const std::string& name, const std::string& specimen, const std::string& planar,
                               const std::string& type, const std::string& E, const std::string& nu,
                               const std::string& density = "2600") {
  return system_from_yaml(name, specimen + "\nmodel: {type: correspondence, " + planar +
                                    "horizon_factor: 3.015, stabilisation: " + stabilisation_yaml(type) + "}\n"
                                    "materials: [{name: rock, density: " + density + ", youngs_modulus: " + E +
                                    ", poisson_ratio: " + nu + "}]\ntime: {steps: 1}\n");
}

// A small-strain field with shear and a rotation part (eps not symmetric): F must come out
// as I + eps exactly, the stress from the Green-Lagrange strain sym(eps) + eps^T eps / 2.
const double kEps[9] = {1.0e-4, 2.0e-5, -3.0e-5, -1.0e-5, -5.0e-5, 1.5e-5, 4.0e-5, -2.5e-5, 3.0e-5};

struct PatchResult {
  double worst_f = 0, worst_energy = 0, worst_interior_force = 0;
  int interior = 0;
};

// Affine u = eps x: every particle (surface ones too, K is built from the bonds it has)
// must have F = I + eps and W = classical W(E), E = sym(eps) + eps^T eps / 2 (the
// St Venant-Kirchhoff energy; it differs from W(sym eps) by about |eps| = 1e-4 relative, 1e5
// times the bound below); particles farther than two horizons
// from every face (their neighbours' families are complete too) carry no force.
PatchResult patch(PdSystem& s, const double* eps, double side) {
  impose_affine(s, eps);
  cpu_compute_forces(s);
  const int d = s.dimension;
  double green[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
  for (int a = 0; a < d; ++a)
    for (int b = 0; b < d; ++b) {
      double hh = 0.0;
      for (int c = 0; c < d; ++c) hh += eps[3 * c + a] * eps[3 * c + b];
      green[3 * a + b] = 0.5 * (eps[3 * a + b] + eps[3 * b + a]) + 0.5 * hh;
    }
  ElasticInput in;
  in.dimension = d;
  in.planar = s.config.planar;
  in.youngs_modulus = s.config.materials[0].youngs_modulus;
  in.poisson_ratio = s.config.materials[0].poisson_ratio;
  const double w_exact = classical_energy_density(in, green);
  const double force_scale = in.youngs_modulus * 1e-4 / s.horizon[0];  // sigma / delta
  PatchResult r;
  for (size_t i = 0; i < s.n; ++i) {
    for (int a = 0; a < d; ++a)
      for (int b = 0; b < d; ++b)
        r.worst_f = std::max(r.worst_f, std::fabs(s.corr_deformation[9 * i + 3 * a + b] - (a == b) - eps[3 * a + b]));
    r.worst_energy = std::max(r.worst_energy, std::fabs(s.energy_density[i] / w_exact - 1.0));
    double margin = 1e300;
    for (int a = 0; a < d; ++a) margin = std::min({margin, s.x0[3 * i + a], side - s.x0[3 * i + a]});
    if (margin <= 2.0 * s.horizon[i]) continue;
    ++r.interior;
    for (int a = 0; a < d; ++a) r.worst_interior_force = std::max(r.worst_interior_force, std::fabs(s.force[3 * i + a]) / force_scale);
  }
  return r;
}

}  // namespace

class CorrespondencePatch : public ::testing::TestWithParam<const char*> {};

// Round-off bounds: F and W are sums of ~100-500 terms of size |eps| (relative 1e-12 is
// ~1e4 x double epsilon); the interior force is a sum of terms of size sigma/delta that
// cancel by symmetry (1e-9 of one term).
TEST_P(CorrespondencePatch, AffineFieldGivesExactStressAndNoInteriorForceIn3D) {
  PdSystem s = correspondence_system(std::string("corr_patch3d_") + GetParam(),
                                     "specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.015, 0.015, 0.015], spacing: 1 mm}}",
                                     "", GetParam(), "50 GPa", "0.3");
  const PatchResult r = patch(s, kEps, 0.015);
  std::printf("3D patch (%s): max |F - I - eps| %.2e, max |W / W_exact - 1| %.2e, max interior |f| / (sigma/delta) %.2e over %d\n",
              GetParam(), r.worst_f, r.worst_energy, r.worst_interior_force, r.interior);
  EXPECT_LT(r.worst_f, 1e-12);
  EXPECT_LT(r.worst_energy, 1e-9);
  ASSERT_GT(r.interior, 0);
  EXPECT_LT(r.worst_interior_force, 1e-9);
}

TEST_P(CorrespondencePatch, AffineFieldGivesExactStressAndNoInteriorForceIn2D) {
  for (const char* planar : {"plane_stress", "plane_strain"}) {
    PdSystem s = correspondence_system(std::string("corr_patch2d_") + GetParam() + planar,
                                       "specimen: {lattice: {dimension: 2, box: [0, 0, 0.02, 0.02], spacing: 1 mm, thickness: 1 mm}}",
                                       "planar: " + std::string(planar) + ", ", GetParam(), "50 GPa", "0.2");
    const double eps2[9] = {1.0e-4, 3.0e-5, 0, -1.0e-5, -4.0e-5, 0, 0, 0, 0};
    const PatchResult r = patch(s, eps2, 0.02);
    std::printf("2D %s patch (%s): max |F - I - eps| %.2e, max |W / W_exact - 1| %.2e, max interior |f| / (sigma/delta) %.2e over %d\n",
                planar, GetParam(), r.worst_f, r.worst_energy, r.worst_interior_force, r.interior);
    EXPECT_LT(r.worst_f, 1e-12) << planar;
    EXPECT_LT(r.worst_energy, 1e-9) << planar;
    ASSERT_GT(r.interior, 0) << planar;
    EXPECT_LT(r.worst_interior_force, 1e-9) << planar;
  }
}

// Uniaxial strain column (lateral displacements held), fundamental free-free mode
// u = A cos(pi x / L): period 2L / c_p, c_p = sqrt((lambda + 2 mu) / rho) (plane strain:
// K_2 + mu). The wavelength (120 mm) is 80 horizons, where PD dispersion is far below 0.1 %;
// 1 % leaves room for timing the modal zero crossing within a step. The penalty must not change
// it: a cosine is affine to second order over a horizon.
TEST_P(CorrespondencePatch, PWaveSpeedInAColumnMatchesTheory) {
  PdSystem s = system_from_yaml(std::string("corr_pwave_") + GetParam(),
                                "specimen: {lattice: {dimension: 2, box: [0, 0, 0.06, 0.004], spacing: 0.5 mm, thickness: 1 mm}}\n"
                                "model: {type: correspondence, planar: plane_strain, horizon_factor: 3.015, stabilisation: " +
                                    stabilisation_yaml(GetParam()) + "}\n"
                                "materials: [{name: steel, density: 7850, youngs_modulus: 200 GPa, poisson_ratio: 0.25}]\n"
                                "time: {steps: 1}\n");
  for (auto& f : s.fixed_dof) f |= 2u;
  const double E = 200e9, nu = 0.25, rho = 7850;
  const double cp = std::sqrt(E * (1 - nu) / ((1 + nu) * (1 - 2 * nu)) / rho);
  // The atlas's measure: the modal amplitude's first zero crossing is a quarter period.
  const double error = breccia::atlas::fundamental_mode_speed_error(s, 0.06, cp);
  std::printf("correspondence P-wave (%s): |c / c_p - 1| = %.2e\n", GetParam(), error);
  EXPECT_LT(error, 0.01);
}

INSTANTIATE_TEST_SUITE_P(Stabilisation, CorrespondencePatch, ::testing::Values("none", "penalty"),
                         [](const ::testing::TestParamInfo<const char*>& info) { return std::string(info.param); });

namespace {

// Runs `s` to its end without writing results or progress, in a temporary folder of `name`.
RunResult run_quietly(PdSystem& s, const std::string& name) {
  s.config.write_results = false;
  RunOptions o;
  o.out_dir = process_temp_dir() + "/" + name;
  o.progress = false;
  return run_system(s, o);
}

// A free 2D plane-strain square (20 mm, dx 1 mm, m = 3) set moving in one of two ways that
// feed the particle-scale modes: "impact", one column starting at 5 m/s; "noise", random
// velocities (+-1 m/s per component, fixed seed) in every mode, the zero-energy ones too.
RunResult provoke(const std::string& scenario, const std::string& stabilisation, long long steps, double safety,
                  double* energy_change = nullptr) {
  const std::string initial = scenario == "impact" ? "initial: [{type: velocity, set: xmin, value: [5, 0, 0]}]\n" : "";
  PdSystem s = system_from_yaml("corr_" + scenario + "_" + stabilisation,
                                "specimen: {lattice: {dimension: 2, box: [0, 0, 0.02, 0.02], spacing: 1 mm, thickness: 1 mm}}\n"
                                "model: {type: correspondence, planar: plane_strain, horizon_factor: 3.015, stabilisation: " +
                                    stabilisation_yaml(stabilisation) + "}\n"
                                "materials: [{name: rock, density: 2600, youngs_modulus: 50 GPa, poisson_ratio: 0.25}]\n" +
                                    initial + "time: {steps: " + std::to_string(steps) + ", safety: " + std::to_string(safety) +
                                    "}\n"
                                "output: {every: 1000000, history_every: 5, fields: [damage]}\n");
  if (scenario == "noise") {
    std::mt19937_64 rng(20071);
    std::uniform_real_distribution<double> uni(-1.0, 1.0);
    for (size_t i = 0; i < s.n; ++i)
      for (int d = 0; d < 2; ++d) s.v[3 * i + d] = uni(rng);
  }
  const Energies e0 = measure(s);
  RunResult r = run_quietly(s, "corr_" + scenario + "_" + stabilisation);
  if (energy_change) *energy_change = (r.final_energies.kinetic + r.final_energies.strain) / (e0.kinetic + e0.strain) - 1.0;
  return r;
}

void expect_zero_energy_message(const RunResult& r, long long steps) {
  EXPECT_EQ(r.status, "unstable");
  EXPECT_LT(r.steps, steps) << "the detector must stop the run early";
  EXPECT_NE(r.message.find("zero-energy (hourglass) modes"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("model.stabilisation: {type: penalty"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("last good output is kept"), std::string::npos) << r.message;
}

}  // namespace

// Measured (docs/atlas.md, correspondence map, m = 3): without stabilisation the non-affine
// ratio reaches ~500 under noise (limit 1) and ~1.5-2.6 after the impact (first above 1 at
// step 15), against <= 0.71 and <= 0.47 with G = 1.
TEST(CorrespondenceZeroEnergyModes, UnstabilisedNoiseIsStoppedByTheZeroEnergyDetector) {
  expect_zero_energy_message(provoke("noise", "none", 400, 0.8), 400);
}

TEST(CorrespondenceZeroEnergyModes, UnstabilisedImpactIsStoppedByTheZeroEnergyDetector) {
  expect_zero_energy_message(provoke("impact", "none", 400, 0.8), 400);
}

// With G = 1 the ratio is bounded by 1/G by energy conservation: both provocations run to the
// end. The impact at a quarter of the stable step also checks that the penalty conserves
// energy (it is exactly the derivative of its energy): measured +1 % over 1000 steps, all of
// it velocity Verlet's shadow-energy offset of the initial particle-scale velocity jump (at
// safety 0.8 the same offset is +20 % for LPS too); 2 % bounds it.
TEST(CorrespondenceZeroEnergyModes, StabilisedImpactRunsToTheEndConservingEnergy) {
  double change = 0;
  const RunResult r = provoke("impact", "penalty", 1000, 0.2, &change);
  EXPECT_EQ(r.status, "completed") << r.message;
  EXPECT_EQ(r.steps, 1000);
  EXPECT_LT(std::fabs(change), 0.02);
}

TEST(CorrespondenceZeroEnergyModes, StabilisedNoiseRunsToTheEndWithoutTrippingTheDetector) {
  const RunResult r = provoke("noise", "penalty", 400, 0.8);
  EXPECT_EQ(r.status, "completed") << r.message;
  EXPECT_EQ(r.steps, 400);
}

TEST(CorrespondenceInput, StabilisationWithAnOrdinaryModelIsRefused) {
  try {
    system_from_yaml("corr_bad_model",
                     "specimen: {lattice: {dimension: 2, box: [0, 0, 0.01, 0.01], spacing: 1 mm}}\n"
                     "model: {type: lps, planar: plane_strain, stabilisation: {type: penalty}}\n"
                     "materials: [{density: 2600, youngs_modulus: 50 GPa}]\ntime: {steps: 1}\n");
    FAIL() << "stabilisation with lps must be refused";
  } catch (const breccia::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("model.stabilisation"), std::string::npos) << e.what();
  }
  try {
    system_from_yaml("corr_bad_coefficient",
                     "specimen: {lattice: {dimension: 2, box: [0, 0, 0.01, 0.01], spacing: 1 mm}}\n"
                     "model: {type: correspondence, planar: plane_strain, stabilisation: {type: none, coefficient: 1}}\n"
                     "materials: [{density: 2600, youngs_modulus: 50 GPa}]\ntime: {steps: 1}\n");
    FAIL() << "a coefficient with type: none must be refused, not ignored";
  } catch (const breccia::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("coefficient"), std::string::npos) << e.what();
  }
}

#ifdef BRECCIA_SOLVE_EXE
// The same unstabilised impact through breccia-solve: exit code 3, the message on stderr, and
// the history up to the last good step kept.
TEST(CorrespondenceZeroEnergyModes, CliExitsWithCodeThreeAndKeepsTheHistory) {
  const std::string dir = process_temp_dir() + "/corr_cli";
  const std::string file = write_case("corr_cli",
      "specimen: {lattice: {dimension: 2, box: [0, 0, 0.02, 0.02], spacing: 1 mm, thickness: 1 mm}}\n"
      "model: {type: correspondence, planar: plane_strain, stabilisation: {type: none}}\n"
      "materials: [{name: rock, density: 2600, youngs_modulus: 50 GPa, poisson_ratio: 0.25}]\n"
      "initial: [{type: velocity, set: xmin, value: [5, 0, 0]}]\n"
      "time: {steps: 400}\n"
      "output: {every: 1000000, history_every: 5, fields: [damage]}\n");
  const std::string cmd = std::string(BRECCIA_SOLVE_EXE) + " " + file + " -o " + dir + " --quiet --backend cpu 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  ASSERT_NE(p, nullptr);
  std::string out;
  char buf[512];
  while (fgets(buf, sizeof buf, p)) out += buf;
  const int status = pclose(p);
  EXPECT_EQ(WEXITSTATUS(status), 3) << out;
  EXPECT_NE(out.find("zero-energy (hourglass) modes"), std::string::npos) << out;
  std::ifstream history(dir + "/history.csv");
  ASSERT_TRUE(history.good());
  int lines = 0;
  for (std::string line; std::getline(history, line);) ++lines;
  EXPECT_GE(lines, 2) << "header and at least the initial state";
}
#endif

// Objectivity (docs/theory.md, "Correspondence"): a rigid rotation must leave the body
// unstressed. u = (R - I) x turns a 3D block by 30 degrees about (1, 1, 1) and a 2D square by
// 30 degrees about z: every particle's F is R (to round-off), so the strain measure, the
// energy density and every force, surface particles' included, vanish. With the small strain
// sym(F) - I the turn reads as a compression of 1 - cos 30 = 13 % in the plane of rotation:
// about 0.1 E of stress, its traction on every surface particle. Bounds: F's entries are sums
// of ~100-500 terms of size 1 (1e-12 is ~1e4 ulp); the energy density against E (1e-20: the
// square of a 1e-10 strain) and the force against E / delta (1e-9).
TEST_P(CorrespondencePatch, ARigidRotationLeavesTheBodyUnstressed) {
  const double theta = std::numbers::pi / 6, c = std::cos(theta), s_ = std::sin(theta);
  for (int dimension : {3, 2}) {
    const std::string specimen = dimension == 3
                                     ? "specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.012, 0.012, 0.012], spacing: 1 mm}}"
                                     : "specimen: {lattice: {dimension: 2, box: [0, 0, 0.02, 0.02], spacing: 1 mm, thickness: 1 mm}}";
    const std::string planar = dimension == 3 ? "" : "planar: plane_strain, ";
    PdSystem s = correspondence_system(std::string("corr_rotation_") + std::to_string(dimension) + GetParam(), specimen,
                                       planar, GetParam(), "50 GPa", "0.3");
    // R about the unit axis n (Rodrigues); 2D: n = z.
    const double k = dimension == 3 ? 1.0 / std::sqrt(3.0) : 0.0;
    const double n[3] = {k, k, dimension == 3 ? k : 1.0};
    double R[9];
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        const int e = 3 - a - b;  // the third index when a != b
        const double cross = a == b ? 0.0 : ((b == (a + 1) % 3) ? -n[e] : n[e]);
        R[3 * a + b] = (a == b ? c : 0.0) + (1 - c) * n[a] * n[b] + s_ * cross;
      }
    double turn[9];
    for (int q = 0; q < 9; ++q) turn[q] = R[q] - (q % 4 == 0 ? 1.0 : 0.0);
    impose_affine(s, turn);
    cpu_compute_forces(s);
    const double E = 50e9, force_scale = E / s.horizon[0];
    double worst_f = 0, worst_w = 0, worst_force = 0;
    for (size_t i = 0; i < s.n; ++i) {
      for (int a = 0; a < dimension; ++a)
        for (int b = 0; b < dimension; ++b)
          worst_f = std::max(worst_f, std::fabs(s.corr_deformation[9 * i + 3 * a + b] - R[3 * a + b]));
      worst_w = std::max(worst_w, std::fabs(s.energy_density[i]) / E);
      for (int a = 0; a < 3; ++a) worst_force = std::max(worst_force, std::fabs(s.force[3 * i + a]) / force_scale);
    }
    std::printf("%dD rigid rotation of 30 deg (%s): max |F - R| %.2e, max W / E %.2e, max |f| / (E/delta) %.2e\n",
                dimension, GetParam(), worst_f, worst_w, worst_force);
    EXPECT_LT(worst_f, 1e-12) << dimension << "D";
    EXPECT_LT(worst_w, 1e-20) << dimension << "D";
    EXPECT_LT(worst_force, 1e-9) << dimension << "D";
  }
}

// The same in motion: a free 2D square (20 mm, dx 1 mm) set spinning as a rigid body about its
// centre, at a rate whose centrifugal stress rho omega^2 R^2 is 1e-5 E, turns a quarter turn
// and keeps its shape: its diagonal stays within the spin's strain (~1e-5; bound 1e-4) and
// its corner moves by the quarter turn's chord (bound 1e-3). The small strain sym(F) - I
// measured no strain at all in u = t omega x r, the rigid motion's linear part, so under it
// every particle flew off along its tangent without resistance: at the quarter turn the
// square had grown by the factor sqrt(1 + (pi/2)^2) = 1.86 with zero strain energy, its corner
// 1.111 chords from where it started. Also: the energy density stays at the spin's (~5e-11 E,
// twice that while the suddenly applied centrifugal load rings; bound 1e-8 E), angular
// momentum to round-off (P F^T is symmetric: sums over ~1e4 steps, 1e-10 relative) and the
// total energy of velocity Verlet within 1e-6 (measured 1e-9 to 5e-8, the step's O(dt^2)).
TEST_P(CorrespondencePatch, ASpinningBodyTurnsAQuarterTurnUnstressed) {
  PdSystem s = correspondence_system(std::string("corr_spin_") + GetParam(),
                                     "specimen: {lattice: {dimension: 2, box: [0, 0, 0.02, 0.02], spacing: 1 mm, thickness: 1 mm}}",
                                     "planar: plane_strain, ", GetParam(), "50 GPa", "0.25");
  const double E = 50e9, rho = 2600, centre = 0.01;
  const double radius = centre * std::sqrt(2.0), omega = std::sqrt(1e-5 * E / rho) / radius;
  for (size_t i = 0; i < s.n; ++i) {
    s.v[3 * i] = -omega * (s.x0[3 * i + 1] - centre);
    s.v[3 * i + 1] = omega * (s.x0[3 * i] - centre);
  }
  auto angular = [&] {
    double L = 0.0;
    for (size_t i = 0; i < s.n; ++i) {
      const double m = s.density[i] * s.volume[i];
      const double x = s.x0[3 * i] + s.u[3 * i] - centre, y = s.x0[3 * i + 1] + s.u[3 * i + 1] - centre;
      L += m * (x * s.v[3 * i + 1] - y * s.v[3 * i]);
    }
    return L;
  };
  const double L0 = angular();
  const Energies e0 = measure(s);
  long long steps = 0;
  while (s.time < 0.5 * std::numbers::pi / omega) {
    cpu_step(s);
    ++steps;
  }
  const Energies e1 = measure(s);
  auto diagonal = [&](bool current) {
    const int64_t a = nearest(s, 0.0005, 0.0005, 0), b = nearest(s, 0.0195, 0.0195, 0);
    double d2 = 0.0;
    for (int q = 0; q < 2; ++q) {
      const double e = s.x0[3 * b + q] - s.x0[3 * a + q] + (current ? s.u[3 * b + q] - s.u[3 * a + q] : 0.0);
      d2 += e * e;
    }
    return std::sqrt(d2);
  };
  double worst_w = 0.0;
  for (size_t i = 0; i < s.n; ++i) worst_w = std::max(worst_w, std::fabs(s.energy_density[i]) / E);
  const int64_t corner = nearest(s, 0.0005, 0.0005, 0);
  const double moved = std::hypot(s.u[3 * corner], s.u[3 * corner + 1]);
  const double chord = std::sqrt(2.0) * std::hypot(s.x0[3 * corner] - centre, s.x0[3 * corner + 1] - centre);
  const double energy_change = (e1.kinetic + e1.strain) / (e0.kinetic + e0.strain) - 1.0;
  const double stretch = diagonal(true) / diagonal(false) - 1.0;
  std::printf("spin (%s): %lld steps, diagonal stretched %.2e, corner moved %.5f of its chord, max W / E %.2e, "
              "L change %.2e, energy change %.2e\n",
              GetParam(), steps, stretch, moved / chord, worst_w, angular() / L0 - 1.0, energy_change);
  EXPECT_NEAR(stretch, 0.0, 1e-4);
  EXPECT_NEAR(moved / chord, 1.0, 1e-3);
  EXPECT_LT(worst_w, 1e-8);
  EXPECT_NEAR(angular() / L0, 1.0, 1e-10);
  EXPECT_NEAR(energy_change, 0.0, 1e-6);
}

// The pre-cracked glass plate of the PMB restart test as a correspondence plate with the
// penalty, under a gentler load (5 MPa ramped over 2 us: the PMB deck's sudden 20 MPa makes
// the correspondence plate blow up within 20 steps, before and after St Venant-Kirchhoff);
// its crack grows (about 600 bonds break in 400 steps).
// `load` over `ramp` and `model_extra` (", key: value" entries of the model) as given.
std::string correspondence_plate_deck(const std::string& time, const std::string& load = "5 MPa",
                                      const std::string& ramp = "2 us", const std::string& model_extra = "") {
  std::string deck = kPrecrackedGlassPlateDeck;
  auto swap = [&deck](const std::string& from, const std::string& to) { deck.replace(deck.find(from), from.size(), to); };
  swap("model: {type: pmb, planar: plane_stress, horizon_factor: 3.015}",
       "model: {type: correspondence, planar: plane_stress, horizon_factor: 3.015, "
       "stabilisation: {type: penalty, coefficient: 1}" + model_extra + "}");
  const std::string history = ", history: {type: ramp, value: 1, ramp_time: " + ramp + "}}";
  swap("value: [0, 20 MPa, 0]}", "value: [0, " + load + ", 0]" + history);
  swap("value: [0, -20 MPa, 0]}", "value: [0, -" + load + ", 0]" + history);
  return deck + time + "output: {every: 100, history_every: 20}\n";
}

// A correspondence run stopped at its checkpoint and continued equals the straight run bit for
// bit (F and A_i are recomputed from u at every pass; the checkpoint holds u, v, the forces and
// the bond states).
TEST(CorrespondenceRestart, HalfRunsWithACheckpointEqualOneStraightRunBitForBit) {
  const CaseConfig config = parse_case_file(write_case("corr_restart", correspondence_plate_deck("time: {steps: 400}\n")));
  auto [straight, second] = straight_and_restarted(config, "corr_restart", 200);
  const long long broken = measure(straight).broken_half_bonds;
  std::printf("correspondence restart: %lld broken half-bonds, dissipated %.4e J\n", broken, straight.dissipated_energy);
  ASSERT_GT(broken, 0) << "the case should break bonds";
  expect_same_motion(second, straight);
  EXPECT_EQ(second.dissipated_energy, straight.dissipated_energy);
}

// A blow-up is stopped although its breaks book what it puts in the bonds. The same plate at
// 1.5 times the stable step grows a mode; correspondence's breaks book the drop of each
// particle's energy, which the growing mode makes as large as it likes, so the energy the
// solver created sits in the dissipated column (6e11 J by step 20, measured). The check judges
// kinetic + strain + dissipated against the work supplied; with the dissipation counted as
// supplied (the check before 2026-12-07) this run went on to its end with every bond broken.
TEST(CorrespondenceFracture, ABlowUpIsStoppedAlthoughItsBreaksBookItsEnergy) {
  PdSystem s = system_from_yaml("corr_blowup", correspondence_plate_deck("time: {steps: 400, safety: 1.5, check_stability: false}\n"));
  const RunResult r = run_quietly(s, "corr_blowup");
  std::printf("blow-up: status %s at step %lld: %s\n", r.status.c_str(), r.steps, r.message.substr(0, 160).c_str());
  EXPECT_EQ(r.status, "unstable");
  EXPECT_LT(r.steps, 400);
  EXPECT_NE(r.message.find("grew beyond 10x the energy supplied"), std::string::npos) << r.message;
}

// model.stress_damage_limit: a particle whose family has lost more than half its own volume
// carries no stress, and crossing the limit is booked as a break. The plate at 10 MPa over
// 5 us runs away without it (stopped at step 20, docs/theory.md "A break can raise the
// energy") and with it runs its 400 steps, pulled apart, the books closed: measured
// (2026-12-07) 0.1 % of the work at the end (4.2 % at worst on the way, the first-order error
// of sudden breaks at this step, as on the DCB). Bound 2 %. The DCB's slow crack is the same
// bits with and without the limit at 0.5 (no particle there loses half its family).
TEST(CorrespondenceFracture, AStressLimitKeepsASuddenlyLoadedCrackStable) {
  for (const bool limit : {false, true}) {
    PdSystem s = system_from_yaml(limit ? "corr_limit" : "corr_no_limit",
                                  correspondence_plate_deck("time: {steps: 400}\n", "10 MPa", "5 us",
                                                            limit ? ", stress_damage_limit: 0.5" : ""));
    const RunResult r = run_quietly(s, limit ? "corr_limit" : "corr_no_limit");
    const Energies& e = r.final_energies;
    const double imbalance = (e.kinetic + e.strain + s.dissipated_energy - s.external_work) / s.external_work;
    std::printf("plate at 10 MPa, limit %s: %s at step %lld, work %.3e J, imbalance %.2e\n", limit ? "0.5" : "none",
                r.status.c_str(), r.steps, s.external_work, imbalance);
    if (!limit) {
      EXPECT_EQ(r.status, "unstable") << "the case no longer runs away without the limit: find another";
      continue;
    }
    EXPECT_EQ(r.status, "completed") << r.message;
    EXPECT_EQ(r.steps, 400);
    EXPECT_GT(measure(s).broken_half_bonds, 0);
    EXPECT_LT(std::abs(imbalance), 0.02);
  }
}

TEST(CorrespondenceInput, StressDamageLimitOutsideCorrespondenceOrOutOfRangeIsRefused) {
  for (const auto& [model, value] : {std::pair{"lps", "0.5"}, std::pair{"correspondence", "1"}}) {
    try {
      system_from_yaml(std::string("corr_bad_limit_") + model,
                       "specimen: {lattice: {dimension: 2, box: [0, 0, 0.01, 0.01], spacing: 1 mm}}\n"
                       "model: {type: " + std::string(model) + ", planar: plane_strain, stress_damage_limit: " + value +
                           "}\nmaterials: [{density: 2600, youngs_modulus: 50 GPa}]\ntime: {steps: 1}\n");
      FAIL() << "stress_damage_limit " << value << " with " << model << " must be refused";
    } catch (const breccia::InputError& e) {
      EXPECT_NE(std::string(e.what()).find("model.stress_damage_limit"), std::string::npos) << e.what();
    }
  }
}
