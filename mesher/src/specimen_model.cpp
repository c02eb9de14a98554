#include "specimen_model.hpp"

#include <gmsh.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <set>

#include "breccia/common/error.hpp"
#include "specimen_geometry.hpp"

namespace breccia::mesher {
namespace {

using DimTags = gmsh::vectorpair;
using PointTest = std::function<bool(const Vec3&)>;

int add_point(const Vec3& p) { return gmsh::model::occ::addPoint(p[0], p[1], p[2]); }

// Plane polygon through the given corners (in order).
int add_polygon(const std::vector<Vec3>& corners) {
  std::vector<int> points, lines;
  for (const auto& c : corners) points.push_back(add_point(c));
  for (size_t i = 0; i < points.size(); ++i)
    lines.push_back(gmsh::model::occ::addLine(points[i], points[(i + 1) % points.size()]));
  return gmsh::model::occ::addPlaneSurface({gmsh::model::occ::addCurveLoop(lines)});
}

Vec3 notch_normal(const Notch& n) { return normalized(cross(n.edge_a, n.edge_b)); }
Vec3 notch_normal_2d(const Notch& n) { return normalized(Vec3{-n.edge_a[1], n.edge_a[0], 0}); }

// Parallelogram coordinates (s, t) of p's projection on corner + s*a + t*b.
std::pair<double, double> plane_coordinates(const Vec3& p, const Vec3& corner, const Vec3& a, const Vec3& b) {
  const Vec3 d = sub(p, corner);
  const double aa = dot(a, a), ab = dot(a, b), bb = dot(b, b), da = dot(d, a), db = dot(d, b);
  const double det = aa * bb - ab * ab;
  return {(da * bb - db * ab) / det, (db * aa - da * ab) / det};
}

int add_body(const Specimen& spec) {
  const Body& b = spec.body;
  switch (b.shape) {
    case BodyShape::Box:
      return gmsh::model::occ::addBox(b.origin[0], b.origin[1], b.origin[2], b.size[0], b.size[1], b.size[2]);
    case BodyShape::Rectangle:
      return gmsh::model::occ::addRectangle(b.origin[0], b.origin[1], 0, b.size[0], b.size[1]);
    case BodyShape::Cylinder:
      return gmsh::model::occ::addCylinder(b.origin[0], b.origin[1], b.origin[2], 0, 0, b.height_m, b.radius_m);
    case BodyShape::Disc:
      return gmsh::model::occ::addDisk(b.origin[0], b.origin[1], 0, b.radius_m, b.radius_m);
  }
  return -1;
}

// A blind hole that starts on the surface is extended outwards so the cut never leaves
// a sliver where the cylinder's end face would coincide with the body's face.
double hole_extension(const Specimen& spec, const Hole& h) {
  return signed_distance_inside(spec.body, h.entry) < 10 * geometric_tolerance(spec) ? 2 * h.radius_m : 0.0;
}

DimTags add_hole_tool(const Specimen& spec, const Hole& h) {
  if (spec.dimension == 2) return {{2, gmsh::model::occ::addDisk(h.entry[0], h.entry[1], 0, h.radius_m, h.radius_m)}};
  const double through = 4 * body_extent(spec.body);
  const double back = h.depth_m ? hole_extension(spec, h) : through / 2;
  const double length = h.depth_m ? *h.depth_m + back : through;
  const Vec3 start = sub(h.entry, scale(h.axis, back));
  const Vec3 d = scale(h.axis, length);
  return {{3, gmsh::model::occ::addCylinder(start[0], start[1], start[2], d[0], d[1], d[2], h.radius_m)}};
}

DimTags add_slot_tool(const Specimen& spec, const Notch& n) {
  if (spec.dimension == 2) {
    const Vec3 off = scale(notch_normal_2d(n), n.width_m / 2);
    const Vec3 end = add(n.corner, n.edge_a);
    return {{2, add_polygon({sub(n.corner, off), sub(end, off), add(end, off), add(n.corner, off)})}};
  }
  const Vec3 off = scale(notch_normal(n), n.width_m / 2);
  const Vec3 c0 = sub(n.corner, off);
  const int face = add_polygon({c0, add(c0, n.edge_a), add(add(c0, n.edge_a), n.edge_b), add(c0, n.edge_b)});
  const Vec3 w = scale(off, 2);
  DimTags out;
  gmsh::model::occ::extrude({{2, face}}, w[0], w[1], w[2], out);
  for (const auto& dt : out)
    if (dt.first == 3) return {dt};
  throw RunError("gmsh: extruding slot '" + n.name + "' gave no volume");
}

DimTags add_crack(const Specimen& spec, const Notch& n) {
  if (spec.dimension == 2)
    return {{1, gmsh::model::occ::addLine(add_point(n.corner), add_point(add(n.corner, n.edge_a)))}};
  const Vec3& c = n.corner;
  return {{2, add_polygon({c, add(c, n.edge_a), add(add(c, n.edge_a), n.edge_b), add(c, n.edge_b)})}};
}

// Points on the entity. A curve's parameter range is the curve itself, but a trimmed
// face's is only a rectangle around it (a skewed notch's parallelogram, a face with a hole
// cut out), and a point of that rectangle off the face fails the notch test although it
// lies on the face's plane. So a grid over the rectangle is kept where gmsh places it on
// the face; the rectangle's points serve only where gmsh finds none (a sliver).
std::vector<Vec3> sample_points(int dim, int tag) {
  std::vector<double> lo, hi, params, xyz;
  gmsh::model::getParametrizationBounds(dim, tag, lo, hi);
  if (dim == 1) {
    for (double t : {0.2, 0.5, 0.8}) params.push_back(lo[0] + t * (hi[0] - lo[0]));
  } else {
    constexpr int kGrid = 9;
    for (int i = 0; i < kGrid; ++i)
      for (int j = 0; j < kGrid; ++j) {
        const std::vector<double> uv{lo[0] + (i + 0.5) / kGrid * (hi[0] - lo[0]), lo[1] + (j + 0.5) / kGrid * (hi[1] - lo[1])};
        if (gmsh::model::isInside(dim, tag, uv) == 1) params.insert(params.end(), uv.begin(), uv.end());
      }
    if (params.empty())
      for (auto [s, t] : {std::pair{0.5, 0.5}, {0.25, 0.25}, {0.75, 0.25}, {0.25, 0.75}, {0.75, 0.75}}) {
        params.push_back(lo[0] + s * (hi[0] - lo[0]));
        params.push_back(lo[1] + t * (hi[1] - lo[1]));
      }
  }
  gmsh::model::getValue(dim, tag, params, xyz);
  std::vector<Vec3> pts;
  for (size_t i = 0; i + 2 < xyz.size(); i += 3) pts.push_back({xyz[i], xyz[i + 1], xyz[i + 2]});
  return pts;
}

// Geometric tests for the body's own boundary groups (before aliases).
std::vector<std::pair<std::string, PointTest>> body_face_tests(const Specimen& spec, double tol) {
  const Body& b = spec.body;
  std::vector<std::pair<std::string, PointTest>> tests;
  if (b.shape == BodyShape::Box || b.shape == BodyShape::Rectangle) {
    const int axes = spec.dimension;
    const char* names[3][2] = {{"xmin", "xmax"}, {"ymin", "ymax"}, {"zmin", "zmax"}};
    for (int a = 0; a < axes; ++a)
      for (int side = 0; side < 2; ++side) {
        const double plane = b.origin[a] + side * b.size[a];
        tests.emplace_back(names[a][side], [=](const Vec3& p) { return std::abs(p[a] - plane) < tol; });
      }
    return tests;
  }
  const auto radial = [=](const Vec3& p) { return std::hypot(p[0] - b.origin[0], p[1] - b.origin[1]); };
  if (b.shape == BodyShape::Disc) {
    tests.emplace_back("outer", [=](const Vec3& p) { return std::abs(radial(p) - b.radius_m) < tol; });
    return tests;
  }
  tests.emplace_back("bottom", [=](const Vec3& p) { return std::abs(p[2] - b.origin[2]) < tol; });
  tests.emplace_back("top", [=](const Vec3& p) { return std::abs(p[2] - b.origin[2] - b.height_m) < tol; });
  tests.emplace_back("lateral", [=](const Vec3& p) { return std::abs(radial(p) - b.radius_m) < tol; });
  return tests;
}

PointTest hole_test(const Specimen& spec, const Hole& h, double tol) {
  if (spec.dimension == 2)
    return [=](const Vec3& p) { return std::abs(norm(sub(p, h.entry)) - h.radius_m) < tol; };
  const double back = h.depth_m ? hole_extension(spec, h) : 1e300;
  const double depth = h.depth_m.value_or(1e300);
  return [=](const Vec3& p) {
    const Vec3 d = sub(p, h.entry);
    const double along = dot(d, h.axis);
    const double radial = norm(sub(d, scale(h.axis, along)));
    const bool on_wall = std::abs(radial - h.radius_m) < tol && along > -back - tol && along < depth + tol;
    const bool on_bottom = h.depth_m && std::abs(along - depth) < tol && radial < h.radius_m + tol;
    // An entry inside the body (back == 0: not extended) makes a closed cavity, whose
    // entry disc is a face of the hole like its bottom. On the surface it is no face.
    const bool on_entry = h.depth_m && back == 0 && std::abs(along) < tol && radial < h.radius_m + tol;
    return on_wall || on_bottom || on_entry;
  };
}

PointTest notch_test(const Specimen& spec, const Notch& n, double tol) {
  const double half_width = n.kind == Notch::Kind::Slot ? n.width_m / 2 : 0.0;
  if (spec.dimension == 2) {
    const Vec3 normal = notch_normal_2d(n);
    const double len = norm(n.edge_a);
    return [=](const Vec3& p) {
      const Vec3 d = sub(p, n.corner);
      const double s = dot(d, n.edge_a) / (len * len);
      return std::abs(dot(d, normal)) < half_width + tol && s > -tol / len && s < 1 + tol / len;
    };
  }
  const Vec3 normal = notch_normal(n);
  const double slack = tol / std::min(norm(n.edge_a), norm(n.edge_b));
  return [=](const Vec3& p) {
    const double offset = dot(sub(p, n.corner), normal);
    const auto [s, t] = plane_coordinates(sub(p, scale(normal, offset)), n.corner, n.edge_a, n.edge_b);
    return std::abs(offset) < half_width + tol && s > -slack && s < 1 + slack && t > -slack && t < 1 + slack;
  };
}

bool all_pass(const std::vector<Vec3>& pts, const PointTest& test) {
  return !pts.empty() && std::all_of(pts.begin(), pts.end(), test);
}

void add_alias(GroupMap& groups, const std::string& alias, const std::vector<std::string>& members) {
  std::set<int> tags;
  int dim = -1;
  for (const auto& m : members) {
    const auto it = groups.find(m);
    if (it == groups.end()) continue;
    dim = it->second.dim;
    tags.insert(it->second.tags.begin(), it->second.tags.end());
  }
  if (dim >= 0) groups[alias] = {dim, {tags.begin(), tags.end()}};
}

}  // namespace

GroupMap build_specimen_model(const Specimen& spec) {
  namespace occ = gmsh::model::occ;
  const int dim = spec.dimension;
  const double tol = geometric_tolerance(spec);
  gmsh::model::add("specimen");

  DimTags body{{dim, add_body(spec)}};
  DimTags cut_tools;
  for (const auto& h : spec.holes) {
    const auto t = add_hole_tool(spec, h);
    cut_tools.insert(cut_tools.end(), t.begin(), t.end());
  }
  for (const auto& n : spec.notches)
    if (n.kind == Notch::Kind::Slot) {
      const auto t = add_slot_tool(spec, n);
      cut_tools.insert(cut_tools.end(), t.begin(), t.end());
    }
  std::vector<DimTags> map;
  if (!cut_tools.empty()) {
    DimTags cut_body;
    occ::cut(body, cut_tools, cut_body, map);
    body = cut_body;
  }
  DimTags embedded;
  for (const auto& n : spec.notches) {
    if (n.kind != Notch::Kind::Crack) continue;
    // Keep only the part of the crack inside the body (it may cross a hole or slot).
    DimTags inside;
    occ::intersect(add_crack(spec, n), body, inside, map, -1, true, false);
    embedded.insert(embedded.end(), inside.begin(), inside.end());
  }
  for (const auto& inc : spec.inclusions) {
    const auto& c = inc.centre;
    embedded.push_back(dim == 3 ? DimTags::value_type{3, occ::addSphere(c[0], c[1], c[2], inc.radius_m)}
                                : DimTags::value_type{2, occ::addDisk(c[0], c[1], 0, inc.radius_m, inc.radius_m)});
  }
  if (!embedded.empty()) {
    DimTags pieces;
    occ::fragment(body, embedded, pieces, map);
  }
  occ::synchronize();

  GroupMap groups;
  // Volumes (surfaces in 2D): an inclusion's piece lies inside its sphere; the rest is the body.
  DimTags cells;
  gmsh::model::getEntities(cells, dim);
  for (const auto& [d, tag] : cells) {
    std::string owner = spec.body.name;
    double x0, y0, z0, x1, y1, z1, cx, cy, cz;
    gmsh::model::getBoundingBox(d, tag, x0, y0, z0, x1, y1, z1);
    occ::getCenterOfMass(d, tag, cx, cy, cz);
    for (const auto& inc : spec.inclusions) {
      // OCC boxes of curved shapes can be loose by a fraction of the radius.
      const double slack = 0.05 * inc.radius_m;
      const auto& c = inc.centre;
      const bool boxed = x0 > c[0] - inc.radius_m - slack && x1 < c[0] + inc.radius_m + slack &&
                         y0 > c[1] - inc.radius_m - slack && y1 < c[1] + inc.radius_m + slack &&
                         (dim == 2 || (z0 > c[2] - inc.radius_m - slack && z1 < c[2] + inc.radius_m + slack));
      if (boxed && norm(sub({cx, cy, cz}, c)) < inc.radius_m) owner = inc.name;
    }
    groups[owner].dim = dim;
    groups[owner].tags.push_back(tag);
  }

  // Boundary entities: outer faces first; a face that is not outer may belong to a hole,
  // a slot or a crack.
  const auto face_tests = body_face_tests(spec, tol);
  std::vector<std::pair<std::string, PointTest>> feature_tests;
  for (const auto& h : spec.holes) feature_tests.emplace_back(h.name, hole_test(spec, h, tol));
  for (const auto& n : spec.notches) feature_tests.emplace_back(n.name, notch_test(spec, n, tol));
  DimTags faces;
  gmsh::model::getEntities(faces, dim - 1);
  std::set<std::string> outer_names;
  for (const auto& [d, tag] : faces) {
    const auto pts = sample_points(d, tag);
    bool outer = false;
    for (const auto& [name, test] : face_tests)
      if (all_pass(pts, test)) {
        groups[name].dim = d;
        groups[name].tags.push_back(tag);
        outer_names.insert(name);
        outer = true;
      }
    if (outer) continue;
    for (const auto& [name, test] : feature_tests)
      if (all_pass(pts, test)) {
        groups[name].dim = d;
        groups[name].tags.push_back(tag);
        break;
      }
  }

  switch (spec.body.shape) {
    case BodyShape::Box:
      add_alias(groups, "bottom", {"zmin"});
      add_alias(groups, "top", {"zmax"});
      add_alias(groups, "sides", {"xmin", "xmax", "ymin", "ymax"});
      add_alias(groups, "outer", {"xmin", "xmax", "ymin", "ymax", "zmin", "zmax"});
      break;
    case BodyShape::Rectangle:
      add_alias(groups, "bottom", {"ymin"});
      add_alias(groups, "top", {"ymax"});
      add_alias(groups, "sides", {"xmin", "xmax"});
      add_alias(groups, "outer", {"xmin", "xmax", "ymin", "ymax"});
      break;
    case BodyShape::Cylinder:
      add_alias(groups, "outer", {"bottom", "top", "lateral"});
      break;
    case BodyShape::Disc:
      break;
  }
  for (const auto& [alias, members] : spec.group_aliases) add_alias(groups, alias, members);

  std::vector<std::string> expected = body_boundary_groups(spec);
  expected.push_back(spec.body.name);
  for (const auto& h : spec.holes) expected.push_back(h.name);
  for (const auto& n : spec.notches) expected.push_back(n.name);
  for (const auto& i : spec.inclusions) expected.push_back(i.name);
  for (const auto& [alias, members] : spec.group_aliases) expected.push_back(alias);
  for (const auto& name : expected)
    if (!groups.count(name) || groups[name].tags.empty())
      throw InputError(spec.file, name, "no entity of the built geometry belongs to this group",
                       "a feature that leaves part of its surface in the body");

  for (const auto& [name, g] : groups) {
    const int phys = gmsh::model::addPhysicalGroup(g.dim, g.tags);
    gmsh::model::setPhysicalName(g.dim, phys, name);
  }
  return groups;
}

void apply_size_fields(const Specimen& spec, const GroupMap& groups, double size_factor) {
  namespace field = gmsh::model::mesh::field;
  const double global = spec.mesh.size_m * size_factor;
  gmsh::option::setNumber("Mesh.MeshSizeMax", global);
  gmsh::option::setNumber("Mesh.MeshSizeFromPoints", 0);
  gmsh::option::setNumber("Mesh.MeshSizeFromCurvature", 0);
  if (spec.mesh.refine.empty()) return;

  std::vector<double> thresholds;
  for (const auto& r : spec.mesh.refine) {
    const PhysicalGroup& g = groups.at(r.near);
    DimTags targets;
    for (int tag : g.tags) targets.emplace_back(g.dim, tag);
    if (g.dim == spec.dimension) {  // near a volume: distance to its boundary
      DimTags boundary;
      gmsh::model::getBoundary(targets, boundary, true, false, false);
      targets = boundary;
    }
    std::vector<double> points, curves, surfaces;
    double extent = 0;
    for (const auto& [d, tag] : targets) {
      (d == 0 ? points : d == 1 ? curves : surfaces).push_back(tag);
      double x0, y0, z0, x1, y1, z1;
      gmsh::model::getBoundingBox(d, tag, x0, y0, z0, x1, y1, z1);
      extent = std::max({extent, x1 - x0, y1 - y0, z1 - z0});
    }
    const int distance = field::add("Distance");
    if (!points.empty()) field::setNumbers(distance, "PointsList", points);
    if (!curves.empty()) field::setNumbers(distance, "CurvesList", curves);
    if (!surfaces.empty()) field::setNumbers(distance, "FacesList", surfaces);
    // Sample the entities at about half the fine size, so the distance is accurate to
    // well within the fine zone.
    const double fine = r.size_m * size_factor;
    const double samples = std::clamp(std::ceil(2 * extent / fine), 20.0, 400.0);
    field::setNumber(distance, "NumPointsPerCurve", samples);

    const int threshold = field::add("Threshold");
    field::setNumber(threshold, "InField", distance);
    field::setNumber(threshold, "SizeMin", fine);
    field::setNumber(threshold, "SizeMax", global);
    field::setNumber(threshold, "DistMin", r.distance_min_m);
    field::setNumber(threshold, "DistMax", r.distance_max_m);
    thresholds.push_back(threshold);
  }
  const int combined = field::add("Min");
  field::setNumbers(combined, "FieldsList", thresholds);
  field::setAsBackgroundMesh(combined);
  gmsh::option::setNumber("Mesh.MeshSizeExtendFromBoundary", 0);
}

}  // namespace breccia::mesher
