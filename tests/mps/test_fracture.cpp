// Brittle fracture of the stress-based MPS solid with the separation tensor (fracture.hpp):
// spall of a reflected pulse at the place and time of 1D wave theory, crack normals along
// the principal direction on a lattice whose bonds are 13 degrees off it, no separation
// from the unbalanced (inertial) forces of surface particles, and the case keys.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "breccia/common/error.hpp"
#include "breccia/mps/case_spec.hpp"
#include "breccia/mps/solid.hpp"
#include "breccia/mps/solid_case.hpp"
#include "mps_test_util.hpp"

using namespace breccia::mps;
using std::numbers::pi;

namespace {

// nu = 0: no Poisson coupling, so a strip under uniaxial strain along x is in uniaxial
// stress and 1D bar theory holds exactly (E = lambda + 2 mu = 2 mu, c = sqrt(E/rho)).
constexpr double kYoung = 1e9, kDensity = 1000.0, kStrength = 1e6;
const double kWaveSpeed = std::sqrt(kYoung / kDensity);  // 1000 m/s

// The rate-form elastic law, as a case with fracture runs by default (case_spec.cpp: a cut
// keeps the particle's stress and re-measures its gradient on the cut stencil, which only
// the rate law carries across; docs/mps.md "Elastic law").
SolidLaw brittle_law() {
  SolidLaw law;
  law.lame_lambda_pa = 0.0;
  law.shear_modulus_pa = 0.5 * kYoung;
  law.elastic = ElasticLaw::Rate;
  return law;
}

Solid make_brittle(const std::vector<double>& pos, double h, double strength) {
  SolidOptions opt;
  opt.dimension = 2;
  opt.spacing_m = h;
  opt.thickness_m = h;
  Solid solid(pos, std::vector<double>(pos.size() / 3, h * h * h), kDensity, brittle_law(), opt);
  solid.set_fracture({strength});
  return solid;
}

// Smooth step 0 -> 1 over [0, w] (half cosine).
double ramp(double s, double w) { return s <= 0 ? 0.0 : s >= w ? 1.0 : 0.5 * (1.0 - std::cos(pi * s / w)); }

}  // namespace

