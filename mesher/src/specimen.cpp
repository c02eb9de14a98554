#include "breccia/mesher/specimen.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <set>

#include "breccia/common/error.hpp"
#include "breccia/common/yaml_input.hpp"
#include "specimen_geometry.hpp"

namespace breccia::mesher {
namespace {

std::string format_length(double metres) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6g mm", metres * 1e3);
  return buf;
}

// A point or vector: 3 entries in 3D, 2 in 2D (z = 0).
Vec3 read_point(const Section& s, const std::string& key, int dimension) {
  const auto v = s.numbers(key, Quantity::Length, static_cast<size_t>(dimension));
  return {v[0], v[1], dimension == 3 ? v[2] : 0.0};
}

Vec3 read_direction(const Section& s, const std::string& key) {
  const auto v = s.numbers(key, Quantity::Dimensionless, 3);
  const double n = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  if (!(n > 0)) throw InputError(s.file(), s.field(key), "is the zero vector", "a direction like [0, 0, -1]");
  return {v[0] / n, v[1] / n, v[2] / n};
}

// Names become gmsh physical group names and solver keys: keep them plain identifiers.
std::string read_name(const Section& s, const std::string& key, const std::string& fallback) {
  const std::string name = s.text(key, fallback);
  const bool ok = !name.empty() && std::all_of(name.begin(), name.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-';
  });
  if (!ok) throw InputError(s.file(), s.field(key), "'" + name + "' is not a plain name", "letters, digits, '_' or '-'");
  return name;
}

Body read_body(const Section& s, int dimension, double thickness_m) {
  s.allow_only({"shape", "name", "origin", "size", "radius", "height"});
  Body b;
  b.name = read_name(s, "name", "body");
  const std::string shape = dimension == 3 ? s.choice("shape", {"box", "cylinder", "plate"})
                                           : s.choice("shape", {"rectangle", "disc", "plate"});
  auto forbid = [&](const std::string& key) {
    if (s.has(key)) throw InputError(s.file(), s.field(key), "is not used by shape '" + shape + "'", "no '" + key + "'");
  };
  if (s.has("origin")) b.origin = read_point(s, "origin", dimension);
  if (shape == "box" || shape == "rectangle" || shape == "plate") {
    forbid("radius");
    forbid("height");
    const size_t n = (shape == "box") ? 3 : 2;
    const auto v = s.numbers("size", Quantity::Length, n);
    for (size_t i = 0; i < n; ++i)
      if (!(v[i] > 0))
        throw InputError(s.file(), s.field("size") + "[" + std::to_string(i) + "]",
                         "value " + format_length(v[i]) + " is not positive", "a length > 0");
    b.shape = dimension == 3 ? BodyShape::Box : BodyShape::Rectangle;
    b.size = {v[0], v[1], n == 3 ? v[2] : (dimension == 3 ? thickness_m : 0.0)};
  } else {
    forbid("size");
    b.radius_m = s.positive("radius", Quantity::Length);
    if (shape == "cylinder") {
      b.shape = BodyShape::Cylinder;
      b.height_m = s.positive("height", Quantity::Length);
    } else {
      forbid("height");
      b.shape = BodyShape::Disc;
    }
  }
  return b;
}

// Rim of a circle of radius r around `centre` in the plane normal to `axis`.
std::vector<Vec3> rim_points(const Vec3& centre, const Vec3& axis, double r) {
  const Vec3 helper = std::abs(axis[0]) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
  const Vec3 u = normalized(cross(axis, helper));
  const Vec3 v = cross(axis, u);
  std::vector<Vec3> pts;
  for (int k = 0; k < 16; ++k) {
    const double t = 2 * std::numbers::pi * k / 16;
    pts.push_back(add(centre, add(scale(u, r * std::cos(t)), scale(v, r * std::sin(t)))));
  }
  return pts;
}

