// The set-up's geometry on a surface's real facets (CGAL's AABB tree): `surface` pre-cracks
// and `near_surface` / `material` sets, each against a brute-force answer written here, and
// particle files without facet vertices (older files, lattices) handled by their fallbacks.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include "breccia/common/error.hpp"
#include "breccia/common/particle_file.hpp"
#include "helpers.hpp"

using namespace breccia::solver;
using namespace breccia::solver::testing;
using breccia::ParticleModel;
using breccia::SurfaceFacets;

namespace {

using P3 = std::array<double, 3>;

P3 sub(const P3& a, const P3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
double dot(const P3& a, const P3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// Distance from p to the closed segment a-b.
double segment_distance(const P3& p, const P3& a, const P3& b) {
  const P3 ab = sub(b, a), ap = sub(p, a);
  const double t = std::clamp(dot(ap, ab) / dot(ab, ab), 0.0, 1.0);
  const P3 d = {ap[0] - t * ab[0], ap[1] - t * ab[1], ap[2] - t * ab[2]};
  return std::sqrt(dot(d, d));
}

// Distance from p to the triangle abc: to its plane when the foot lies inside (barycentric
// test), else to the nearest of its edges.
double triangle_distance(const P3& p, const P3& a, const P3& b, const P3& c) {
  const P3 ab = sub(b, a), ac = sub(c, a), ap = sub(p, a);
  const double d00 = dot(ab, ab), d01 = dot(ab, ac), d11 = dot(ac, ac), d20 = dot(ap, ab), d21 = dot(ap, ac);
  const double den = d00 * d11 - d01 * d01;
  const double v = (d11 * d20 - d01 * d21) / den, w = (d00 * d21 - d01 * d20) / den;
  if (v >= 0 && w >= 0 && v + w <= 1) {
    const P3 foot = {a[0] + v * ab[0] + w * ac[0], a[1] + v * ab[1] + w * ac[1], a[2] + v * ab[2] + w * ac[2]};
    const P3 d = sub(p, foot);
    return std::sqrt(dot(d, d));
  }
  return std::min({segment_distance(p, a, b), segment_distance(p, b, c), segment_distance(p, c, a)});
}

P3 vertex(const std::vector<double>& v, size_t k) { return {v[3 * k], v[3 * k + 1], v[3 * k + 2]}; }

// A 3D grid of 1 mm cells, 10 x 10 x 10, three materials by position, and a curved surface
// "fold" of triangles (two slanted strips meeting along a ridge) written with its vertices.
std::string write_grid_with_fold(const std::string& name) {
  ParticleModel m;
  m.dimension = 3;
  const double h = 1e-3;
  for (int k = 0; k < 10; ++k)
    for (int j = 0; j < 10; ++j)
      for (int i = 0; i < 10; ++i) {
        m.position_m.insert(m.position_m.end(), {(i + 0.5) * h, (j + 0.5) * h, (k + 0.5) * h});
        m.volume_m3.push_back(h * h * h);
        m.material_id.push_back(i < 3 ? 0 : (k < 5 ? 1 : 2));
      }
  m.material_names = {"rock", "steel", "glue"};
  SurfaceFacets fold;
  fold.name = "fold";
  const double ridge_x = 5.1e-3, ridge_z = 6.3e-3, foot_z = 2.2e-3;
  for (int strip = 0; strip < 4; ++strip) {  // along y, each strip two triangles per side
    const double y0 = 1.3e-3 + 2e-3 * strip, y1 = y0 + 2e-3;
    for (int side = -1; side <= 1; side += 2) {
      const double xf = ridge_x + side * 3.7e-3;
      const P3 a = {ridge_x, y0, ridge_z}, b = {ridge_x, y1, ridge_z}, c = {xf, y1, foot_z}, d = {xf, y0, foot_z};
      for (const auto& tri : {std::array<P3, 3>{a, b, c}, std::array<P3, 3>{a, c, d}}) {
        for (const P3& v : tri) fold.vertices_m.insert(fold.vertices_m.end(), v.begin(), v.end());
        const P3 u = sub(tri[1], tri[0]), w = sub(tri[2], tri[0]);
        const P3 n = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
        const double len = std::sqrt(dot(n, n));
        fold.area_m2.push_back(0.5 * len);
        for (int q = 0; q < 3; ++q) {
          fold.normal.push_back(n[q] / len);
          fold.centroid_m.push_back((tri[0][q] + tri[1][q] + tri[2][q]) / 3.0);
        }
        fold.particle.push_back(0);  // the owner plays no part in distances
      }
    }
  }
  m.surfaces.push_back(fold);
  const std::string path = process_temp_dir() + "/" + name + "/particles.h5";
  breccia::write_particle_file(path, m);
  return path;
}

std::string head(const std::string& particles) {
  return "specimen: {particles: " + particles + "}\nmodel: {type: pmb, horizon_factor: 3.015}\n"
         "materials:\n"
         "  - {name: rock, density: 2000, youngs_modulus: 30 GPa, poisson_ratio: 0.25}\n"
         "  - {name: steel, density: 7800, youngs_modulus: 200 GPa, poisson_ratio: 0.25}\n"
         "  - {name: glue, density: 1200, youngs_modulus: 3 GPa, poisson_ratio: 0.25}\n"
         "time: {steps: 1}\n";
}

const std::vector<int64_t>& set_of(const PdSystem& s, const std::string& name) {
  static const std::vector<int64_t> none;
  const breccia::ParticleSet* set = s.particles.find_set(name);
  EXPECT_NE(set, nullptr) << name;
  return set ? set->indices : none;
}

std::string error_of(const std::string& name, const std::string& yaml) {
  try {
    system_from_yaml(name, yaml);
  } catch (const breccia::InputError& e) {
    return e.what();
  }
  return "no error";
}

}  // namespace

TEST(CaseSets, NearSurfaceAndMaterialSelectWhatBruteForceSelects) {
  const std::string particles = write_grid_with_fold("fold_grid");
  const double limit = 1.3e-3;
  const PdSystem s = system_from_yaml("near_fold", head(particles) +
      "sets:\n"
      "  - {name: near, near_surface: {surface: fold, distance: 1.3 mm}}\n"
      "  - {name: soft, material: [rock, glue]}\n"
      "  - {name: near_soft, intersection: [near, soft]}\n");
  const ParticleModel& pm = s.particles;
  const SurfaceFacets& fold = *pm.find_surface("fold");
  std::vector<int64_t> near, soft, near_soft;
  size_t borderline = 0;
  for (size_t i = 0; i < pm.size(); ++i) {
    const P3 p = vertex(pm.position_m, i);
    double d = 1e300;
    for (size_t f = 0; f < fold.size(); ++f)
      d = std::min(d, triangle_distance(p, vertex(fold.vertices_m, 3 * f), vertex(fold.vertices_m, 3 * f + 1),
                                        vertex(fold.vertices_m, 3 * f + 2)));
    // Distances are computed two ways in floating point; none may sit within round-off of
    // the limit, or the comparison below would test round-off (the geometry avoids it).
    borderline += std::fabs(d - limit) < 1e-12;
    const bool is_near = d <= limit, is_soft = pm.material_id[i] != 1;
    if (is_near) near.push_back(static_cast<int64_t>(i));
    if (is_soft) soft.push_back(static_cast<int64_t>(i));
    if (is_near && is_soft) near_soft.push_back(static_cast<int64_t>(i));
  }
  ASSERT_EQ(borderline, 0u);
  EXPECT_EQ(set_of(s, "near"), near);
  EXPECT_EQ(set_of(s, "soft"), soft);
  EXPECT_EQ(set_of(s, "near_soft"), near_soft);
  // Not trivial: some particles near the fold and some not, of each kind.
  EXPECT_GT(near.size(), 50u);
  EXPECT_LT(near.size(), pm.size() / 2);
  EXPECT_GT(near_soft.size(), 10u);
  EXPECT_LT(near_soft.size(), near.size());
}

TEST(CaseSets, NearSurfaceOnALatticeFaceIsTheLayersWithinTheDistance) {
  // A lattice's facets have no vertices: each is taken as the square of its area, which
  // tiles the face exactly, so the set is the layers whose centres lie within the distance
  // of the face x = 0 (centres at 0.5, 1.5, 2.5 mm: 2.2 mm takes two layers).
  const PdSystem s = system_from_yaml("near_lattice_face",
      "specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.006, 0.005, 0.004], spacing: 1 mm}}\n"
      "model: {type: pmb, horizon_factor: 3.015}\n"
      "materials: [{name: m, density: 1000, youngs_modulus: 1 GPa, poisson_ratio: 0.25}]\n"
      "time: {steps: 1}\n"
      "sets: [{name: skin, near_surface: {surface: xmin, distance: 2.2 mm}}]\n");
  std::vector<int64_t> expected;
  for (size_t i = 0; i < s.particles.size(); ++i)
    if (s.particles.position_m[3 * i] < 2.2e-3) expected.push_back(static_cast<int64_t>(i));
  EXPECT_EQ(expected.size(), 2u * 5u * 4u);
  EXPECT_EQ(set_of(s, "skin"), expected);
}

TEST(CaseSets, UnknownSurfaceOrMaterialIsNamedWithTheKnownOnes) {
  const std::string particles = write_grid_with_fold("fold_grid_errors");
  const std::string surface =
      error_of("near_bad", head(particles) + "sets: [{name: a, near_surface: {surface: fault, distance: 1 mm}}]\n");
  EXPECT_NE(surface.find("sets[0].near_surface.surface"), std::string::npos) << surface;
  EXPECT_NE(surface.find("'fault'"), std::string::npos) << surface;
  EXPECT_NE(surface.find("fold"), std::string::npos) << surface;  // the known ones
  const std::string material = error_of("material_bad", head(particles) + "sets: [{name: a, material: [rock, basalt]}]\n");
  EXPECT_NE(material.find("sets[0].material[1]"), std::string::npos) << material;
  EXPECT_NE(material.find("rock, steel, glue"), std::string::npos) << material;
  const std::string distance =
      error_of("distance_bad", head(particles) + "sets: [{name: a, near_surface: {surface: fold, distance: -1 mm}}]\n");
  EXPECT_NE(distance.find("sets[0].near_surface.distance"), std::string::npos) << distance;
}

TEST(SurfacePrecracks, A2DSurfaceOfEdgesCutsTheBondsItsSegmentCuts) {
  // A 2D lattice and a crack as a facet group of three collinear edges, against the same
  // crack as one segment. The ends sit off every bond line (no tie in the crossing tests),
  // so the two must agree exactly.
  ParticleModel m;
  m.dimension = 2;
  m.thickness_m = 1e-3;
  const double h = 0.5e-3;
  for (int j = 0; j < 20; ++j)
    for (int i = 0; i < 40; ++i) {
      m.position_m.insert(m.position_m.end(), {(i + 0.5) * h, (j + 0.5) * h, 0.0});
      m.volume_m3.push_back(h * h * m.thickness_m);
      m.material_id.push_back(0);
    }
  m.material_names = {"glass"};
  SurfaceFacets crack;
  crack.name = "crack";
  const double y = 5.0e-3 + 1.234567e-5, x0 = -0.1e-3, x1 = 11.03141e-3;
  for (int e = 0; e < 3; ++e) {
    const double a = x0 + (x1 - x0) * e / 3.0, b = x0 + (x1 - x0) * (e + 1) / 3.0;
    crack.vertices_m.insert(crack.vertices_m.end(), {a, y, 0.0, b, y, 0.0});
    crack.area_m2.push_back((b - a) * m.thickness_m);
    crack.normal.insert(crack.normal.end(), {0.0, 1.0, 0.0});
    crack.centroid_m.insert(crack.centroid_m.end(), {0.5 * (a + b), y, 0.0});
    crack.particle.push_back(0);
  }
  m.surfaces.push_back(crack);
  const std::string path = process_temp_dir() + "/edges_2d/particles.h5";
  breccia::write_particle_file(path, m);
  const std::string deck = "specimen: {particles: " + path + "}\n"
      "model: {type: pmb, planar: plane_stress, horizon_factor: 3.015}\n"
      "materials: [{name: glass, density: 2440, youngs_modulus: 72 GPa, poisson_ratio: 0.3333333333333333}]\n"
      "time: {steps: 1}\n";
  const PdSystem by_surface = system_from_yaml("edges_surface", deck + "precracks: [{type: surface, surface: crack}]\n");
  char segment[200];
  std::snprintf(segment, sizeof segment, "precracks: [{type: segment, from: [%.17g, %.17g], to: [%.17g, %.17g]}]\n", x0, y,
                x1, y);
  const PdSystem by_segment = system_from_yaml("edges_segment", deck + segment);
  ASSERT_GT(by_segment.precrack_pairs.size(), 100u);
  EXPECT_EQ(by_surface.precrack_pairs, by_segment.precrack_pairs);
}

TEST(SurfacePrecracks, AFileWithoutFacetVerticesCutsTheSameBondsThroughItsMesh) {
  // A cube with an embedded crack, placed by breccia-place (facet vertices in the file); the
  // same file without them (as files written before they were stored) recovers the facets
  // from /mesh and must cut exactly the same bonds.
  const std::string path = mesh_and_place("vertices_crack",
      "dimension: 3\n"
      "body: {shape: box, name: block, origin: [0, 0, 0], size: [40 mm, 40 mm, 40 mm]}\n"
      "notches:\n  - {name: notch, type: crack, corner: [10 mm, 10 mm, 20 mm], edge_a: [20 mm, 0, 0], edge_b: [0, 20 mm, 0]}\n"
      "mesh: {size: 5 mm}\n");
  ASSERT_FALSE(path.empty());
  ParticleModel m = breccia::read_particle_file(path);
  ASSERT_TRUE(m.find_surface("notch")->has_vertices());
  for (auto& sf : m.surfaces) sf.vertices_m.clear();
  const std::string old_path = process_temp_dir() + "/vertices_crack_old/particles.h5";
  breccia::write_particle_file(old_path, m);
  const std::string model = "model: {type: pmb, horizon_factor: 3.015}\n"
      "materials: [{name: block, density: 2000, youngs_modulus: 30 GPa, poisson_ratio: 0.25}]\ntime: {steps: 1}\n"
      "precracks: [{type: surface, surface: notch}]\n";
  const PdSystem with = system_from_yaml("crack_with_vertices", "specimen: {particles: " + path + "}\n" + model);
  const PdSystem without = system_from_yaml("crack_without_vertices", "specimen: {particles: " + old_path + "}\n" + model);
  ASSERT_GT(with.precrack_pairs.size(), 50u);
  EXPECT_EQ(with.precrack_pairs, without.precrack_pairs);
}