// ---------------------------------------------------------------------------------------
// (a) Spall. A compressive pulse (amplitude 1.5 x strength, plateau between half-height
// points lc = 40 h, half-cosine edges of width w = 8 h) runs along a free strip and
// reflects at the free right end as tension. 1D theory: net tension first appears where
// the reflected head meets the incident tail, half the pulse length from the end,
// x_s = L - lc/2; there the stress is sigma_p (2 R - 1) with R the edge profile a time tau
// after both half-height points cross, so sigma_f = (2/3) sigma_p is reached at
// R = 5/6, i.e. c tau = (acos(-2/3)/pi - 1/2) w = 0.232 w, and t_s = (x_s - a)/c + tau
// (a: the incident tail's half-height point at t = 0). Points off x_s reach it later.
TEST(MpsFracture, SpallOfAReflectedPulseAtThePlaceAndTimeOfWaveTheory) {
  const double h = 1e-3;
  const int nx = 200, ny = 6;
  const double length = nx * h;
  const std::vector<double> pos = breccia::mps::test::lattice(2, nx, ny, 1, h);
  Solid solid = make_brittle(pos, h, kStrength);
  const double sigma_p = 1.5 * kStrength, strain = sigma_p / kYoung;
  const double w = 8 * h, lc = 40 * h, a = 30 * h;  // tail half-height point at x = a
  // Right-travelling pulse: strain eps(x) = -strain g(x), velocity v = c strain g(x),
  // displacement u(x) = strain * integral_x^inf g (positive behind the pulse).
  auto g = [&](double x) { return ramp(x - (a - w / 2), w) * (1.0 - ramp(x - (a + lc - w / 2), w)); };
  const int fine = 4000;
  std::vector<double> cumulative(fine + 1, 0.0);  // integral of g from x_k to L
  for (int k = fine - 1; k >= 0; --k) {
    const double x0 = length * k / fine, x1 = length * (k + 1) / fine;
    cumulative[k] = cumulative[k + 1] + 0.5 * (g(x0) + g(x1)) * (x1 - x0);
  }
  for (size_t i = 0; i < solid.size(); ++i) {
    const double x = pos[3 * i];
    const double t = x / length * fine;
    const int k = std::min(fine - 1, static_cast<int>(t));
    const double integral = cumulative[k] + (cumulative[k + 1] - cumulative[k]) * (t - k);
    solid.displacement(0)[i] = strain * integral;
    solid.velocity(0)[i] = kWaveSpeed * strain * g(x);
  }
  const double x_spall = length - lc / 2;
  const double tau = (std::acos(-2.0 / 3.0) / pi - 0.5) * w / kWaveSpeed;
  const double t_spall = (x_spall - a) / kWaveSpeed + tau;
  const FractureModel& fr = *solid.fracture();
  while (fr.failed_particles() == 0 && solid.time_s() < 1.3 * t_spall) solid.step();
  ASSERT_GT(fr.failed_particles(), 0) << "no failure by 1.3 t_spall";
  double t_first = 1e300, x_first = 0;
  for (size_t i = 0; i < solid.size(); ++i)
    if (fr.failures()[i] > 0) {
      t_first = std::min(t_first, fr.first_failure_time_s()[i]);
      x_first = pos[3 * i];
    }
  // Tolerances: the free end of the particle strip lies within half a spacing of L, the
  // lattice's dispersion (c_L -1% at 24 points per wavelength, docs/mps.md) and the 8 h
  // edges smear the meeting point by about a spacing: 3 h in place, 4 h / c in time
  // (3% of the 150 h flight).
  EXPECT_NEAR(x_first, x_spall, 3 * h);
  EXPECT_NEAR(t_first, t_spall, 4 * h / kWaveSpeed);
  std::printf("spall: first failure x = %.1f h (theory %.1f h), t = %.2f us (theory %.2f us)\n", x_first / h,
              x_spall / h, t_first * 1e6, t_spall * 1e6);
  // Let the crack run across the strip: every row must fail near x_s, normals along x.
  const double t_end = t_first + 10 * h / kWaveSpeed;
  while (solid.time_s() < t_end) solid.step();
  std::vector<int> row_failed(ny, 0);
  for (size_t i = 0; i < solid.size(); ++i) {
    if (fr.failures()[i] == 0) continue;
    const auto& n = fr.first_normal()[i];
    // Uniaxial tension: the separation tensor is s n n^T with n = e_x before any crack;
    // particles that fail once part of the section has cracked also see the crack tip's
    // field (measured: up to 2.9 deg), hence 5 degrees.
    EXPECT_GT(std::fabs(n[0]), std::cos(5.0 * pi / 180)) << "particle " << i << " normal " << n[0] << "," << n[1];
    EXPECT_NEAR(pos[3 * i], x_spall, 4 * h) << "particle " << i << " failed away from the spall plane";
    row_failed[static_cast<int>(pos[3 * i + 1] / h)] = 1;
  }
  for (int r = 0; r < ny; ++r) EXPECT_EQ(row_failed[r], 1) << "row " << r << " did not fail";
}

