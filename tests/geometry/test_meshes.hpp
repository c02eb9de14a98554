#pragma once
// Test meshes built with the gmsh C++ API (OpenCASCADE kernel), written to .msh files,
// plus independent reference measures computed straight from gmsh's node coordinates.
#include <gmsh.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

namespace breccia::geometry::testing {

// One scratch folder per test process: ctest runs the discovered tests in parallel
// processes, which must not write the same mesh file at the same time.
inline std::string scratch_dir() {
  static const std::string dir = [] {
    const std::string d = ::testing::TempDir() + "/breccia_geometry_" + std::to_string(::getpid());
    std::filesystem::create_directories(d);
    return d;
  }();
  return dir;
}

class RemoveScratchDir : public ::testing::Environment {
public:
  void TearDown() override {
    std::error_code ec;
    std::filesystem::remove_all(scratch_dir(), ec);
  }
};

// Block L x W x H with a cylindrical hole of radius r along z through its middle.
struct BlockWithHole {
  double length_m = 1.0, width_m = 0.6, height_m = 0.4, hole_radius_m = 0.1;
  double mesh_size_m = 0.08;
  double hole_x() const { return 0.5 * length_m; }
  double hole_y() const { return 0.5 * width_m; }
  double volume() const { return length_m * width_m * height_m - M_PI * hole_radius_m * hole_radius_m * height_m; }
  double side_area() const { return 2.0 * (length_m + width_m) * height_m; }
  double hole_wall_area() const { return 2.0 * M_PI * hole_radius_m * height_m; }
};

inline void start_gmsh() {
  gmsh::initialize();  // a second call is a no-op
  gmsh::option::setNumber("General.Terminal", 0);
  gmsh::clear();
}

// Groups: volume "concrete"; surfaces "sides" (the four planar side faces), "caps" (top
// and bottom, with the hole), "hole" (the cylinder wall); point "corner" (the origin).
inline void write_block_with_hole(const std::string& path, const BlockWithHole& b, double msh_version = 4.1) {
  start_gmsh();
  gmsh::model::add("block");
  const int box = gmsh::model::occ::addBox(0, 0, 0, b.length_m, b.width_m, b.height_m);
  const int cyl = gmsh::model::occ::addCylinder(b.hole_x(), b.hole_y(), 0, 0, 0, b.height_m, b.hole_radius_m);
  gmsh::vectorpair out;
  std::vector<gmsh::vectorpair> out_map;
  gmsh::model::occ::cut({{3, box}}, {{3, cyl}}, out, out_map);
  gmsh::model::occ::synchronize();
  const int volume = out.at(0).second;
  gmsh::vectorpair boundary;
  gmsh::model::getBoundary({{3, volume}}, boundary, false, false, false);
  std::vector<int> sides, caps, hole;
  for (const auto& [dim, tag] : boundary) {
    double x0, y0, z0, x1, y1, z1;
    gmsh::model::getBoundingBox(2, std::abs(tag), x0, y0, z0, x1, y1, z1);
    // OCC pads bounding boxes by its tolerance (1e-7 m), far below the block's size.
    if (std::abs(z1 - z0) < 1e-5 * b.height_m) caps.push_back(std::abs(tag));
    else if (x1 - x0 < 2.5 * b.hole_radius_m && y1 - y0 < 2.5 * b.hole_radius_m) hole.push_back(std::abs(tag));
    else sides.push_back(std::abs(tag));
  }
  gmsh::model::addPhysicalGroup(3, {volume}, 1);
  gmsh::model::setPhysicalName(3, 1, "concrete");
  gmsh::model::addPhysicalGroup(2, sides, 2);
  gmsh::model::setPhysicalName(2, 2, "sides");
  gmsh::model::addPhysicalGroup(2, caps, 3);
  gmsh::model::setPhysicalName(2, 3, "caps");
  gmsh::model::addPhysicalGroup(2, hole, 4);
  gmsh::model::setPhysicalName(2, 4, "hole");
  gmsh::vectorpair points;
  gmsh::model::getEntitiesInBoundingBox(-1e-6, -1e-6, -1e-6, 1e-6, 1e-6, 1e-6, points, 0);
  std::vector<int> point_tags;
  for (const auto& p : points) point_tags.push_back(p.second);
  gmsh::model::addPhysicalGroup(0, point_tags, 5);
  gmsh::model::setPhysicalName(0, 5, "corner");
  gmsh::option::setNumber("Mesh.MeshSizeMax", b.mesh_size_m);
  gmsh::model::mesh::generate(3);
  gmsh::option::setNumber("Mesh.MshFileVersion", msh_version);
  gmsh::write(path);
}

// Unit cube with an embedded planar pre-crack "notch" at z = 0.5 (x in [0, 0.5],
// y in [0.25, 0.75], so 0.25 m^2), meshed conformingly: tets on both sides share its faces.
inline void write_cube_with_notch(const std::string& path, double mesh_size_m) {
  start_gmsh();
  gmsh::model::add("notched");
  const int box = gmsh::model::occ::addBox(0, 0, 0, 1, 1, 1);
  const int rect = gmsh::model::occ::addRectangle(0, 0.25, 0.5, 0.5, 0.5);
  gmsh::vectorpair out;
  std::vector<gmsh::vectorpair> out_map;
  gmsh::model::occ::fragment({{3, box}}, {{2, rect}}, out, out_map);
  gmsh::model::occ::synchronize();
  // out_map[i]: what became of input i (the box, then the rectangle).
  std::vector<int> volumes, notch;
  for (const auto& [dim, tag] : out_map.at(0)) volumes.push_back(tag);
  for (const auto& [dim, tag] : out_map.at(1)) notch.push_back(tag);
  gmsh::model::addPhysicalGroup(3, volumes, 1);
  gmsh::model::setPhysicalName(3, 1, "body");
  gmsh::model::addPhysicalGroup(2, notch, 2);
  gmsh::model::setPhysicalName(2, 2, "notch");
  gmsh::option::setNumber("Mesh.MeshSizeMax", mesh_size_m);
  gmsh::model::mesh::generate(3);
  gmsh::option::setNumber("Mesh.MshFileVersion", 4.1);
  gmsh::write(path);
}

// Plate L x W in z = 0 with a circular hole; groups: surface "plate", curves "edges"
// (the four straight edges), "hole" (the circle).
struct PlateWithHole {
  double length_m = 0.4, width_m = 0.2, hole_radius_m = 0.04, mesh_size_m = 0.02;
  double area() const { return length_m * width_m - M_PI * hole_radius_m * hole_radius_m; }
};

inline void write_plate_with_hole(const std::string& path, const PlateWithHole& p) {
  start_gmsh();
  gmsh::model::add("plate");
  const int rect = gmsh::model::occ::addRectangle(0, 0, 0, p.length_m, p.width_m);
  const int disk = gmsh::model::occ::addDisk(0.5 * p.length_m, 0.5 * p.width_m, 0, p.hole_radius_m, p.hole_radius_m);
  gmsh::vectorpair out;
  std::vector<gmsh::vectorpair> out_map;
  gmsh::model::occ::cut({{2, rect}}, {{2, disk}}, out, out_map);
  gmsh::model::occ::synchronize();
  const int surface = out.at(0).second;
  gmsh::vectorpair boundary;
  gmsh::model::getBoundary({{2, surface}}, boundary, false, false, false);
  std::vector<int> edges, hole;
  for (const auto& [dim, tag] : boundary) {
    std::string type;
    gmsh::model::getType(1, std::abs(tag), type);
    (type == "Line" ? edges : hole).push_back(std::abs(tag));
  }
  gmsh::model::addPhysicalGroup(2, {surface}, 1);
  gmsh::model::setPhysicalName(2, 1, "plate");
  gmsh::model::addPhysicalGroup(1, edges, 2);
  gmsh::model::setPhysicalName(1, 2, "edges");
  gmsh::model::addPhysicalGroup(1, hole, 3);
  gmsh::model::setPhysicalName(1, 3, "hole");
  gmsh::option::setNumber("Mesh.MeshSizeMax", p.mesh_size_m);
  gmsh::model::mesh::generate(2);
  gmsh::option::setNumber("Mesh.MshFileVersion", 4.1);
  gmsh::write(path);
}

// Reference measures from the file, computed here independently of the library: the sum
// of |tet volumes| (3D) or |triangle areas| (2D), and the element count.
struct MeshMeasure {
  double total = 0;
  size_t elements = 0;
};

inline MeshMeasure measure_msh(const std::string& path, int element_type) {
  start_gmsh();
  gmsh::open(path);
  std::vector<std::size_t> node_tags;
  std::vector<double> coords, parametric;
  gmsh::model::mesh::getNodes(node_tags, coords, parametric, -1, -1, false, false);
  std::vector<double> x(3 * (*std::max_element(node_tags.begin(), node_tags.end()) + 1));
  for (size_t i = 0; i < node_tags.size(); ++i)
    for (int k = 0; k < 3; ++k) x[3 * node_tags[i] + k] = coords[3 * i + k];
  std::vector<std::size_t> tags, nodes;
  gmsh::model::mesh::getElementsByType(element_type, tags, nodes);
  MeshMeasure m;
  m.elements = tags.size();
  for (size_t e = 0; e < tags.size(); ++e) {
    if (element_type == 4) {
      const double* p[4];
      for (int k = 0; k < 4; ++k) p[k] = &x[3 * nodes[4 * e + k]];
      double a[3][3];
      for (int r = 0; r < 3; ++r)
        for (int k = 0; k < 3; ++k) a[r][k] = p[r + 1][k] - p[0][k];
      const double det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
                         a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
                         a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
      m.total += std::abs(det) / 6.0;
    } else {
      const double* p[3];
      for (int k = 0; k < 3; ++k) p[k] = &x[3 * nodes[3 * e + k]];
      m.total += 0.5 * std::abs((p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[1][1] - p[0][1]) * (p[2][0] - p[0][0]));
    }
  }
  gmsh::clear();
  return m;
}

}  // namespace breccia::geometry::testing
