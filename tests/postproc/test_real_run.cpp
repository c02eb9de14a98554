// breccia-post on a real breccia-solve fracture run: a 2D glass strip (8 x 4 mm, lattice
// spacing 0.2 mm, 1 mm thick) with a 1.9 mm ligament between two edge pre-cracks, pulled
// apart at 0.1 m/s until it separates into two halves. The crack tips (y = 1.05 and 2.95 mm)
// lie off every bond line: a tip exactly on one (y = 1.0 mm on this lattice) once cut pairs on
// one side only, and the unbalanced forces broke the strip early; with both sides cut alike
// (tests/solver Precracks.ASegmentEndingOnABondLine...) that strip had not separated by 150 us.
#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "real_run.hpp"

namespace fs = std::filesystem;
using breccia::postproc::testing::json_number;

namespace {

constexpr double kLigament_m = 1.9e-3, kThickness_m = 1e-3, kG0 = 3.8;

// Runs the solver and breccia-post once for all tests of this file.
const std::string& ligament_post_json() {
  static const std::string json = [] {
    return breccia::postproc::testing::solve_and_post("breccia_post_real_run", [](const fs::path& dir) {
      std::ofstream(dir / "case.yaml") << R"(name: ligament
specimen: {lattice: {dimension: 2, box: [0, 0, 0.008, 0.004], spacing: 0.2 mm, thickness: 1 mm}}
model: {type: pmb, planar: plane_stress, horizon_factor: 3.015, no_fail: [xmin, xmax]}
materials: [{name: glass, density: 2440, youngs_modulus: 72 GPa, poisson_ratio: 0.3333333333333333, fracture_energy: 3.8}]
precracks:
  - {type: segment, from: [0.004, 0], to: [0.004, 0.00105]}
  - {type: segment, from: [0.004, 0.00295], to: [0.004, 0.004]}
boundary:
  - {type: velocity, set: xmax, value: [0.1, 0, 0], components: [x], ramp_time: 20 us}
  - {type: velocity, set: xmin, value: [-0.1, 0, 0], components: [x], ramp_time: 20 us}
time: {end: 120 us}
output: {every: 100000, history_every: 50}
)";
    });
  }();
  return json;
}

}  // namespace

TEST(RealFractureRun, SeparatingCrackAreaIsTheLigamentWhileBrokenBondFacesOvercountIt) {
  const std::string& json = ligament_post_json();
  ASSERT_FALSE(json.empty()) << "breccia-solve or breccia-post failed";
  // Two halves (plus single-particle debris chips torn out of the crack band).
  ASSERT_GE(json_number(json, "fragment_count", "\"fragments\""), 2);
  const double ligament_area = kLigament_m * kThickness_m;
  // Broken bonds spread over a band a few spacings wide around the crack: every lattice
  // face with a broken bond counts, about 4x the ligament here (3.8x measured) (the lead's 3x on a finer
  // lattice). The check is only that the over-count exists, which is what the separating
  // criterion removes.
  EXPECT_GT(json_number(json, "fracture_area_m2", "\"cracks\""), 2.0 * ligament_area);
  // Faces between different fragments, smoothed: the through-crack. Tolerance: the crack is
  // rough on scales longer than the smoothing radius (4 faces) and debris chips sit in it;
  // measured 1.04-1.16x the ligament on five runs (this case at 120 and 150 us: 1.16, 1.16;
  // earlier runs with the one-sided pre-crack cut: 1.08, 1.15; the 10 x 6 mm case of issue 5
  // at 0.1 mm spacing: 1.04; a 6 x 3 mm strip at 0.03 m/s: 1.13), hence [1, 1.2]. Counting every broken-bond face gives 3.7x; counting debris-chip
  // faces in full (both sides of each chip) gives 1.36x.
  const double separating = json_number(json, "smoothed_separating_fracture_area_m2", "\"cracks\"");
  EXPECT_GE(separating, ligament_area);
  EXPECT_LE(separating, 1.2 * ligament_area);
  // The separating energy ratio is reported (1.30 here: the dynamic crack leaves a damage
  // band and chips, docs/postproc.md); the 10 % energy check of issue 5 is made on a stable
  // DCB crack instead (test_energy_real_run.cpp).
  const double g0_separating = json_number(json, "G0_times_separating_area_J", "\"energy\"");
  EXPECT_NEAR(g0_separating, kG0 * separating,
              1e-6 * kG0 * separating);  // one material: G0 x area, to the 10 digits printed
  EXPECT_TRUE(std::isfinite(json_number(json, "ratio_separating", "\"energy\"")));
}