// Largest signed distance into the body along the line p + t * axis: >= 0 when the line
// meets the body. The signed distance is concave along a line for the convex bodies
// (a minimum of affine and concave terms), so a ternary search finds its maximum. `p` is
// a rim point, offset across the axis from an entry in the body, so the body lies within
// its diameter (< 2 extents) of t = 0 along the line.
double deepest_on_line(const Body& b, const Vec3& p, const Vec3& axis) {
  double lo = -2 * body_extent(b), hi = 2 * body_extent(b);
  const auto depth = [&](double t) { return signed_distance_inside(b, add(p, scale(axis, t))); };
  for (int k = 0; k < 200 && hi - lo > 1e-9 * body_extent(b); ++k) {
    const double m1 = lo + (hi - lo) / 3, m2 = hi - (hi - lo) / 3;
    if (depth(m1) < depth(m2)) lo = m1;
    else hi = m2;
  }
  return depth((lo + hi) / 2);
}

Hole read_hole(const Section& s, const Specimen& spec) {
  const double tol = geometric_tolerance(spec);
  Hole h;
  h.name = read_name(s, "name", "hole");
  h.radius_m = s.positive("radius", Quantity::Length);
  const auto wall_outside = [&] {
    return InputError(spec.file, s.field("radius"), "hole wall (radius " + format_length(h.radius_m) + ") reaches outside the body",
                      "a hole whose wall lies inside the body");
  };
  if (spec.dimension == 2) {
    s.allow_only({"name", "centre", "radius"});
    h.entry = read_point(s, "centre", 2);
    const double d = signed_distance_inside(spec.body, h.entry);
    if (d < h.radius_m + tol)
      throw InputError(spec.file, s.field("radius"), "hole (radius " + format_length(h.radius_m) + ") reaches outside the body",
                       "a circle entirely inside the body (use a notch for an edge cut)");
    return h;
  }
  s.allow_only({"name", "centre", "axis", "radius", "depth"});
  h.entry = read_point(s, "centre", 3);
  if (s.has("axis")) h.axis = read_direction(s, "axis");
  if (s.has("depth")) h.depth_m = s.positive("depth", Quantity::Length);
  if (signed_distance_inside(spec.body, h.entry) < -tol)
    throw InputError(spec.file, s.field("centre"), "hole entry point lies outside the body", "a point inside or on the body");
  if (!h.depth_m) {
    // A through hole is cut along its whole axis line. Each line of its wall must meet
    // the body, else the wall runs outside it along its whole length: the cut opens a
    // groove along a side or splits the body (the body's cross-section across the axis
    // must hold the hole's circle).
    for (const auto& p : rim_points(h.entry, h.axis, h.radius_m))
      if (deepest_on_line(spec.body, p, h.axis) < -tol) throw wall_outside();
    return h;
  }
  const Vec3 bottom = add(h.entry, scale(h.axis, *h.depth_m));
  if (signed_distance_inside(spec.body, bottom) <= tol)
    throw InputError(spec.file, s.field("depth"), "hole bottom lies on or outside the body",
                     "a blind hole ending inside the body (omit depth for a through hole)");
  for (const auto& centre : {h.entry, bottom})
    for (const auto& p : rim_points(centre, h.axis, h.radius_m))
      if (signed_distance_inside(spec.body, p) < -tol) throw wall_outside();
  return h;
}

