// Regular lattices: exact spacing and volumes, boundary layers, facets and normals.
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>

#include "breccia/common/error.hpp"
#include "breccia/geometry/lattice.hpp"

namespace breccia::geometry {
namespace {

double total(const std::vector<double>& v) { return std::accumulate(v.begin(), v.end(), 0.0); }

TEST(CubicLattice, ParticlesSitAtCellCentresWithExactVolume) {
  const double dx = 0.1;
  const ParticleModel m = make_cubic_lattice({-0.5, 0, 1}, {0.5, 0.5, 1.3}, dx);
  ASSERT_EQ(m.size(), 10u * 5u * 3u);
  EXPECT_EQ(m.dimension, 3);
  EXPECT_EQ(m.nodes_per_cell, 0);
  for (size_t i = 0; i < m.size(); ++i) {
    ASSERT_EQ(m.volume_m3[i], dx * dx * dx);
    ASSERT_EQ(m.spacing_m[i], dx);
  }
  EXPECT_NEAR(total(m.volume_m3), 1.0 * 0.5 * 0.3, 1e-12);  // box volume, round-off of 150 terms
  // Index runs x fastest: neighbours along x, y, z are 1, nx, nx*ny apart, exactly dx away
  // (to the round-off of lower + (i + 1/2) dx).
  const size_t nx = 10, ny = 5;
  const size_t stride[3] = {1, nx, nx * ny};
  for (int axis = 0; axis < 3; ++axis)
    for (int other = 0; other < 3; ++other) {
      const double d = m.position_m[3 * stride[axis] + other] - m.position_m[other];
      EXPECT_NEAR(d, axis == other ? dx : 0.0, 1e-15) << "axis " << axis << " component " << other;
    }
  EXPECT_NEAR(m.position_m[0], -0.5 + 0.5 * dx, 1e-15);
  EXPECT_NEAR(m.position_m[2], 1.0 + 0.5 * dx, 1e-15);
}

TEST(CubicLattice, FaceSetsAreTheOutermostLayers) {
  const double dx = 0.1;
  const ParticleModel m = make_cubic_lattice({0, 0, 0}, {1.0, 0.5, 0.3}, dx);
  const struct { const char* name; int axis; double coordinate; size_t count; } faces[] = {
      {"xmin", 0, 0.05, 15}, {"xmax", 0, 0.95, 15}, {"ymin", 1, 0.05, 30},
      {"ymax", 1, 0.45, 30}, {"zmin", 2, 0.05, 50}, {"zmax", 2, 0.25, 50}};
  for (const auto& f : faces) {
    const ParticleSet* s = m.find_set(f.name);
    ASSERT_NE(s, nullptr) << f.name;
    EXPECT_EQ(s->indices.size(), f.count) << f.name;
    for (auto p : s->indices) ASSERT_NEAR(m.position_m[3 * p + f.axis], f.coordinate, 1e-12) << f.name;
  }
}

TEST(CubicLattice, BoundaryFacetsTileTheBoxSurfaceAndCloseIt) {
  const double dx = 0.1;
  const ParticleModel m = make_cubic_lattice({0, 0, 0}, {1.0, 0.5, 0.3}, dx);
  double area = 0;
  double weighted_normal[3] = {0, 0, 0};
  for (const auto& s : m.surfaces) {
    const ParticleSet* set = m.find_set(s.name);
    ASSERT_NE(set, nullptr);
    EXPECT_EQ(s.particle, set->indices) << "one facet per boundary particle";
    for (size_t f = 0; f < s.size(); ++f) {
      ASSERT_EQ(s.area_m2[f], dx * dx);
      area += s.area_m2[f];
      for (int k = 0; k < 3; ++k) weighted_normal[k] += s.area_m2[f] * s.normal[3 * f + k];
      // Outward: the facet centroid is half a spacing beyond its particle along the normal.
      for (int k = 0; k < 3; ++k)
        ASSERT_NEAR(s.centroid_m[3 * f + k] - m.position_m[3 * s.particle[f] + k], 0.5 * dx * s.normal[3 * f + k], 1e-12);
    }
  }
  EXPECT_NEAR(area, 2 * (1.0 * 0.5 + 1.0 * 0.3 + 0.5 * 0.3), 1e-12);  // box surface area
  for (double w : weighted_normal) EXPECT_NEAR(w, 0.0, 1e-12);         // closed surface
}

TEST(SquareLattice, VolumesAreSpacingSquaredTimesThickness) {
  const double dx = 0.01, thickness = 0.005;
  const ParticleModel m = make_square_lattice({0, 0}, {0.4, 0.2}, dx, thickness);
  ASSERT_EQ(m.size(), 40u * 20u);
  EXPECT_EQ(m.dimension, 2);
  EXPECT_EQ(m.thickness_m, thickness);
  for (size_t i = 0; i < m.size(); ++i) {
    ASSERT_EQ(m.volume_m3[i], dx * dx * thickness);
    ASSERT_EQ(m.position_m[3 * i + 2], 0.0);
  }
  EXPECT_NEAR(total(m.volume_m3), 0.4 * 0.2 * thickness, 1e-15);  // plate volume, round-off
  EXPECT_EQ(m.find_set("zmin"), nullptr);
  EXPECT_EQ(m.find_set("xmin")->indices.size(), 20u);
  EXPECT_EQ(m.find_set("ymax")->indices.size(), 40u);
  double area = 0;
  for (const auto& s : m.surfaces)
    for (size_t f = 0; f < s.size(); ++f) {
      ASSERT_EQ(s.area_m2[f], dx * thickness);  // edge length x thickness
      ASSERT_EQ(s.normal[3 * f + 2], 0.0);
      area += s.area_m2[f];
    }
  EXPECT_NEAR(area, 2 * (0.4 + 0.2) * thickness, 1e-15);  // perimeter x thickness
}

TEST(Lattice, BoxThatIsNotAWholeNumberOfSpacingsIsRejected) {
  try {
    make_cubic_lattice({0, 0, 0}, {1.05, 1, 1}, 0.1);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("--box x"), std::string::npos) << message;
    EXPECT_NE(message.find("10.5"), std::string::npos) << message;
  }
  EXPECT_THROW(make_cubic_lattice({0, 0, 0}, {1, 1, 1}, 0.0), InputError);
  EXPECT_THROW(make_square_lattice({0, 0}, {1, -1}, 0.1, 0.01), InputError);
  EXPECT_THROW(make_square_lattice({0, 0}, {1, 1}, 0.1, 0.0), InputError);
}

}  // namespace
}  // namespace breccia::geometry
