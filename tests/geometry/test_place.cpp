// Mesh -> particles: volumes, counts, sets, surfaces and normals of meshes built with gmsh.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <numeric>

#include "breccia/common/error.hpp"
#include "breccia/geometry/place.hpp"
#include "test_meshes.hpp"

namespace breccia::geometry {
namespace {

using testing::BlockWithHole;
using testing::PlateWithHole;

std::string temp_path(const std::string& name) { return testing::scratch_dir() + "/" + name; }

[[maybe_unused]] ::testing::Environment* const kCleanup =
    ::testing::AddGlobalTestEnvironment(new testing::RemoveScratchDir);

double total(const std::vector<double>& v) { return std::accumulate(v.begin(), v.end(), 0.0); }

// Area-weighted normal sum of some surfaces: zero for a closed surface (divergence
// theorem applied to a constant field).
std::array<double, 3> weighted_normal_sum(const ParticleModel& m, const std::vector<std::string>& names) {
  std::array<double, 3> sum{0, 0, 0};
  for (const auto& name : names) {
    const SurfaceFacets* s = m.find_surface(name);
    EXPECT_NE(s, nullptr) << name;
    if (!s) continue;
    for (size_t f = 0; f < s->size(); ++f)
      for (int k = 0; k < 3; ++k) sum[k] += s->area_m2[f] * s->normal[3 * f + k];
  }
  return sum;
}

// The hole is inscribed in the cylinder (its nodes lie on it), so the mesh removes less
// than the exact hole. A chord s subtending theta = s / r cuts off r^2 theta^3 / 12 of
// the disc; over 2 pi / theta chords that is pi s^2 / 6. gmsh's edges stay below 1.5 h.
double hole_area_deficit_bound(double mesh_size) { return M_PI * std::pow(1.5 * mesh_size, 2) / 6.0; }
// The inscribed polygon's perimeter falls short by 1 - sin(theta/2)/(theta/2) <= theta^2/24.
double hole_perimeter_relative_bound(double mesh_size, double radius) { return std::pow(1.5 * mesh_size / radius, 2) / 24.0; }

class BlockWithHoleModel : public ::testing::Test {
protected:
  static void SetUpTestSuite() {
    path_ = new std::string(temp_path("block.msh"));
    testing::write_block_with_hole(*path_, block_);
    reference_ = new testing::MeshMeasure(testing::measure_msh(*path_, 4));
    model_ = new ParticleModel(place_particles(*path_, PlaceOptions{}));
  }
  static void TearDownTestSuite() {
    delete model_;
    delete reference_;
    delete path_;
  }
  static inline const BlockWithHole block_{};
  static inline std::string* path_ = nullptr;
  static inline testing::MeshMeasure* reference_ = nullptr;
  static inline ParticleModel* model_ = nullptr;
};

TEST_F(BlockWithHoleModel, OneParticlePerTetrahedron) {
  EXPECT_EQ(model_->size(), reference_->elements);
  EXPECT_EQ(model_->mesh_cells.size(), 4 * reference_->elements);
  EXPECT_EQ(model_->nodes_per_cell, 4);
  EXPECT_EQ(model_->dimension, 3);
}

TEST_F(BlockWithHoleModel, ParticleVolumesSumToTheMeshVolume) {
  // Same tets, same doubles, different summation order: round-off only.
  EXPECT_NEAR(total(model_->volume_m3), reference_->total, 1e-12 * reference_->total);
}

TEST_F(BlockWithHoleModel, ParticleVolumesApproachTheAnalyticVolumeFromAbove) {
  const double excess = total(model_->volume_m3) - block_.volume();
  EXPECT_GE(excess, -1e-12 * block_.volume());  // inscribed hole: never more removed than the cylinder
  EXPECT_LE(excess, hole_area_deficit_bound(block_.mesh_size_m) * block_.height_m);
}

TEST_F(BlockWithHoleModel, VolumeWeightedCentroidIsTheBodyCentroid) {
  // The body is symmetric about its centre; only the faceted hole can shift the centroid,
  // by at most (volume deficit) x (hole radius) / volume.
  const double v = total(model_->volume_m3);
  const double centre[3] = {0.5 * block_.length_m, 0.5 * block_.width_m, 0.5 * block_.height_m};
  const double tolerance = hole_area_deficit_bound(block_.mesh_size_m) * block_.height_m * block_.hole_radius_m / v;
  for (int k = 0; k < 3; ++k) {
    double moment = 0;
    for (size_t i = 0; i < model_->size(); ++i) moment += model_->volume_m3[i] * model_->position_m[3 * i + k];
    EXPECT_NEAR(moment / v, centre[k], tolerance) << "axis " << k;
  }
}

TEST_F(BlockWithHoleModel, SpacingIsTheCubeRootOfVolume) {
  for (size_t i = 0; i < model_->size(); ++i)
    ASSERT_NEAR(std::pow(model_->spacing_m[i], 3), model_->volume_m3[i], 1e-14 * model_->volume_m3[i])
        << "particle " << i;  // cbrt then cube: a few ulp
}

TEST_F(BlockWithHoleModel, EveryPhysicalGroupIsANonEmptySet) {
  for (const char* name : {"concrete", "sides", "caps", "hole", "corner"}) {
    const ParticleSet* s = model_->find_set(name);
    ASSERT_NE(s, nullptr) << name;
    EXPECT_FALSE(s->indices.empty()) << name;
    EXPECT_TRUE(std::is_sorted(s->indices.begin(), s->indices.end())) << name;
  }
  EXPECT_EQ(model_->find_set("concrete")->indices.size(), model_->size());
  ASSERT_EQ(model_->material_names.size(), 1u);
  EXPECT_EQ(model_->material_names[0], "concrete");
}

TEST_F(BlockWithHoleModel, PlanarSideFacesHaveTheirExactArea) {
  // Flat faces are tiled exactly by their triangles: round-off only.
  EXPECT_NEAR(total(model_->find_surface("sides")->area_m2), block_.side_area(), 1e-12 * block_.side_area());
}

TEST_F(BlockWithHoleModel, HoleWallAreaWithinMeshingError) {
  const double area = total(model_->find_surface("hole")->area_m2);
  EXPECT_LE(area, block_.hole_wall_area() * (1 + 1e-12));  // inscribed facets
  EXPECT_NEAR(area, block_.hole_wall_area(),
              block_.hole_wall_area() * hole_perimeter_relative_bound(block_.mesh_size_m, block_.hole_radius_m));
}

TEST_F(BlockWithHoleModel, ClosedBoundaryNormalsSumToZero) {
  const auto sum = weighted_normal_sum(*model_, {"sides", "caps", "hole"});
  const double area = total(model_->find_surface("sides")->area_m2) + total(model_->find_surface("caps")->area_m2) +
                      total(model_->find_surface("hole")->area_m2);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(sum[k], 0.0, 1e-12 * area) << "axis " << k;  // round-off of the sum
}

TEST_F(BlockWithHoleModel, FacetNormalsPointOutOfTheBody) {
  for (const auto& s : model_->surfaces) {
    for (size_t f = 0; f < s.size(); ++f) {
      const double* n = &s.normal[3 * f];
      ASSERT_NEAR(std::hypot(n[0], n[1], n[2]), 1.0, 1e-12);  // unit
      // The owning particle (cell centroid) lies behind the facet.
      const double* c = &s.centroid_m[3 * f];
      const double* x = &model_->position_m[3 * s.particle[f]];
      ASSERT_LT(n[0] * (x[0] - c[0]) + n[1] * (x[1] - c[1]) + n[2] * (x[2] - c[2]), 0.0) << s.name << " facet " << f;
    }
  }
  // On the hole wall "out of the body" is towards the hole axis.
  const SurfaceFacets* hole = model_->find_surface("hole");
  for (size_t f = 0; f < hole->size(); ++f) {
    const double rx = hole->centroid_m[3 * f] - block_.hole_x(), ry = hole->centroid_m[3 * f + 1] - block_.hole_y();
    EXPECT_LT(hole->normal[3 * f] * rx + hole->normal[3 * f + 1] * ry, 0.0);
  }
}

// Each facet's stored vertices are three nodes of its owner tetrahedron whose mean is the
// centroid, whose cross product is twice the area along the normal (either sign: the normal
// was turned away from the owner). Tolerances: round-off of sums of a few products.
TEST_F(BlockWithHoleModel, FacetVerticesAreTheOwnersFaceWithTheFacetsCentroidAreaAndNormal) {
  for (const auto& s : model_->surfaces) {
    ASSERT_EQ(s.vertices_m.size(), 9 * s.size()) << s.name;
    for (size_t f = 0; f < s.size(); ++f) {
      const double* a = &s.vertices_m[9 * f];
      const double *b = a + 3, *c = a + 6;
      const double scale = std::sqrt(s.area_m2[f]);
      for (int k = 0; k < 3; ++k)
        ASSERT_NEAR((a[k] + b[k] + c[k]) / 3.0, s.centroid_m[3 * f + k], 1e-12 * scale) << s.name << " facet " << f;
      const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
      const double cross[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
      const double* n = &s.normal[3 * f];
      const double along = cross[0] * n[0] + cross[1] * n[1] + cross[2] * n[2];
      ASSERT_NEAR(std::fabs(along), 2.0 * s.area_m2[f], 1e-9 * s.area_m2[f]) << s.name << " facet " << f;
      for (const double* v : {a, b, c}) {  // a node of the owner cell
        bool found = false;
        for (int k = 0; k < 4 && !found; ++k) {
          const double* x = &model_->mesh_nodes_m[3 * model_->mesh_cells[4 * s.particle[f] + k]];
          found = x[0] == v[0] && x[1] == v[1] && x[2] == v[2];
        }
        ASSERT_TRUE(found) << s.name << " facet " << f;
      }
    }
  }
}

TEST_F(BlockWithHoleModel, MeshNodesAreCompactAndZeroBased) {
  const int64_t nodes = static_cast<int64_t>(model_->mesh_nodes_m.size() / 3);
  std::vector<char> used(nodes, 0);
  for (int64_t v : model_->mesh_cells) {
    ASSERT_GE(v, 0);
    ASSERT_LT(v, nodes);
    used[v] = 1;
  }
  EXPECT_TRUE(std::all_of(used.begin(), used.end(), [](char u) { return u == 1; }));
}

TEST(MeshFormats, Msh22AndMsh41GiveTheSameParticles) {
  const BlockWithHole block{1.0, 0.6, 0.4, 0.1, 0.15};
  const std::string v41 = temp_path("block41.msh"), v22 = temp_path("block22.msh");
  testing::write_block_with_hole(v41, block, 4.1);
  testing::write_block_with_hole(v22, block, 2.2);
  const ParticleModel a = place_particles(v41, {});
  const ParticleModel b = place_particles(v22, {});
  ASSERT_EQ(a.size(), b.size());
  // gmsh writes coordinates with 16 significant digits in both formats.
  EXPECT_NEAR(total(a.volume_m3), total(b.volume_m3), 1e-12 * total(a.volume_m3));
  for (const char* name : {"sides", "caps", "hole"})
    EXPECT_EQ(a.find_surface(name)->size(), b.find_surface(name)->size()) << name;
}

TEST(EmbeddedNotch, IsKeptAsASurfaceWithNormalsAwayFromTheOwner) {
  const std::string path = temp_path("notch.msh");
  testing::write_cube_with_notch(path, 0.15);
  const ParticleModel m = place_particles(path, {});
  const SurfaceFacets* notch = m.find_surface("notch");
  ASSERT_NE(notch, nullptr);
  ASSERT_GT(notch->size(), 0u);
  EXPECT_NEAR(total(notch->area_m2), 0.25, 1e-12);  // flat 0.5 m x 0.5 m, tiled exactly
  const double first_nz = notch->normal[2];
  for (size_t f = 0; f < notch->size(); ++f) {
    const double* n = &notch->normal[3 * f];
    EXPECT_NEAR(std::abs(n[2]), 1.0, 1e-12);  // the plane z = 0.5
    EXPECT_EQ(n[2] > 0, first_nz > 0) << "gmsh orients one surface consistently";
    const double* x = &m.position_m[3 * notch->particle[f]];
    EXPECT_LT(n[2] * (x[2] - 0.5), 0.0) << "owner behind the facet, facet " << f;
  }
  const ParticleSet* set = m.find_set("notch");
  ASSERT_NE(set, nullptr);
  EXPECT_FALSE(set->indices.empty());
}

TEST(EmbeddedNotch, EveryNotchFacetHasACellOnEachSide) {
  // A conforming pre-crack: the notch's triangles are interior faces, so counting the tet
  // faces lying in the notch rectangle from above and from below gives the facet count
  // twice, and the volume is still exactly that of the cube.
  const std::string path = temp_path("notch_sides.msh");
  testing::write_cube_with_notch(path, 0.2);
  const ParticleModel m = place_particles(path, {});
  EXPECT_NEAR(total(m.volume_m3), 1.0, 1e-12);  // polyhedral cube: exact up to round-off
  const auto on_plane = [&](int64_t v) { return std::abs(m.mesh_nodes_m[3 * v + 2] - 0.5) < 1e-12; };
  size_t above = 0, below = 0;
  for (size_t c = 0; c < m.size(); ++c) {
    const int64_t* v = &m.mesh_cells[4 * c];
    for (int opposite = 0; opposite < 4; ++opposite) {
      double cx = 0, cy = 0;
      bool flat = true;
      for (int k = 0; k < 4; ++k) {
        if (k == opposite) continue;
        flat &= on_plane(v[k]);
        cx += m.mesh_nodes_m[3 * v[k]] / 3;
        cy += m.mesh_nodes_m[3 * v[k] + 1] / 3;
      }
      if (!flat || cx > 0.5 || cy < 0.25 || cy > 0.75) continue;
      (m.mesh_nodes_m[3 * v[opposite] + 2] > 0.5 ? above : below)++;
    }
  }
  const size_t facets = m.find_surface("notch")->size();
  EXPECT_EQ(above, facets);
  EXPECT_EQ(below, facets);
}

TEST(TwoDimensionalMesh, VolumeIsTriangleAreaTimesThickness) {
  const PlateWithHole plate{};
  const std::string path = temp_path("plate.msh");
  testing::write_plate_with_hole(path, plate);
  const testing::MeshMeasure reference = testing::measure_msh(path, 2);
  const double thickness = 0.005;
  PlaceOptions options;
  options.thickness_m = thickness;
  const ParticleModel m = place_particles(path, options);
  EXPECT_EQ(m.dimension, 2);
  EXPECT_EQ(m.nodes_per_cell, 3);
  EXPECT_DOUBLE_EQ(m.thickness_m, thickness);
  ASSERT_EQ(m.size(), reference.elements);
  EXPECT_NEAR(total(m.volume_m3), reference.total * thickness, 1e-12 * reference.total * thickness);
  const double excess = total(m.volume_m3) / thickness - plate.area();
  EXPECT_GE(excess, -1e-12 * plate.area());
  EXPECT_LE(excess, hole_area_deficit_bound(plate.mesh_size_m));
  for (size_t i = 0; i < m.size(); ++i) {
    ASSERT_NEAR(m.spacing_m[i] * m.spacing_m[i] * thickness, m.volume_m3[i], 1e-14 * m.volume_m3[i]);  // sqrt: ulps
    ASSERT_EQ(m.position_m[3 * i + 2], 0.0);
  }
}

TEST(TwoDimensionalMesh, EdgeFacetsCarryLengthTimesThicknessAndOutwardNormals) {
  const PlateWithHole plate{};
  const std::string path = temp_path("plate_edges.msh");
  testing::write_plate_with_hole(path, plate);
  const double thickness = 0.005;
  PlaceOptions options;
  options.thickness_m = thickness;
  const ParticleModel m = place_particles(path, options);
  const double perimeter = 2 * (plate.length_m + plate.width_m);
  EXPECT_NEAR(total(m.find_surface("edges")->area_m2), perimeter * thickness, 1e-12 * perimeter * thickness);
  const double circle = 2 * M_PI * plate.hole_radius_m * thickness;
  EXPECT_NEAR(total(m.find_surface("hole")->area_m2), circle,
              circle * hole_perimeter_relative_bound(plate.mesh_size_m, plate.hole_radius_m));
  const auto sum = weighted_normal_sum(m, {"edges", "hole"});
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(sum[k], 0.0, 1e-12 * perimeter * thickness);  // closed: round-off
  for (const auto& s : m.surfaces)
    for (size_t f = 0; f < s.size(); ++f) {
      const double* n = &s.normal[3 * f];
      const double* c = &s.centroid_m[3 * f];
      const double* x = &m.position_m[3 * s.particle[f]];
      ASSERT_EQ(n[2], 0.0);
      ASSERT_LT(n[0] * (x[0] - c[0]) + n[1] * (x[1] - c[1]), 0.0) << s.name << " facet " << f;
      // The edge's two vertices: their mean is the centroid, their distance the length.
      ASSERT_EQ(s.vertices_m.size(), 6 * s.size());
      const double* v = &s.vertices_m[6 * f];
      const double length = s.area_m2[f] / thickness;
      EXPECT_NEAR(std::hypot(v[3] - v[0], v[4] - v[1]), length, 1e-12 * length);
      for (int k = 0; k < 3; ++k) EXPECT_NEAR(0.5 * (v[k] + v[3 + k]), c[k], 1e-12 * length);
    }
  for (const char* name : {"plate", "edges", "hole"}) {
    ASSERT_NE(m.find_set(name), nullptr) << name;
    EXPECT_FALSE(m.find_set(name)->indices.empty()) << name;
  }
}

TEST(MaterialGroups, VolumeGroupsChooseMaterialsWhenGroupsOverlap) {
  // Two boxes, groups "left", "right" and "all" (overlapping): without --volume-groups the
  // cell would have two materials, which is an error; with left,right it is not.
  testing::start_gmsh();
  gmsh::model::add("two");
  const int a = gmsh::model::occ::addBox(0, 0, 0, 1, 1, 1);
  const int b = gmsh::model::occ::addBox(1, 0, 0, 1, 1, 1);
  gmsh::vectorpair out;
  std::vector<gmsh::vectorpair> out_map;
  gmsh::model::occ::fragment({{3, a}}, {{3, b}}, out, out_map);
  gmsh::model::occ::synchronize();
  gmsh::model::addPhysicalGroup(3, {a}, 1);
  gmsh::model::setPhysicalName(3, 1, "left");
  gmsh::model::addPhysicalGroup(3, {b}, 2);
  gmsh::model::setPhysicalName(3, 2, "right");
  gmsh::model::addPhysicalGroup(3, {a, b}, 3);
  gmsh::model::setPhysicalName(3, 3, "all");
  gmsh::option::setNumber("Mesh.MeshSizeMax", 0.4);
  gmsh::model::mesh::generate(3);
  const std::string path = temp_path("two_boxes.msh");
  gmsh::write(path);

  EXPECT_THROW(place_particles(path, {}), InputError);
  PlaceOptions options;
  options.volume_groups = {"left", "right"};
  const ParticleModel m = place_particles(path, options);
  ASSERT_EQ(m.material_names.size(), 2u);
  double volume[2] = {0, 0};
  for (size_t i = 0; i < m.size(); ++i) {
    volume[m.material_id[i]] += m.volume_m3[i];
    // Left box x < 1, right box x > 1: the centroid tells the material.
    EXPECT_EQ(m.material_names[m.material_id[i]], m.position_m[3 * i] < 1.0 ? "left" : "right");
  }
  EXPECT_NEAR(volume[0], 1.0, 1e-12);  // unit boxes, polyhedral: exact up to round-off
  EXPECT_NEAR(volume[1], 1.0, 1e-12);
  EXPECT_EQ(m.find_set("all")->indices.size(), m.size());
}

}  // namespace
}  // namespace breccia::geometry
