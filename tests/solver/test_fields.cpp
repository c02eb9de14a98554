// Fields by expression in the case file (initial velocity and displacement; muparser through
// common/expression.hpp): the values set-up gives each particle against the same field
// computed here, and the errors for bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <string>

#include "breccia/common/error.hpp"
#include "breccia/common/h5.hpp"
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

// Boundary values by expression in x, y, z and t: the velocity a boundary imposes is the
// field at the middle of each step (as a constant value's ramp is), so the displacement is
// the sum of dt times it; checked here against the same field summed in the test.
TEST(ExpressionFields, VelocityBoundaryInTimeAndSpaceFollowsTheFieldEveryStep) {
  PdSystem s = system_from_yaml("fields_bc_velocity", R"yaml(specimen: {lattice: {dimension: 2, box: [0, 0, 0.02, 0.01], spacing: 1 mm}}
model: {type: pmb, horizon_factor: 3.015, planar: plane_stress}
materials: [{name: m, density: 1000, youngs_modulus: 1 GPa, poisson_ratio: 0.3333333333333333}]
sets: [{name: left, box: [-1, -1, 0.002, 1]}]
boundary:
  - {type: velocity, set: left, components: [x], expression: ["0.1 * sin(2 * _pi * t / 1e-4) * (1 + y / 0.01)", "0"]}
time: {steps: 1}
)yaml");
  const auto field = [](double y, double t) { return 0.1 * std::sin(2 * M_PI * t / 1e-4) * (1 + y / 0.01); };
  std::vector<int64_t> left;
  for (size_t i = 0; i < s.n; ++i)
    if (s.x0[3 * i] <= 0.002) left.push_back(static_cast<int64_t>(i));
  ASSERT_EQ(left.size(), 20u);  // two columns of ten
  std::vector<double> u_expected(s.n, 0.0);
  for (int k = 1; k <= 30; ++k) {
    cpu_step(s);
    const double t_mid = s.time - 0.5 * s.dt;
    for (auto i : left) {
      const double v = field(s.x0[3 * i + 1], t_mid);
      u_expected[i] += s.dt * v;
      // The same formula in muparser and in C++: a few ulps apart at most (4e-15). The field
      // at the step's end instead of its middle would be off by a few % here; muparser's own
      // _pi (13 digits when built by GCC) by 2.5e-13 (common/src/expression.cpp).
      ASSERT_NEAR(s.v[3 * i], v, 4e-15 * std::abs(v) + 1e-20) << "step " << k << " particle " << i;
      ASSERT_NEAR(s.u[3 * i], u_expected[i], 4e-15 * std::abs(u_expected[i]) + 1e-22) << k;
    }
  }
  EXPECT_GT(std::abs(u_expected[left.back()]), 0.0);
}

// A displacement boundary in x only, ramped: evaluated once, scaled by the ramp while it rises.
TEST(ExpressionFields, RampedDisplacementBoundaryInSpace) {
  PdSystem s = system_from_yaml("fields_bc_displacement", R"yaml(specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.006, 0.004, 0.004], spacing: 1 mm}}
model: {type: pmb, horizon_factor: 3.015}
materials: [{name: m, density: 7800, youngs_modulus: 200 GPa, poisson_ratio: 0.25}]
sets: [{name: end, half_space: {point: [0.005, 0, 0], normal: [1, 0, 0]}}]
boundary:
  - {type: displacement, set: end, expression: ["1e-6 * (y + z) / 0.004", "-2e-7 * x / 0.006", "0"], ramp_time: 1 us}
time: {steps: 1}
)yaml");
  for (int k = 1; k <= 40; ++k) {
    cpu_step(s);
    const double ramp = std::min(1.0, s.time / 1e-6);
    for (size_t i = 0; i < s.n; ++i) {
      if (s.x0[3 * i] < 0.005) continue;
      const double x = s.x0[3 * i], y = s.x0[3 * i + 1], z = s.x0[3 * i + 2];
      ASSERT_NEAR(s.u[3 * i], ramp * 1e-6 * (y + z) / 0.004, 1e-21) << k;
      ASSERT_NEAR(s.u[3 * i + 1], ramp * -2e-7 * x / 0.006, 1e-21) << k;
      ASSERT_EQ(s.u[3 * i + 2], 0.0);
    }
  }
  EXPECT_GT(s.time, 1e-6);  // the ramp ended inside the run
}