Notch read_notch(const Section& s, const Specimen& spec) {
  const double tol = geometric_tolerance(spec);
  Notch n;
  n.name = read_name(s, "name", "notch");
  n.kind = s.choice("type", {"crack", "slot"}, "crack") == "slot" ? Notch::Kind::Slot : Notch::Kind::Crack;
  std::vector<std::string> keys = spec.dimension == 3 ? std::vector<std::string>{"name", "type", "corner", "edge_a", "edge_b"}
                                                      : std::vector<std::string>{"name", "type", "start", "end"};
  if (n.kind == Notch::Kind::Slot) keys.push_back("width");
  s.allow_only(keys);
  if (n.kind == Notch::Kind::Slot) n.width_m = s.positive("width", Quantity::Length);
  std::vector<Vec3> corners;
  if (spec.dimension == 3) {
    n.corner = read_point(s, "corner", 3);
    n.edge_a = read_point(s, "edge_a", 3);
    n.edge_b = read_point(s, "edge_b", 3);
    if (norm(cross(n.edge_a, n.edge_b)) < tol * tol)
      throw InputError(spec.file, s.path(), "edge_a and edge_b are parallel or zero", "two edges spanning a plane");
    corners = {n.corner, add(n.corner, n.edge_a), add(n.corner, n.edge_b), add(add(n.corner, n.edge_a), n.edge_b)};
  } else {
    n.corner = read_point(s, "start", 2);
    n.edge_a = sub(read_point(s, "end", 2), n.corner);
    if (norm(n.edge_a) < tol) throw InputError(spec.file, s.path(), "start and end coincide", "a segment of non-zero length");
    corners = {n.corner, add(n.corner, n.edge_a)};
  }
  for (const auto& c : corners)
    if (signed_distance_inside(spec.body, c) < -tol)
      throw InputError(spec.file, s.path(), "notch reaches outside the body", "a notch whose corners lie inside or on the body");
  return n;
}

// Distance from p to the slot's solid: in 3D the parallelogram thickened by width/2 on
// both sides of its plane, in 2D the rectangle of that width around the segment. The
// solid is the product of its plane figure and the interval across it, so the distance
// is the hypotenuse of the in-plane distance and the excess across.
double distance_to_slot(const Specimen& spec, const Notch& n, const Vec3& p) {
  const Vec3 d = sub(p, n.corner);
  if (spec.dimension == 2) {
    const double len = norm(n.edge_a);
    const Vec3 along = scale(n.edge_a, 1 / len), across{-along[1], along[0], 0};
    const double s = dot(d, along);
    const double beyond_ends = std::max({0.0, -s, s - len});
    return std::hypot(beyond_ends, std::max(0.0, std::abs(dot(d, across)) - n.width_m / 2));
  }
  const Vec3 normal = normalized(cross(n.edge_a, n.edge_b));
  const double offset = dot(d, normal);
  const Vec3 q = sub(d, scale(normal, offset));  // in the plane, relative to the corner
  const double aa = dot(n.edge_a, n.edge_a), ab = dot(n.edge_a, n.edge_b), bb = dot(n.edge_b, n.edge_b);
  const double det = aa * bb - ab * ab;
  const double s = (dot(q, n.edge_a) * bb - dot(q, n.edge_b) * ab) / det;
  const double t = (dot(q, n.edge_b) * aa - dot(q, n.edge_a) * ab) / det;
  double in_plane = 0;
  if (s < 0 || s > 1 || t < 0 || t > 1) {
    const Vec3 zero{0, 0, 0}, a = n.edge_a, b = n.edge_b;
    const auto to_edge = [&](const Vec3& from, const Vec3& edge) {
      return distance_to_segment(q, from, normalized(edge), norm(edge));
    };
    in_plane = std::min({to_edge(zero, a), to_edge(zero, b), to_edge(a, b), to_edge(b, a)});
  }
  return std::hypot(in_plane, std::max(0.0, std::abs(offset) - n.width_m / 2));
}

