// The clumping detector of the stress-based MPS solid (mps/stability_checks.hpp; stability map
// in docs/atlas.md): silent for homogeneous deformations of any size, and it stops a run
// whose neighbours pair up.
#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <string>

#include "breccia/common/error.hpp"
#include "breccia/mps/solid.hpp"
#include "breccia/mps/stability_checks.hpp"
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
