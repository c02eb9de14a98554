// The clumping detector of the stress-based MPS solid (mps/stability_checks.hpp; stability map
// in docs/atlas.md): silent for homogeneous deformations of any size, and it stops a run
// whose neighbours pair up.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>
#include <string>

#include "breccia/common/error.hpp"
#include "breccia/mps/solid.hpp"
#include "breccia/mps/stability_checks.hpp"
#include "breccia/mps/strip_pull.hpp"
#include "mps_test_util.hpp"

using namespace breccia::mps;

namespace {

constexpr double kH = 1e-3;

Solid block(double hourglass, std::optional<double> dt = std::nullopt, int nx = 20, int ny = 10) {
  std::vector<double> pos = test::lattice(2, nx, ny, 1, kH);
  std::vector<double> vol(pos.size() / 3, kH * kH * kH);
  SolidLaw law;
  law.lame_lambda_pa = 20e9;
  law.shear_modulus_pa = 20e9;
  SolidOptions opt;
  opt.dimension = 2;
  opt.spacing_m = kH;
  opt.thickness_m = kH;
  opt.hourglass = hourglass;
  opt.dt_s = dt;
  return Solid(pos, vol, 2600, law, opt);
}

}  // namespace

// The measure is |x_j - x_i| / |F_i r_ij|: 1 for any affine field, so 50 % tension and 30 %
// compression (with shear) must read 1. One step computes F; its tiny dt (1e-12 s) keeps the
// surface particles' move dt^2 a to 1e-11 of a spacing, so 1e-6 is rounding with margin.
TEST(MpsClumping, HomogeneousTensionAndCompressionReadOne) {
  for (const double strain : {0.5, -0.3}) {
    Solid s = block(0.1, 1e-12);
    for (size_t i = 0; i < s.size(); ++i) {
      const double x = s.position_m()[3 * i], y = s.position_m()[3 * i + 1];
      s.displacement(0)[i] = strain * x + 0.1 * y;
      s.displacement(1)[i] = -0.2 * strain * y;
    }
    s.step();
    const Clumping c = measure_clumping(s);
    EXPECT_NEAR(c.min_ratio, 1.0, 1e-6) << "strain " << strain;
    EXPECT_EQ(c.clumped_bonds, 0);
    EXPECT_NO_THROW(require_no_clumping(s));
  }
}

// Neighbours paired up: every other column moved by 0.6 spacings towards its left neighbour
// (pairing, as the atlas saw grow in a tension wave without hourglass control), so a pair
// sits 0.4 spacings apart while its particles' gradient predicts about one spacing.
TEST(MpsClumping, PairedNeighboursStopTheRunNamingTheCause) {
  Solid s = block(0.0);
  for (size_t i = 0; i < s.size(); ++i) {
    const int column = static_cast<int>(s.position_m()[3 * i] / kH);
    if (column % 2 == 1) s.displacement(0)[i] = -0.6 * kH;
  }
  try {
    for (long long k = 0; k < kClumpingCheckEvery; ++k) s.step();  // Solid::step runs the check
    FAIL() << "paired neighbours must stop the run";
  } catch (const breccia::RunError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("clumping"), std::string::npos) << what;
    EXPECT_NE(what.find("model.hourglass"), std::string::npos) << what;
    EXPECT_NE(what.find("pressure_force"), std::string::npos) << what;
  }
  EXPECT_LT(measure_clumping(s).min_ratio, kMinNeighbourDistanceRatio);
}