Inclusion read_inclusion(const Section& s, const Specimen& spec) {
  s.allow_only({"name", "centre", "radius"});
  const double tol = geometric_tolerance(spec);
  Inclusion inc;
  inc.name = read_name(s, "name", "inclusion");
  inc.centre = read_point(s, "centre", spec.dimension);
  inc.radius_m = s.positive("radius", Quantity::Length);
  if (signed_distance_inside(spec.body, inc.centre) < inc.radius_m + tol)
    throw InputError(spec.file, s.path(), "inclusion (radius " + format_length(inc.radius_m) + ") reaches outside the body",
                     "a sphere/circle entirely inside the body");
  for (const auto& h : spec.holes) {
    const Vec3 offset = sub(inc.centre, h.entry);
    const double gap = spec.dimension == 2 ? norm(offset)
                       : h.depth_m     ? distance_to_segment(inc.centre, h.entry, h.axis, *h.depth_m)
                                       : norm(cross(offset, h.axis));  // through hole: distance to the axis line
    if (gap < inc.radius_m + h.radius_m + tol)
      throw InputError(spec.file, s.path(), "inclusion overlaps hole '" + h.name + "'", "inclusions clear of holes");
  }
  // A slot is cut out before the inclusions are fragmented in, so an inclusion reaching
  // into it would fill the slot again. Cracks are embedded and may cross an inclusion.
  for (const auto& n : spec.notches)
    if (n.kind == Notch::Kind::Slot && distance_to_slot(spec, n, inc.centre) < inc.radius_m + tol)
      throw InputError(spec.file, s.path(), "inclusion overlaps slot '" + n.name + "'", "inclusions clear of slots");
  for (const auto& other : spec.inclusions)
    if (norm(sub(inc.centre, other.centre)) < inc.radius_m + other.radius_m + tol)
      throw InputError(spec.file, s.path(), "inclusion overlaps another inclusion", "non-overlapping inclusions");
  return inc;
}

MeshSettings read_mesh(const Section& s, const std::set<std::string>& groups) {
  s.allow_only({"size", "refine", "optimize", "algorithm_3d"});
  MeshSettings m;
  m.size_m = s.positive("size", Quantity::Length);
  m.optimize = s.boolean("optimize", true);
  m.algorithm_3d = s.choice("algorithm_3d", {"delaunay", "hxt"}, "delaunay") == "hxt" ? Algorithm3D::Hxt : Algorithm3D::Delaunay;
  for (const auto& r : s.list("refine")) {
    r.allow_only({"near", "size", "distance_min", "distance_max"});
    Refinement ref;
    ref.near = r.text("near");
    if (!groups.count(ref.near)) {
      std::string known;
      for (const auto& g : groups) known += (known.empty() ? "" : ", ") + g;
      throw InputError(s.file(), r.field("near"), "no group named '" + ref.near + "'", "one of: " + known);
    }
    ref.size_m = r.positive("size", Quantity::Length);
    if (ref.size_m > m.size_m)
      throw InputError(s.file(), r.field("size"), format_length(ref.size_m) + " is larger than mesh.size " + format_length(m.size_m),
                       "a refinement size <= mesh.size");
    ref.distance_min_m = r.number("distance_min", Quantity::Length, 0.0);
    if (ref.distance_min_m < 0)
      throw InputError(s.file(), r.field("distance_min"), "value " + format_length(ref.distance_min_m) + " is negative", "a length >= 0");
    ref.distance_max_m = r.positive("distance_max", Quantity::Length);
    if (ref.distance_max_m <= ref.distance_min_m)
      throw InputError(s.file(), r.field("distance_max"), format_length(ref.distance_max_m) + " is not beyond distance_min",
                       "distance_max > distance_min");
    m.refine.push_back(ref);
  }
  return m;
}

}  // namespace

std::vector<std::string> body_boundary_groups(const Specimen& spec) {
  switch (spec.body.shape) {
    case BodyShape::Box:
      return {"xmin", "xmax", "ymin", "ymax", "zmin", "zmax", "bottom", "top", "sides", "outer"};
    case BodyShape::Rectangle:
      return {"xmin", "xmax", "ymin", "ymax", "bottom", "top", "sides", "outer"};
    case BodyShape::Cylinder:
      return {"bottom", "top", "lateral", "outer"};
    case BodyShape::Disc:
      return {"outer"};
  }
  return {};
}