// ---------------------------------------------------------------------------------------
// (b) Crack normals follow the principal direction, not the bonds. A square lattice rotated
// by half of atan(1/2) (13.28 deg: the nearest bond direction of the re = 2.1 stencil,
// which holds bonds at 0, 26.6, 45, ... deg to the lattice axes, is 13.28 deg from x) is
// cut to a bar along x and stretched at a uniform strain rate (initial v_x = rate x). Until
// the release waves from the ends arrive, the middle is in uniaxial stress E rate t, so
// particles fail at t_f = strength / (E rate) with crack normals along x.
TEST(MpsFracture, CrackNormalsFollowThePrincipalDirectionNotTheBonds) {
  const double h = 1e-3, half_x = 30 * h, half_y = 8 * h;
  const double theta = 0.5 * std::atan(0.5);
  std::vector<double> pos;
  for (int i = -60; i <= 60; ++i)
    for (int j = -60; j <= 60; ++j) {
      const double x = (i + 0.25) * h * std::cos(theta) - (j + 0.25) * h * std::sin(theta);
      const double y = (i + 0.25) * h * std::sin(theta) + (j + 0.25) * h * std::cos(theta);
      if (std::fabs(x) < half_x && std::fabs(y) < half_y) pos.insert(pos.end(), {x, y, 0.0});
    }
  Solid solid = make_brittle(pos, h, kStrength);
  // t_f = 10 h / c: the release waves from the ends (30 h away) leave |x| < 20 h uniform.
  const double t_f = 10 * h / kWaveSpeed, rate = kStrength / (kYoung * t_f);
  for (size_t i = 0; i < solid.size(); ++i) solid.velocity(0)[i] = rate * pos[3 * i];
  const FractureModel& fr = *solid.fracture();
  // The core (|x| < 18 h, |y| < 4 h) stays uniform until t_f. The staircase y surfaces of
  // the rotated lattice are not: their particles carry a discrete surface traction that
  // is not quite zero, and the stress there peaks 13% above the core's (measured), so a
  // few surface particles fail at about 0.9 t_f; their cracks need several spacings of
  // wave travel to reach the core.
  auto core = [&](size_t i) { return std::fabs(pos[3 * i]) < 18 * h && std::fabs(pos[3 * i + 1]) < 4 * h; };
  auto core_first = [&]() {
    double t = 1e300;
    for (size_t i = 0; i < solid.size(); ++i)
      if (core(i) && fr.failures()[i] > 0) t = std::min(t, fr.first_failure_time_s()[i]);
    return t;
  };
  while (core_first() > 1e299 && solid.time_s() < 2 * t_f) solid.step();
  double t_any = 1e300;
  for (double t : fr.first_failure_time_s())
    if (t >= 0) t_any = std::min(t_any, t);
  EXPECT_GT(t_any, 0.85 * t_f) << "staircase-surface failures earlier than the measured 13% stress excess";
  // The first core failure is the first time the (incrementally integrated, i.e.
  // logarithmic: 5e-4 below E eps here) stress reaches the strength: t_f within one step.
  const double t_first = core_first();
  EXPECT_GE(t_first, t_f * (1 - 1e-9));
  EXPECT_LE(t_first, t_f * (1 + 1e-3) + solid.dt_s());
  int checked = 0;
  double worst_deg = 0.0;
  for (size_t i = 0; i < solid.size(); ++i) {
    if (fr.failures()[i] == 0 || !core(i)) continue;
    if (fr.first_failure_time_s()[i] > t_first + 0.5 * solid.dt_s()) continue;  // later ones see crack tips
    const auto& n = fr.first_normal()[i];
    worst_deg = std::max(worst_deg, std::acos(std::min(1.0, std::fabs(n[0]))) * 180 / pi);
    ++checked;
  }
  std::printf("rotated lattice: %d first-step failures, worst normal %.2e deg off x (bonds: 13.28 deg)\n", checked,
              worst_deg);
  EXPECT_GE(checked, 5);
  // In exact uniaxial stress every bond force is parallel to x and the separation tensor is
  // s x x^T, normal x to rounding. The core is not exactly uniaxial: in the 10 h / c before
  // t_f the staircase surfaces 4 h away radiate small shear stresses into it (measured
  // worst 0.59 deg). 2 degrees is still 6x below the 13.28 deg of the nearest bond, which a
  // bond-wise criterion would follow.
  EXPECT_LT(worst_deg, 2.0);
}

