// Fields by expression in the case file (initial velocity and displacement; muparser through
// common/expression.hpp): the values set-up gives each particle against the same field
// computed here, and the errors for bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "breccia/common/error.hpp"
#include "helpers.hpp"

using namespace breccia::solver;
using namespace breccia::solver::testing;

namespace {

// A thin tube about the z axis (the fragmenting-cylinder problem of Peridigm's and CabanaPD's
// examples, small): lattice cells of a box, the velocity field v_r = 200 - 50 (z/0.05 - 1)^2,
// v_z = 100 (z/0.05 - 1) m/s written in x, y, z.
const std::string kTube =
    "specimen: {lattice: {dimension: 3, box: [0.005, -0.004, 0, 0.013, 0.004, 0.1], spacing: 1 mm}}\n"
    "model: {type: pmb, horizon_factor: 3.015}\n"
    "materials: [{name: m, density: 7800, youngs_modulus: 190 GPa, poisson_ratio: 0.25}]\n"
    "time: {steps: 1}\n";

std::string error_of(const std::string& name, const std::string& yaml) {
  try {
    system_from_yaml(name, yaml);
  } catch (const breccia::InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(ExpressionFields, FragmentingCylinderVelocityFieldIsSetAtEveryParticle) {
  PdSystem s = system_from_yaml("fields_tube", kTube + R"yaml(initial:
  - type: velocity
    expression:
      - "(200 - 50 * (z / 0.05 - 1)^2) * x / sqrt(x^2 + y^2)"
      - "(200 - 50 * (z / 0.05 - 1)^2) * y / sqrt(x^2 + y^2)"
      - "100 * (z / 0.05 - 1)"
)yaml");
  ASSERT_GT(s.n, 500u);
  for (size_t i = 0; i < s.n; ++i) {
    const double x = s.x0[3 * i], y = s.x0[3 * i + 1], z = s.x0[3 * i + 2];
    const double vr = 200.0 - 50.0 * std::pow(z / 0.05 - 1.0, 2), r = std::hypot(x, y);
    ASSERT_NEAR(s.v[3 * i], vr * x / r, 1e-12 * 200) << i;
    ASSERT_NEAR(s.v[3 * i + 1], vr * y / r, 1e-12 * 200) << i;
    ASSERT_NEAR(s.v[3 * i + 2], 100.0 * (z / 0.05 - 1.0), 1e-12 * 100) << i;
  }
}

TEST(ExpressionFields, DisplacementByExpressionOnACaseSetIn2D) {
  PdSystem s = system_from_yaml("fields_plate", R"yaml(specimen: {lattice: {dimension: 2, box: [0, 0, 0.02, 0.01], spacing: 1 mm}}
model: {type: pmb, horizon_factor: 3.015, planar: plane_stress}
materials: [{name: m, density: 1000, youngs_modulus: 1 GPa, poisson_ratio: 0.3333333333333333}]
sets: [{name: right, box: [0.01, -1, 1, 1]}]
initial:
  - {type: displacement, set: right, expression: ["1e-6 * sin(_pi * x / 0.02)", "2e-7 * x * y / 0.0002"]}
time: {steps: 1}
)yaml");
  int moved = 0;
  for (size_t i = 0; i < s.n; ++i) {
    const double x = s.x0[3 * i], y = s.x0[3 * i + 1];
    const bool in = x >= 0.01;
    EXPECT_NEAR(s.u[3 * i], in ? 1e-6 * std::sin(M_PI * x / 0.02) : 0.0, 1e-18) << i;
    EXPECT_NEAR(s.u[3 * i + 1], in ? 2e-7 * x * y / 0.0002 : 0.0, 1e-18) << i;
    moved += in;
  }
  EXPECT_EQ(moved, 100);
}

TEST(ExpressionFields, BadExpressionsAndUnknownNamesAreInputErrorsWithThePosition) {
  const std::string head = kTube + "initial:\n  - {type: velocity, expression: [";
  std::string m = error_of("fields_syntax", head + "\"200 - 50 * (z / 0.05 - 1)^\", \"0\", \"0\"]}\n");
  EXPECT_NE(m.find("initial[0].expression[0]"), std::string::npos) << m;
  EXPECT_NE(m.find("position"), std::string::npos) << m;
  m = error_of("fields_name", head + "\"0\", \"200 * r\", \"0\"]}\n");
  EXPECT_NE(m.find("initial[0].expression[1]"), std::string::npos) << m;
  EXPECT_NE(m.find("r"), std::string::npos) << m;
  EXPECT_NE(m.find("position 7"), std::string::npos) << m;
  m = error_of("fields_both", kTube + "initial:\n  - {type: velocity, value: [1, 0, 0], expression: [\"1\", \"0\", \"0\"]}\n");
  EXPECT_NE(m.find("both value and expression"), std::string::npos) << m;
  // Finite when read, not at a particle: 1/x on a block that holds x = 0.5 mm but not 0.
  m = error_of("fields_inf", kTube + "initial:\n  - {type: velocity, expression: [\"1 / (x - 0.0055)\", \"0\", \"0\"]}\n");
  EXPECT_NE(m.find("not finite"), std::string::npos) << m;
}
