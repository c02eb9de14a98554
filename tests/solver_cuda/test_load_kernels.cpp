// load_kernels.hpp (what the CUDA backend runs for loads and constraints) against the CPU
// backend's compute_external and apply_constraints. They must agree to the bit: the GPU
// comparison tests rely on both backends rounding identically. Runs on any machine.
#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "breccia/solver/load_kernels.hpp"
#include "breccia/solver/pd_system.hpp"

using namespace breccia::solver;

namespace {

PdSystem system_from_yaml(const std::string& name, const std::string& yaml) {
  const std::string path = ::testing::TempDir() + "/load_kernels_" + name + ".yaml";
  std::ofstream(path) << yaml;
  return setup_system(parse_case_file(path));
}

bool bitwise_equal(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

}  // namespace

TEST(LoadKernels, FacetBodyAndIndenterForcesEqualTheCpuBackendBitForBit) {
  PdSystem s = system_from_yaml("loads", R"(
specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.004, 0.004, 0.003], spacing: 0.5 mm}}
model: {type: lps, horizon_factor: 3.015}
materials: [{name: rock, density: 2600, youngs_modulus: 50 GPa, poisson_ratio: 0.25}]
loads:
  - {type: pressure, surface: xmin, history: {type: double_exponential, peak: 50 MPa, rise_time: 2 us, ratio: 5}}
  - {type: pressure, surface: zmax, history: {type: constant, value: 10 MPa}}
  - {type: traction, surface: xmax, value: [1 MPa, 2 MPa, 0], history: {type: ramp, value: 1, ramp_time: 3 us}}
  - {type: body_force, value: [0, 0, -9.81e3]}
indenter: {radius: 2 mm, center: [0.002, 0.002, 0.0045], velocity: [0, 0, -20], stiffness: 1e17}
time: {steps: 1}
)");
  const double t = 1.7e-6;  // inside every ramp and the blast's rise
  for (size_t k = 0; k < s.u.size(); ++k) s.u[k] = 1e-6 * std::sin(0.37 * static_cast<double>(k));
  compute_external(s, t);

  std::vector<double> body(s.body.size(), 0.0);
  for (const auto& sl : s.surface_loads) {
    const double h = sl.spec->history.at(t);
    for (const auto& f : sl.facets) {
      double force[3];
      facet_force(sl.spec->kind == LoadSpec::Kind::Pressure, h, f.area, f.normal, sl.spec->vector.data(), force);
      for (int d = 0; d < 3; ++d) body[3 * f.particle + d] += force[d] / s.volume[f.particle];
    }
  }
  for (const auto& bl : s.body_loads) {
    const double h = bl.spec->history.at(t);
    for (size_t i = 0; i < s.n; ++i)
      for (int d = 0; d < 3; ++d) body[3 * i + d] += s.density[i] * h * bl.spec->vector[d];
  }
  const IndenterSpec& ind = s.config.indenter;
  double c[3];
  for (int d = 0; d < 3; ++d) c[d] = ind.center[d] + ind.velocity[d] * t;
  int touched = 0;
  for (size_t i = 0; i < s.n; ++i) {
    const double before = body[3 * i + 2];
    add_indenter_force(s.x0.data(), s.u.data(), static_cast<int64_t>(i), c, ind.radius, ind.stiffness, body.data());
    touched += body[3 * i + 2] != before;
  }
  ASSERT_GT(touched, 0) << "the indenter must reach the block for its force to be compared";
  EXPECT_TRUE(bitwise_equal(body, s.body));
}

TEST(LoadKernels, PrescribedComponentsEqualTheCpuBackendBitForBit) {
  PdSystem s = system_from_yaml("constraints", R"(
specimen: {lattice: {dimension: 2, box: [0, 0, 0.01, 0.005], spacing: 0.5 mm, thickness: 1 mm}}
model: {type: pmb, planar: plane_stress, horizon_factor: 3.015}
materials: [{name: glass, density: 2440, youngs_modulus: 72 GPa, poisson_ratio: 0.3333333333333333}]
boundary:
  - {type: fixed, set: ymin}
  - {type: velocity, set: xmin, value: [-0.5, 0.25, 0], components: [x, y], ramp_time: 1 us}
  - {type: displacement, set: xmax, value: [1e-6, 0, 0], components: [x], ramp_time: 3 us}
time: {steps: 1}
)");
  for (size_t k = 0; k < s.u.size(); ++k) {
    s.u[k] = 1e-7 * std::cos(0.11 * static_cast<double>(k));
    s.v[k] = 0.1 * std::sin(0.23 * static_cast<double>(k));
  }
  std::vector<double> u = s.u, v = s.v;
  const double t = 0.6e-6, dt = 2e-8;  // mid-ramp for both ramped boundaries
  apply_constraints(s, t, dt);
  for (const auto& con : s.constraints) {
    const BoundarySpec& b = *con.spec;
    double velocity[3], target[3];
    prescribed_values(b, t, dt, velocity, target);
    for (auto i : con.particles)
      for (int d = 0; d < 3; ++d)
        if (b.components[d])
          constrain_component(static_cast<int>(b.kind), velocity[d], target[d], dt, u[3 * i + d], v[3 * i + d]);
  }
  EXPECT_TRUE(bitwise_equal(u, s.u));
  EXPECT_TRUE(bitwise_equal(v, s.v));
}