// ---------------------------------------------------------------------------------------
// (c) The inertial part is removed. A free block given an affine stretch eps along x has
// the uniform Hooke stress E eps at every particle (the corrected gradient is exact for
// linear fields, surfaces included), but the particles of the two x faces are pulled by
// their bonds to one side only: that unbalanced force accelerates them (it is the inertial
// part) and the separation tensor removes it. Interior particles carry S = E eps exactly;
// with the strength at 0.9 E eps the interior fails while the x-face particles, whose
// stress is just as far above the strength, do not (the thesis' "surface particles do not
// scatter").
TEST(MpsFracture, UnbalancedSurfaceForcesDoNotSeparate) {
  const double h = 1e-3, eps = 1e-3;
  const int nx = 20, ny = 20;
  const std::vector<double> pos = breccia::mps::test::lattice(2, nx, ny, 1, h);
  Solid solid = make_brittle(pos, h, 0.9 * kYoung * eps);
  for (size_t i = 0; i < solid.size(); ++i) solid.displacement(0)[i] = eps * pos[3 * i];
  solid.step();  // the stress update and the separation are evaluated on the initial state
  const FractureModel& fr = *solid.fracture();
  const double sigma0 = kYoung * eps;
  double face_worst = 0.0, corner_worst = 0.0;
  int interior = 0;
  for (size_t i = 0; i < solid.size(); ++i) {
    EXPECT_NEAR(solid.stress_pa()[i].xx, sigma0, 1e-9 * sigma0) << "Hooke stress at particle " << i;
    const int col = static_cast<int>(pos[3 * i] / h), row = static_cast<int>(pos[3 * i + 1] / h);
    const bool x_face = col == 0 || col == nx - 1;
    const bool corner = x_face && (row == 0 || row == ny - 1);
    // Full stencil whose neighbours have full stencils too (re = 2.1 h): rows and columns
    // 4 ... n - 5. Nearer the surface the neighbours' truncated moment matrices leave a
    // small net force (6e-5 sigma0 in row 3), which the separation tensor removes as well.
    const bool deep = col >= 4 && col <= nx - 5 && row >= 4 && row <= ny - 5;
    if (x_face) EXPECT_EQ(fr.failures()[i], 0) << "x-face particle " << i << " failed";
    if (x_face && !corner) face_worst = std::max(face_worst, fr.separation_pa()[i]);
    if (corner) {
      // At a corner the moment-matrix correction tilts some bond forces to the other side
      // of the particle, so part of the pull is balanced: measured 0.18 sigma0.
      EXPECT_LT(fr.separation_pa()[i], 0.25 * sigma0);
      corner_worst = std::max(corner_worst, fr.separation_pa()[i]);
    }
    if (deep) {
      // Symmetric neighbourhood, uniform uniaxial stress: S = sigma0 (rounding).
      EXPECT_NEAR(fr.separation_pa()[i], sigma0, 1e-9 * sigma0);
      ++interior;
    }
  }
  std::printf("affine stretch: S on the x faces <= %.3g sigma0, corners %.3g sigma0 (stress there = sigma0)\n",
              face_worst / sigma0, corner_worst / sigma0);
  // All bond forces of an x-face particle point inward and parallel to x: their resultant
  // is their sum, so varsigma = 0 to rounding.
  EXPECT_LT(face_worst, 1e-9 * sigma0);
  EXPECT_GT(interior, 100);
  EXPECT_GT(fr.failed_particles(), 0) << "the interior at S = sigma0 > strength should fail";
}

// ---------------------------------------------------------------------------------------
// Compression alone never separates: the same block compressed affinely to 100x the
// strength (uniaxial, nu = 0, so no principal value is positive) has S = 0 everywhere and
// no failure (without the tension filter the compressive terms m(sum f-) - sum m(f-) of the
// surface particles would be positive).
TEST(MpsFracture, CompressionAloneDoesNotSeparate) {
  const double h = 1e-3, eps = -1e-3;
  const std::vector<double> pos = breccia::mps::test::lattice(2, 20, 20, 1, h);
  Solid solid = make_brittle(pos, h, 0.01 * kYoung * std::fabs(eps));
  for (size_t i = 0; i < solid.size(); ++i) solid.displacement(0)[i] = eps * pos[3 * i];
  solid.step();
  const FractureModel& fr = *solid.fracture();
  EXPECT_EQ(fr.failed_particles(), 0);
  EXPECT_EQ(fr.max_separation_pa(), 0.0);
}