Specimen load_specimen(const std::string& file) {
  const Section root = Section::load_file(file);
  root.allow_only({"description", "dimension", "thickness", "body", "holes", "notches", "inclusions", "groups", "mesh"});
  Specimen spec;
  spec.file = file;
  spec.dimension = static_cast<int>(root.integer("dimension", 3));
  if (spec.dimension != 2 && spec.dimension != 3)
    throw InputError(file, "dimension", "'" + std::to_string(spec.dimension) + "'", "2 or 3");
  spec.thickness_m = root.positive("thickness", Quantity::Length, spec.dimension == 2 ? 1.0 : 0.0);
  const Section body = root.section("body");
  if (spec.dimension == 3 && body.has("shape") && body.text("shape") == "plate" && !root.has("thickness"))
    throw InputError(file, "thickness", "missing", "the plate thickness (a length)");
  spec.body = read_body(body, spec.dimension, spec.thickness_m);
  // The body's cells and its faces are groups of different dimension; one name for both
  // would leave only one of them in the mesh.
  const auto own = body_boundary_groups(spec);
  if (std::count(own.begin(), own.end(), spec.body.name))
    throw InputError(file, body.field("name"), "'" + spec.body.name + "' is a boundary group of the body", "a distinct name");

  std::set<std::string> surface_groups;  // (dim - 1) group names
  for (const auto& g : own) surface_groups.insert(g);
  std::set<std::string> volume_groups{spec.body.name};
  auto claim_surface = [&](const Section& s, const std::string& name) {
    if (volume_groups.count(name))
      throw InputError(file, s.field("name"), "'" + name + "' is already a volume group name", "a distinct name");
    surface_groups.insert(name);
  };

  for (const auto& h : root.list("holes")) {
    spec.holes.push_back(read_hole(h, spec));
    if (std::count(own.begin(), own.end(), spec.holes.back().name))
      throw InputError(file, h.field("name"), "'" + spec.holes.back().name + "' is a boundary group of the body", "a distinct name");
    claim_surface(h, spec.holes.back().name);
  }
  for (const auto& n : root.list("notches")) {
    spec.notches.push_back(read_notch(n, spec));
    const auto& name = spec.notches.back().name;
    if (std::count(own.begin(), own.end(), name) ||
        std::any_of(spec.holes.begin(), spec.holes.end(), [&](const Hole& h) { return h.name == name; }))
      throw InputError(file, n.field("name"), "'" + name + "' is already used by the body or a hole", "a distinct name");
    claim_surface(n, name);
  }
  for (const auto& i : root.list("inclusions")) {
    spec.inclusions.push_back(read_inclusion(i, spec));
    const auto& name = spec.inclusions.back().name;
    if (surface_groups.count(name))
      throw InputError(file, i.field("name"), "'" + name + "' is already a boundary group name", "a distinct name");
    volume_groups.insert(name);
  }
  if (const auto groups = root.optional_section("groups")) {
    for (const auto& kv : groups->node()) {
      const std::string alias = kv.first.as<std::string>();
      const std::string field = groups->field(alias);
      if (surface_groups.count(alias) || volume_groups.count(alias))
        throw InputError(file, field, "'" + alias + "' already exists", "a new group name");
      const auto members = groups->texts(alias);
      if (members.empty()) throw InputError(file, field, "is empty", "a list of group names");
      const bool surfaces = surface_groups.count(members.front()) > 0;
      for (const auto& m : members) {
        if (!(surfaces ? surface_groups : volume_groups).count(m))
          throw InputError(file, field, "'" + m + "' is not a " + std::string(surfaces ? "boundary" : "volume") +
                                            " group (all members must be of one kind)",
                           "names of existing groups");
      }
      spec.group_aliases[alias] = members;
    }
    for (const auto& [alias, members] : spec.group_aliases)
      (surface_groups.count(members.front()) ? surface_groups : volume_groups).insert(alias);
  }
  std::set<std::string> all = surface_groups;
  all.insert(volume_groups.begin(), volume_groups.end());
  spec.mesh = read_mesh(root.section("mesh"), all);
  return spec;
}

}  // namespace breccia::mesher