namespace {

// The atlas's quasi-static pull (tools/atlas/mps_atlas.cpp, "MPS in tension"): a 2D strip
// 40 x 10 particles, dx 1 mm, rock (E 50 GPa, nu 0.25), two particle columns at each end driven
// apart in x to a nominal strain, ramped smoothly over eight transit times and held for two.
// Returns the smallest clumping ratio seen; throws RunError if Solid::step's check stops it.
struct PullResult {
  double min_ratio = 1.0;
  double worst_x = 0.0, worst_y = 0.0;
  long long steps = 0;
};
PullResult slow_pull(double strain, double hourglass, PressureForce pressure, double ramp_transits = 8.0) {
  constexpr double E = 50e9, nu = 0.25, rho = 2600, L = 0.04;
  constexpr int nx = 40, ny = 10;
  std::vector<double> pos = test::lattice(2, nx, ny, 1, kH);
  std::vector<double> vol(pos.size() / 3, kH * kH * kH);
  SolidLaw law;
  law.lame_lambda_pa = E * nu / ((1 + nu) * (1 - 2 * nu));
  law.shear_modulus_pa = E / (2 * (1 + nu));
  SolidOptions opt;
  opt.dimension = 2;
  opt.spacing_m = kH;
  opt.thickness_m = kH;
  opt.hourglass = hourglass;
  opt.pressure = pressure;
  Solid solid(pos, vol, rho, law, opt);
  const double c_l = std::sqrt((law.lame_lambda_pa + 2 * law.shear_modulus_pa) / rho);
  const double ramp = ramp_transits * L / c_l, end = ramp + 2 * L / c_l;
  const StripPull pull = strip_pull(solid, L, kH, strain, ramp);
  PullResult r;
  while (solid.time_s() < end) {
    solid.step();
    drive_strip_pull(solid, pull);
    if (solid.steps() % kClumpingCheckEvery == 0) {
      const Clumping c = measure_clumping(solid);
      if (c.min_ratio < r.min_ratio) {
        r.min_ratio = c.min_ratio;
        r.worst_x = pos[3 * c.worst_particle];
        r.worst_y = pos[3 * c.worst_particle + 1];
      }
    }
  }
  r.steps = solid.steps();
  return r;
}

}  // namespace

// docs/atlas.md listed possible false alarms in slow pulls beyond 50 % strain. The cause
// (measured with this pull): the two driven columns at each end move as one rigid block, so
// their own bonds keep their length while F_i, fitted over a stencil that reaches into the
// stretching strip, predicts the stretch: the old measure read 0.64 at 70 % and 0.61 at 80 %
// there (0.57 at 100 %, 0.50 without hourglass control, which stopped a stable pull). The
// detector now skips bonds no shorter than their reference length (clumping pulls neighbours
// together); the same pulls read 0.74 and 0.72, at the top of the strip near the grips where
// the strain field bends. 0.68 lies between the old and the new readings: it fails if the
// driven block is counted again, with 0.035 of margin to the reading (the run is
// deterministic on one thread).
TEST(MpsClumping, SlowPullOfAStableStripToSeventyAndEightyPercentDoesNotTripTheDetector) {
  for (const double strain : {0.7, 0.8}) {
    PullResult r;
    ASSERT_NO_THROW(r = slow_pull(strain, 0.1, PressureForce::Conservative)) << "strain " << strain;
    std::printf("strain %.2f: smallest clumping ratio %.3f at (%.1f, %.1f) mm over %lld steps\n", strain, r.min_ratio,
                r.worst_x * 1e3, r.worst_y * 1e3, r.steps);
    EXPECT_GT(r.min_ratio, 0.68) << "strain " << strain;
  }
}

// The mechanism itself, without dynamics: a held end (x < 5 mm, u = 0) next to a part
// stretched uniformly by 150 %. F_i of the held particles next to the kink predicts a stretch
// their own bonds do not have: the old measure |x_j - x_i| / |F_i r_ij| reads 0.72 there
// (about 1 / (1 + strain / 4): 0.57 at 300 %, below 0.5 beyond 400 %; in the dynamic pull,
// where the grips also bend the field, it reached 0.50 at 100 %). No bond is shorter than its
// reference length, so the detector skips them. A tiny dt (1e-12 s) keeps the step from
// moving anything but by rounding.
TEST(MpsClumping, RigidlyHeldEndNextToAStretchedPartIsNotClumping) {
  constexpr double strain = 1.5, x_held = 5e-3;
  Solid s = block(0.1, 1e-12);
  for (size_t i = 0; i < s.size(); ++i)
    s.displacement(0)[i] = strain * std::max(0.0, s.position_m()[3 * i] - x_held);
  s.step();
  double old_measure = 1.0;
  const BondList& b = s.bonds();
  for (size_t i = 0; i < s.size(); ++i)
    for (long long k = b.offset[i]; k < b.offset[i + 1]; ++k) {
      const double r = std::hypot(b.rx[k], b.ry[k]);
      if (r > 1.5 * kH) continue;
      const int j = b.neighbour[k];
      const auto& h = s.displacement_gradient()[i];
      const double fr = std::hypot(b.rx[k] + h(0, 0) * b.rx[k] + h(0, 1) * b.ry[k],
                                   b.ry[k] + h(1, 0) * b.rx[k] + h(1, 1) * b.ry[k]);
      const double d = std::hypot(b.rx[k] + s.displacement(0)[j] - s.displacement(0)[i],
                                  b.ry[k] + s.displacement(1)[j] - s.displacement(1)[i]);
      old_measure = std::min(old_measure, d / fr);
    }
  // 0.75: the deficit the test exists for (0.72 measured; 1 for an affine field).
  EXPECT_LT(old_measure, 0.75) << "the kinematics no longer provoke the held-block deficit";
  const Clumping c = measure_clumping(s);
  EXPECT_EQ(c.clumped_bonds, 0) << "worst " << c.min_ratio << " at particle " << c.worst_particle;
  // Only bonds the step shortened by its rounding-size motion (~1e-11 of a spacing) are
  // measured; they read F_i's own small misfit at the surface (0.994), nowhere near 0.72.
  EXPECT_GT(c.min_ratio, 0.99);
  EXPECT_NO_THROW(require_no_clumping(s));
}