// ---------------------------------------------------------------------------------------
// 3D: an affine uniaxial stretch along n = (1, 2, 2)/3 of a cubic-lattice block (no bond of
// the re = 2.1 stencil is within 10 deg of n). Interior particles with symmetric
// neighbourhoods carry S = sigma0 with normal n (rounding: the Jacobi eigen-solver
// converges to 1e-15), which checks the 3D path and the calibration D(n) off the axes.
TEST(MpsFracture, ThreeDimensionalSeparationFollowsAnOffAxisPrincipalDirection) {
  const double h = 1e-3, eps = 1e-4;
  const int m = 10;
  const std::vector<double> pos = breccia::mps::test::lattice(3, m, m, m, h);
  SolidOptions opt;
  opt.dimension = 3;
  opt.spacing_m = h;
  Solid solid(pos, std::vector<double>(pos.size() / 3, h * h * h), kDensity, brittle_law(), opt);
  solid.set_fracture({1e30});  // measure only
  const double n[3] = {1.0 / 3, 2.0 / 3, 2.0 / 3};
  // u = eps n (n . X): uniaxial strain eps along n, with nu = 0 uniaxial stress E eps n n^T.
  for (size_t i = 0; i < solid.size(); ++i) {
    const double along = n[0] * pos[3 * i] + n[1] * pos[3 * i + 1] + n[2] * pos[3 * i + 2];
    for (int a = 0; a < 3; ++a) solid.displacement(a)[i] = eps * n[a] * along;
  }
  solid.step();
  const FractureModel& fr = *solid.fracture();
  const double sigma0 = kYoung * eps;
  int interior = 0;
  for (size_t i = 0; i < solid.size(); ++i) {
    bool deep = true;
    for (int a = 0; a < 3; ++a) {
      const int c = static_cast<int>(pos[3 * i + a] / h);
      deep = deep && c >= 4 && c <= m - 5;
    }
    if (!deep) continue;
    ++interior;
    // The stress itself is Hooke's of the incremental strain sym(H) = eps n n^T: exact.
    EXPECT_NEAR(fr.separation_pa()[i], sigma0, 1e-9 * sigma0);
    const auto& nn = fr.normal_of(i);
    EXPECT_NEAR(std::fabs(nn[0] * n[0] + nn[1] * n[1] + nn[2] * n[2]), 1.0, 1e-12);
  }
  EXPECT_EQ(interior, 8);
}

// ---------------------------------------------------------------------------------------
// Case keys: material.fracture.tensile_strength > 0, stress formulation only.
TEST(MpsFracture, CaseKeysAreValidatedNamingTheField) {
  const std::string base = R"(
specimen:
  lattice: {dimension: 2, box: [0, 0, 10 mm, 5 mm], spacing: 0.5 mm, thickness: 1 mm}
model: {type: mps, formulation: stress}
materials:
  - {name: pmma, density: 1190, youngs_modulus: 3 GPa, poisson_ratio: 0.35, fracture: FRACTURE}
time: {end: 1 us}
)";
  auto with = [&](const std::string& fracture, const std::string& formulation = "stress") {
    std::string s = base;
    s.replace(s.find("FRACTURE"), 8, fracture);
    s.replace(s.find("formulation: stress"), 19, "formulation: " + formulation);
    return s;
  };
  auto error_of = [](const std::string& yaml) -> std::string {
    try {
      make_solid(parse_case_text(yaml, "case.yaml"));
    } catch (const breccia::InputError& e) {
      return e.what();
    }
    return "";
  };
  const CaseSpec ok = parse_case_text(with("{tensile_strength: 70 MPa}"), "case.yaml");
  ASSERT_TRUE(ok.material.fracture.has_value());
  EXPECT_DOUBLE_EQ(ok.material.fracture->tensile_strength_pa, 70e6);
  EXPECT_NE(make_solid(ok).fracture(), nullptr);
  const std::string negative = error_of(with("{tensile_strength: -1 MPa}"));
  EXPECT_NE(negative.find("case.yaml"), std::string::npos) << negative;
  EXPECT_NE(negative.find("tensile_strength"), std::string::npos) << negative;
  EXPECT_NE(negative.find("> 0"), std::string::npos) << negative;
  EXPECT_NE(error_of(with("{}")).find("tensile_strength"), std::string::npos);
  EXPECT_NE(error_of(with("{tensile_strength: 1 MPa, energy: 3}")).find("energy"), std::string::npos);
  const std::string displacement = error_of(with("{tensile_strength: 70 MPa}", "displacement"));
  EXPECT_NE(displacement.find("fracture"), std::string::npos) << displacement;
}

