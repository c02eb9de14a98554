// Graded particle arrangements on the stability map (docs/atlas.md): one horizon from the
// median spacing under-resolves the coarse part (refused at start-up, naming
// model.variable_horizon), dual horizon passes, and a steep grading with dual horizon is
// warned about (waves reflect at the change).
#include <gtest/gtest.h>

#include <string>

#include "breccia/common/error.hpp"
#include "breccia/common/particle_file.hpp"
#include "breccia/solver/graded_check.hpp"
#include "helpers.hpp"
#include "measures.hpp"

using namespace breccia;
using namespace breccia::solver;
using namespace breccia::solver::testing;

namespace {

// 2D strip 20 x 10 mm: spacing 0.5 mm for x < 10 mm, r x 0.5 mm beyond (the atlas's strip,
// smaller: 400 fine particles and 100 / r^2 coarse ones).
std::string graded_strip(double r) {
  return breccia::atlas::write_graded_strip(
      process_temp_dir() + "/graded_stability_r" + std::to_string(static_cast<int>(10 * r)) + ".h5", 0.02, 0.01, 0.5e-3, r);
}

std::string graded_yaml(double r, bool dual_horizon, bool check) {
  return "specimen: {particles: " + graded_strip(r) + "}\n"
         "model: {type: pmb, planar: plane_strain, horizon_factor: 3.015, variable_horizon: " +
         (dual_horizon ? "true" : "false") +
         "}\nmaterials: [{name: rock, density: 2600, youngs_modulus: 50 GPa, poisson_ratio: 0.25}]\n"
         "time: {steps: 1, check_stability: " + (check ? "true" : "false") + "}\n";
}

}  // namespace

// Measured (atlas, graded strip): one horizon over a 2:1 grading leaves the coarse half at
// local m = 1.5 with its shear energy 18 % low; over 4:1 (m = 0.75) it has no shear stiffness.
TEST(GradedStability, OneHorizonOverATwoToOneGradingIsRefusedNamingDualHorizon) {
  for (const double r : {2.0, 4.0}) {
    try {
      system_from_yaml("graded_refused", graded_yaml(r, false, true));
      FAIL() << "grading " << r << " with one horizon must be refused";
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("model.variable_horizon"), std::string::npos) << what;
      EXPECT_NE(what.find("under-resolved"), std::string::npos) << what;
      EXPECT_NE(what.find("variable_horizon: true"), std::string::npos) << what;
    }
    // The check is what refuses it: with checks off the same set-up builds.
    EXPECT_NO_THROW(system_from_yaml("graded_refused_off", graded_yaml(r, false, false)));
  }
}

// 1.5:1 leaves local m = 2.0 in the coarse part (energy within 1.7 %, measured): not refused.
TEST(GradedStability, GentleGradingWithOneHorizonPasses) {
  PdSystem s = system_from_yaml("graded_gentle", graded_yaml(1.5, false, true));
  EXPECT_NEAR(horizon_grading(s).min_local_ratio, 3.015 / 1.5, 1e-9);
}

// Dual horizon keeps m = horizon_factor at every particle: the same gradings pass; the
// warning about wave reflection appears from a 4:1 jump between bonded neighbours only.
TEST(GradedStability, DualHorizonPassesAndWarnsOnlyAboutSteepGrading) {
  PdSystem two = system_from_yaml("graded_dh2", graded_yaml(2.0, true, true));
  EXPECT_NEAR(horizon_grading(two).min_local_ratio, 3.015, 1e-9);
  EXPECT_TRUE(graded_horizon_warning(two).empty()) << graded_horizon_warning(two);
  PdSystem four = system_from_yaml("graded_dh4", graded_yaml(4.0, true, true));
  const std::string w = graded_horizon_warning(four);
  EXPECT_NE(w.find("reflects"), std::string::npos) << w;
  EXPECT_NE(w.find("model.variable_horizon"), std::string::npos) << w;
}