TEST(ExpressionFields, BoundaryExpressionErrorsNameTheKey) {
  const std::string head = kTube + "sets: [{name: base, box: [0, -1, 0, 1, 1, 0.002]}]\nboundary:\n";
  std::string m = error_of("fields_bc_name", head + "  - {type: velocity, set: base, expression: [\"0\", \"0\", \"T * 2\"]}\n");
  EXPECT_NE(m.find("boundary[0].expression[2]"), std::string::npos) << m;
  EXPECT_NE(m.find("position 1"), std::string::npos) << m;
  m = error_of("fields_bc_both", head + "  - {type: displacement, set: base, value: [0, 0, 1e-6], expression: [\"0\", \"0\", \"t\"]}\n");
  EXPECT_NE(m.find("both value and expression"), std::string::npos) << m;
  // Relaxation has no time: an expression in t is refused there, one in x, y, z is not.
  const std::string adr = R"yaml(specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.006, 0.004, 0.004], spacing: 1 mm}}
model: {type: pmb, horizon_factor: 3.015}
materials: [{name: m, density: 7800, youngs_modulus: 200 GPa, poisson_ratio: 0.25}]
sets: [{name: end, half_space: {point: [0.005, 0, 0], normal: [1, 0, 0]}}]
time: {integrator: adr}
boundary:
)yaml";
  m = error_of("fields_bc_adr", adr + "  - {type: displacement, set: end, expression: [\"1e-6 * t\", \"0\", \"0\"]}\n");
  EXPECT_NE(m.find("boundary[0].expression[0]"), std::string::npos) << m;
  EXPECT_NE(m.find("adr"), std::string::npos) << m;
  EXPECT_EQ(error_of("fields_bc_adr_x", adr + "  - {type: displacement, set: end, expression: [\"1e-6 * x\", \"0\", \"0\"]}\n"), "");
}

// A velocity field read from an HDF5 file in the particle file's order: the file is written
// from a first set-up's reference positions (original_index: internal -> file order), so a
// row read for the wrong particle would not match the field at that particle's position.
TEST(ExpressionFields, InitialVelocityFromAnHdf5FieldInParticleFileOrder) {
  const std::string head =
      "specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.006, 0.004, 0.004], spacing: 1 mm}}\n"
      "model: {type: pmb, horizon_factor: 3.015}\n"
      "materials: [{name: m, density: 7800, youngs_modulus: 200 GPa, poisson_ratio: 0.25}]\n"
      "time: {steps: 1}\nsets: [{name: low, box: [0, 0, 0, 1, 1, 0.002]}]\n";
  const PdSystem first = system_from_yaml("fields_file_probe", head);
  const auto field = [](double x, double y, double z, int d) { return d == 0 ? 1e3 * x : d == 1 ? -2e3 * y : 5e2 * z + 1; };
  std::vector<double> rows(3 * first.n);
  for (size_t i = 0; i < first.n; ++i)
    for (int d = 0; d < 3; ++d)
      rows[3 * first.original_index[i] + d] = field(first.x0[3 * i], first.x0[3 * i + 1], first.x0[3 * i + 2], d);
  const std::string h5path = process_temp_dir() + "/v0.h5";
  {
    breccia::h5::File f(h5path, breccia::h5::File::Mode::Create);
    f.write("velocity", rows, {first.n, 3});
  }
  const PdSystem s = system_from_yaml(
      "fields_file", head + "initial:\n  - {type: velocity, set: low, file: " + h5path + ", dataset: velocity}\n");
  int set = 0;
  for (size_t i = 0; i < s.n; ++i) {
    const bool in = s.x0[3 * i + 2] <= 0.002;
    set += in;
    for (int d = 0; d < 3; ++d)  // copied, not computed: exactly equal
      ASSERT_EQ(s.v[3 * i + d], in ? field(s.x0[3 * i], s.x0[3 * i + 1], s.x0[3 * i + 2], d) : 0.0) << i;
  }
  EXPECT_GT(set, 0);
  EXPECT_LT(set, static_cast<int>(s.n));
  // The same field as CSV (a header line, 17 significant digits: the same doubles).
  const std::string csv = process_temp_dir() + "/v0.csv";
  {
    std::ofstream out(csv);
    out << "vx,vy,vz\n";
    out.precision(17);
    for (size_t r = 0; r < first.n; ++r) out << rows[3 * r] << "," << rows[3 * r + 1] << "," << rows[3 * r + 2] << "\n";
  }
  const PdSystem from_csv = system_from_yaml("fields_csv", head + "initial:\n  - {type: velocity, set: low, file: " + csv + "}\n");
  EXPECT_EQ(from_csv.v, s.v);
  // Another row count, a missing dataset, a dataset without .h5: errors naming the key.
  {
    breccia::h5::File f(h5path, breccia::h5::File::Mode::Create);
    f.write("velocity", std::vector<double>(3 * (first.n - 1), 0.0), {first.n - 1, 3});
  }
  std::string m = error_of("fields_file_rows", head + "initial:\n  - {type: velocity, file: " + h5path + ", dataset: velocity}\n");
  EXPECT_NE(m.find(std::to_string(first.n) + " rows"), std::string::npos) << m;
  m = error_of("fields_file_name", head + "initial:\n  - {type: velocity, file: " + h5path + ", dataset: v}\n");
  EXPECT_NE(m.find("initial[0].dataset"), std::string::npos) << m;
  m = error_of("fields_file_missing", head + "initial:\n  - {type: velocity, file: /nonexistent/v.h5, dataset: v}\n");
  EXPECT_NE(m.find("initial[0].file"), std::string::npos) << m;
}