// Remnant stencils (fracture.hpp, kRemnantConditioning): on a 9 x 9 lattice (re = 2.1
// spacings) the centre particle keeps only the bonds a selection allows. A crack face (half
// stencil) and a crack meeting a surface (quarter) stay; a stencil of two bonds at 45 deg,
// (2,0) and (1,1) spacings, has conditioning 0.046 (closed form: L = [[0.2925, 0.2425],
// [0.2425, 0.2425]] h^2 V / h^2, eigenvalues 0.5113 and 0.0237) and is detached; a collinear
// sliver (bonds on one line only) is kept.
TEST(MpsFracture, RemnantStencilIsDetachedButFacesCornersAndSliversStay) {
  const double h = 1e-3;
  const auto pos = test::lattice(2, 9, 9, 1, h);
  const std::vector<double> vol(pos.size() / 3, h * h);
  const long long centre = 4 * 9 + 4;
  struct Case {
    const char* name;
    bool (*keep)(double x, double y);  // bond vector in spacings
    bool detached;
  };
  const Case cases[] = {
      {"intact", [](double, double) { return true; }, false},
      {"crack face (half)", [](double x, double) { return x > -1e-9; }, false},
      {"crack at a surface (quarter)", [](double x, double y) { return x > -1e-9 && y > -1e-9; }, false},
      {"collinear sliver", [](double x, double y) { return std::fabs(y) < 1e-9 && x > 0; }, false},
      {"remnant (2,0) + (1,1)", [](double x, double y) {
         return (std::fabs(x - 2) < 1e-9 && std::fabs(y) < 1e-9) || (std::fabs(x - 1) < 1e-9 && std::fabs(y - 1) < 1e-9);
       }, true},
  };
  for (const Case& c : cases) {
    BondList bonds = build_bonds(2, pos, 2.1 * h);
    FractureModel model(FractureLaw{1e6}, bonds, h);
    for (long long k = bonds.offset[centre]; k < bonds.offset[centre + 1]; ++k) {
      if (c.keep(bonds.rx[k] / h, bonds.ry[k] / h)) continue;
      const long long j = bonds.neighbour[k];
      bonds.weight[k] = 0.0;
      for (long long m = bonds.offset[j]; m < bonds.offset[j + 1]; ++m)
        if (bonds.neighbour[m] == centre) bonds.weight[m] = 0.0;
    }
    const double conditioning = stencil_conditioning(centre, bonds.view(), vol.data(), 2);
    const bool flagged = model.absorb_remnant(centre, bonds, vol.data(), 2);
    model.detach_flagged(bonds);
    int intact = 0;
    for (long long k = bonds.offset[centre]; k < bonds.offset[centre + 1]; ++k) intact += bonds.weight[k] > 0.0;
    std::printf("%-30s conditioning %.4f, %s, %d bonds left\n", c.name, conditioning, flagged ? "detached" : "kept", intact);
    EXPECT_EQ(flagged, c.detached) << c.name;
    EXPECT_EQ(intact == 0, c.detached) << c.name;
    EXPECT_EQ(model.detached_particles(), c.detached ? 1 : 0) << c.name;
    if (c.detached) EXPECT_NEAR(conditioning, 0.0237 / 0.5113, 2e-3) << c.name;  // the closed form above
  }
}
