// Loads act through surface facets; restart is bit-identical.
#include <gtest/gtest.h>

#include <cstring>

#include "breccia/solver/outputs.hpp"
#include "breccia/solver/run.hpp"
#include "helpers.hpp"

using namespace breccia::solver;
using namespace breccia::solver::testing;

namespace {
const char* kBoxWithPressure = R"(
specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.01, 0.008, 0.006], spacing: 1 mm}}
model: {type: lps, horizon_factor: 3.015}
materials: [{name: m, density: 2000, youngs_modulus: 10 GPa, poisson_ratio: 0.3}]
loads:
  - {type: pressure, surface: xmin, history: {type: constant, value: 2 MPa}}
  - {type: pressure, surface: xmax, history: {type: constant, value: 2 MPa}}
  - {type: pressure, surface: ymin, history: {type: constant, value: 2 MPa}}
  - {type: pressure, surface: ymax, history: {type: constant, value: 2 MPa}}
  - {type: pressure, surface: zmin, history: {type: constant, value: 2 MPa}}
  - {type: pressure, surface: zmax, history: {type: constant, value: 2 MPa}}
time: {steps: 1}
)";

void total_force(const PdSystem& s, double f[3]) {
  f[0] = f[1] = f[2] = 0;
  for (size_t i = 0; i < s.n; ++i)
    for (int d = 0; d < 3; ++d) f[d] += s.volume[i] * s.body[3 * i + d];
}
}  // namespace

TEST(Loads, PressureOnAClosedSurfaceHasZeroResultant) {
  PdSystem s = system_from_yaml("closed_pressure", kBoxWithPressure);
  compute_external(s, 0.0);
  double f[3];
  total_force(s, f);
  // Round-off relative to the force on one face (2 MPa x 80 mm2 = 160 N).
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(f[d], 0.0, 1e-12 * 160.0);
}

TEST(Loads, PressureOnAFlatFaceGivesPressureTimesArea) {
  std::string yaml = kBoxWithPressure;
  PdSystem s = system_from_yaml("face_pressure", yaml);
  s.surface_loads.resize(2);  // keep xmin and xmax only
  s.surface_loads.erase(s.surface_loads.begin());  // xmax alone
  compute_external(s, 0.0);
  double f[3];
  total_force(s, f);
  const double area = 0.008 * 0.006;
  EXPECT_NEAR(f[0], -2e6 * area, 1e-12 * 2e6 * area);  // pushes inward, against +x
  EXPECT_NEAR(f[1], 0.0, 1e-9);
}

TEST(Loads, DoubleExponentialPressurePeaksAtTheRiseTime) {
  // Seed 001 eq. 12 with the granite values: P0 150 MPa, t0 5 us, beta/alpha 5.
  HistorySpec h;
  h.kind = HistorySpec::Kind::DoubleExponential;
  h.value = 150e6;
  h.rise_time = 5e-6;
  h.ratio = 5.0;
  EXPECT_NEAR(h.at(5e-6), 150e6, 1e-6);
  EXPECT_LT(h.at(4.9e-6), 150e6);
  EXPECT_LT(h.at(5.1e-6), 150e6);
  // benchmarks.md section 4: P falls to 50 % at 16.3 us (derived there).
  EXPECT_NEAR(h.at(16.3e-6) / 150e6, 0.5, 0.01);
}

TEST(Restart, HalfRunsWithACheckpointEqualOneStraightRunBitForBit) {
  const std::string case_file =
      write_case("restart", kPrecrackedGlassPlateDeck + "time: {steps: 400}\noutput: {every: 100, history_every: 20}\n");
  const CaseConfig config = parse_case_file(case_file);
  auto [straight, second] = straight_and_restarted(config, "restart", 200);
  ASSERT_GT(measure(straight).broken_half_bonds, 0) << "the case should break bonds";
  expect_same_motion(second, straight);
  EXPECT_EQ(second.dissipated_energy, straight.dissipated_energy);
}

TEST(Loads, RigidIndenterPushesOverlappingParticlesWithLammpsIndentForce) {
  // LAMMPS fix indent: F(r) = -K (r - R)^2 for r < R, along the radius, here per unit volume.
  PdSystem s = system_from_yaml("indenter", R"(
specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.004, 0.004, 0.004], spacing: 1 mm}}
model: {type: pmb, horizon_factor: 3.015}
materials: [{name: m, density: 2000, youngs_modulus: 10 GPa, poisson_ratio: 0.25}]
indenter: {radius: 1 mm, center: [0.0015, 0.0015, 0.0048], velocity: [0, 0, -10], stiffness: 1e15}
time: {steps: 1}
)");
  const double t = 1e-5;  // the sphere has moved 0.1 mm down: centre z = 4.7 mm
  compute_external(s, t);
  const int64_t top = nearest(s, 0.0015, 0.0015, 0.0035);  // 1.2 mm below the centre: outside
  EXPECT_EQ(s.body[3 * top + 2], 0.0);
  s.u[3 * top + 2] = 0.0003;  // now 0.9 mm below the centre: 0.1 mm inside the sphere
  compute_external(s, t);
  const double expected = -1e15 * 0.0001 * 0.0001;  // pushed down, out of the sphere
  EXPECT_NEAR(s.body[3 * top + 2], expected, 1e-9 * std::fabs(expected));
  EXPECT_NEAR(s.body[3 * top], 0.0, 1e-9 * std::fabs(expected));
}