namespace {

// A 20 x 10 block (1 mm) with a crack along x = 10 mm from the top down to y = 5 mm (bonds
// crossing it with both ends above y = 5 mm cut, as fracture leaves them: weight 0), and one
// pair of particles pushed together to 0.4 of their 1 mm bond, each by 0.3 mm. Columns
// count from 0 (x = 0.5 mm); the crack faces are columns 9 and 10. Returns the measure after a
// step of 1e-12 s (which only computes F).
Clumping pushed_pair(bool crack, int col_a, int row_a, int col_b, int row_b) {
  Solid s = block(0.1, 1e-12);
  const auto& p = s.position_m();
  if (crack)
    s.cut_bonds([&](long long i, long long j) {
      return (p[3 * i] - 10 * kH) * (p[3 * j] - 10 * kH) < 0 && p[3 * i + 1] > 5 * kH && p[3 * j + 1] > 5 * kH;
    });
  const auto at = [&](int col, int row) { return s.nearest_particle({(col + 0.5) * kH, (row + 0.5) * kH, 0.0}); };
  const int a = at(col_a, row_a), b = at(col_b, row_b);
  for (int axis = 0; axis < 2; ++axis) {
    const double towards = 0.3 * (p[3 * b + axis] - p[3 * a + axis]);
    s.displacement(axis)[a] += towards;
    s.displacement(axis)[b] -= towards;
  }
  s.step();
  return measure_clumping(s);
}

}  // namespace

// Refined measure (stability_checks.hpp): a bond between two crack-face particles (each with a
// cut nearest-neighbour bond) is not measured, because F fitted on a one-sided stencil cannot
// follow a flank closing ahead of a crack tip (the 0.25 mm ring: one flank pair at 0.48 for
// ~1 us that recovered on its own, docs/mps.md). The same pair without the crack, a pair one
// column inside the material, and a pair of one face particle and one intact particle are
// still counted: the exclusion is the flank only.
TEST(MpsClumping, PairOnACrackFlankIsSkippedButPairingBesideTheCrackIsCaught) {
  const Clumping flank = pushed_pair(true, 9, 7, 9, 8);  // both on the left face
  EXPECT_EQ(flank.clumped_bonds, 0) << "worst " << flank.min_ratio << " at particle " << flank.worst_particle;
  EXPECT_EQ(flank.skipped_face_bonds, 2);  // the pair's bond, seen from both ends
  const Clumping no_crack = pushed_pair(false, 9, 7, 9, 8);
  EXPECT_GE(no_crack.clumped_bonds, 2);
  EXPECT_LT(no_crack.min_ratio, kMinNeighbourDistanceRatio);
  const Clumping inside = pushed_pair(true, 8, 7, 8, 8);  // column 8: its cut bonds reach 2 mm only
  EXPECT_GE(inside.clumped_bonds, 2);
  const Clumping across = pushed_pair(true, 8, 8, 9, 8);  // intact particle and face particle
  EXPECT_GE(across.clumped_bonds, 1);
  EXPECT_LT(across.min_ratio, kMinNeighbourDistanceRatio);
}
