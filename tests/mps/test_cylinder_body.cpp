// specimen.bodies shape `cylinder` (3D; docs/mps.md, "Several bodies and contact"): the cubic
// lattice cut to a cylinder along z, as the Taylor bar test sets it up, and its input errors
// naming the field (exit code 2 from the CLI through InputError).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "breccia/common/error.hpp"
#include "breccia/mps/case_spec.hpp"
#include "breccia/mps/particles.hpp"
#include "mps_test_util.hpp"

using namespace breccia::mps;

namespace {

// cases/mps-taylor-bar/case.yaml at 8 particles across (spacing in metres, as run.sh writes it).
const std::string kBar = R"(
specimen:
  bodies:
    dimension: 3
    spacing: 0.0008
    shapes:
      - {name: bar, type: cylinder, center: [0, 0, 0], radius: 3.2 mm, length: 32.4 mm}
model: {type: mps, formulation: stress}
materials:
  - {name: copper, density: 8930, youngs_modulus: 117 GPa, poisson_ratio: 0.35}
time: {end: 1 us}
)";

std::string bar_with(const std::string& from, const std::string& to) { return test::replace_once(kBar, from, to); }

std::string error_of(const std::string& yaml) {
  return test::input_error_of([&] { build_particle_cloud(parse_case_text(yaml, "case.yaml")); });
}

}  // namespace

// The same particles as TEST(MpsSolid, TaylorBarFinalLengthIsWithinFivePercentOfPublished):
// cell centres (i + 1/2) h about the axis kept within the radius, round(L / h) layers.
TEST(MpsCylinderBody, CylinderIsTheTaylorBarLatticeOfTheTest) {
  const ParticleCloud c = build_particle_cloud(parse_case_text(kBar, "case.yaml"));
  const double radius = 3.2e-3, length = 32.4e-3, h = 0.8e-3;
  std::vector<std::array<double, 3>> expected;
  const int nr = static_cast<int>(std::ceil(radius / h)), nz = static_cast<int>(std::lround(length / h));
  for (int k = 0; k < nz; ++k)
    for (int j = -nr; j < nr; ++j)
      for (int i = -nr; i < nr; ++i) {
        const double x = (i + 0.5) * h, y = (j + 0.5) * h, z = (k + 0.5) * h;
        if (x * x + y * y <= radius * radius) expected.push_back({x, y, z});
      }
  ASSERT_EQ(c.volume_m3.size(), expected.size());
  EXPECT_EQ(expected.size(), 2080u);  // 52 per layer, 40 layers
  std::vector<std::array<double, 3>> got;
  for (size_t i = 0; i < c.volume_m3.size(); ++i) {
    got.push_back({c.position_m[3 * i], c.position_m[3 * i + 1], c.position_m[3 * i + 2]});
    EXPECT_DOUBLE_EQ(c.volume_m3[i], h * h * h);
  }
  std::sort(got.begin(), got.end());
  std::sort(expected.begin(), expected.end());
  double worst = 0.0;  // positions agree to rounding (the case's spacing passes through the unit parser)
  for (size_t i = 0; i < got.size(); ++i)
    for (int a = 0; a < 3; ++a) worst = std::max(worst, std::fabs(got[i][a] - expected[i][a]));
  EXPECT_LT(worst, 1e-15);
  ASSERT_EQ(c.set_names.size(), 1u);
  EXPECT_EQ(c.set_names[0], "bar");
  EXPECT_EQ(c.set_members[0].size(), expected.size());
  EXPECT_EQ(c.dimension, 3);
}

TEST(MpsCylinderBody, BadCylinderKeysAreRejectedNamingTheField) {
  const std::string shape = "specimen.bodies.shapes[0].";
  std::string e = error_of(bar_with("dimension: 3", "dimension: 2"));
  EXPECT_NE(e.find(shape + "type"), std::string::npos) << e;
  EXPECT_NE(e.find("cylinder in 3D only"), std::string::npos) << e;
  e = error_of(bar_with("radius: 3.2 mm", "radius: 0.5 mm"));
  EXPECT_NE(e.find(shape + "radius"), std::string::npos) << e;
  e = error_of(bar_with("radius: 3.2 mm", "radius: -1 mm"));
  EXPECT_NE(e.find(shape + "radius"), std::string::npos) << e;
  e = error_of(bar_with(", length: 32.4 mm", ""));
  EXPECT_NE(e.find(shape + "length"), std::string::npos) << e;
  e = error_of(bar_with("length: 32.4 mm", "length: 32.4 mm, outer_radius: 4 mm"));
  EXPECT_NE(e.find(shape + "outer_radius"), std::string::npos) << e;
  e = error_of(bar_with("type: cylinder, center: [0, 0, 0], radius: 3.2 mm, length: 32.4 mm",
                        "type: box, box: [0, 0, 0, 4 mm, 4 mm, 4 mm], radius: 3.2 mm"));
  EXPECT_NE(e.find(shape + "radius"), std::string::npos) << e;
  EXPECT_NE(e.find("type: cylinder only"), std::string::npos) << e;
}
