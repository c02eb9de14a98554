// Pressure through the facets of a real gmsh mesh: the concrete block's blind charge hole.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <numbers>

#include "breccia/common/particle_file.hpp"
#include "helpers.hpp"

using namespace breccia;
using namespace breccia::solver;
using namespace breccia::solver::testing;

TEST(Loads, PressureInABlindHoleOfAMeshPushesOnlyOnTheHoleBottom) {
  // The hole wall is closed around the axis, so its pressure resultant vanishes; what is
  // left is P times the (faceted) bottom disc, pointing down into the block.
  const std::string dir = ::testing::TempDir() + "/mesh_loads";
  std::filesystem::create_directories(dir);
  const std::string spec = std::string(BRECCIA_SOURCE_DIR) + "/cases/concrete-blast/specimen-quick.yaml";
  const std::string cmd = std::string(BRECCIA_MESH_EXE) + " " + spec + " -o " + dir + "/s.msh --quiet > /dev/null 2>&1 && " +
                          BRECCIA_PLACE_EXE + " " + dir + "/s.msh -o " + dir + "/particles.h5 > /dev/null 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  PdSystem s = system_from_yaml("mesh_loads", "specimen: {particles: " + dir + "/particles.h5}\n"
      "model: {type: lps, horizon_factor: 3.015}\n"
      "materials: [{name: concrete, density: 2320, youngs_modulus: 34.2 GPa, poisson_ratio: 0.25}]\n"
      "loads: [{type: pressure, surface: charge_hole, history: {type: constant, value: 1 GPa}}]\n"
      "time: {steps: 1}\n");
  compute_external(s, 0.0);
  double f[3] = {0, 0, 0};
  for (size_t i = 0; i < s.n; ++i)
    for (int d = 0; d < 3; ++d) f[d] += s.volume[i] * s.body[3 * i + d];
  // Exactly P times the area of the hole's bottom facets (round-off) ...
  const SurfaceFacets* hole = s.particles.find_surface("charge_hole");
  double bottom = 0, wall = 0;
  for (size_t k = 0; k < hole->size(); ++k) {
    wall += hole->area_m2[k] * 1e9;
    if (hole->normal[3 * k + 2] > 0.999) bottom += hole->area_m2[k];
  }
  EXPECT_NEAR(f[2], -1e9 * bottom, 1e-9 * wall) << "vertical resultant " << f[2] << " N";
  // ... and that area is the faceted disc of radius 10 mm: a polygon of 7 or more sides
  // inscribed in the circle holds between 0.871 (heptagon) and 1 of pi r^2.
  const double ratio = bottom / (std::numbers::pi * 0.01 * 0.01);
  EXPECT_GT(ratio, 0.85);
  EXPECT_LE(ratio, 1.0);
  // The wall's sideways resultant cancels: round-off against the wall's total |force|.
  EXPECT_LT(std::hypot(f[0], f[1]), 1e-9 * wall);
}
