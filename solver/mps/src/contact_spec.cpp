#include "breccia/mps/contact_spec.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <string>

#include "breccia/common/error.hpp"
#include "breccia/common/yaml_input.hpp"

namespace breccia::mps {
namespace {

[[noreturn]] void fail(const Section& s, const std::string& key, const std::string& found, const std::string& expected) {
  throw InputError(s.file(), s.field(key), found, expected);
}

std::string text_of(double v) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

// Proper intersection of segments ab and cd (shared end points of neighbouring edges are
// excluded by the caller).
bool segments_cross(const double* a, const double* b, const double* c, const double* d) {
  auto orient = [](const double* p, const double* q, const double* r) {
    const double v = (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]);
    return (v > 0) - (v < 0);
  };
  auto on = [](const double* p, const double* q, const double* r) {  // r on segment pq (collinear)
    return std::min(p[0], q[0]) <= r[0] && r[0] <= std::max(p[0], q[0]) && std::min(p[1], q[1]) <= r[1] &&
           r[1] <= std::max(p[1], q[1]);
  };
  const int o1 = orient(a, b, c), o2 = orient(a, b, d), o3 = orient(c, d, a), o4 = orient(c, d, b);
  if (o1 != o2 && o3 != o4) return true;
  return (o1 == 0 && on(a, b, c)) || (o2 == 0 && on(a, b, d)) || (o3 == 0 && on(c, d, a)) || (o4 == 0 && on(c, d, b));
}

}  // namespace

std::vector<std::string> friction_keys() { return {"static_friction", "kinetic_friction", "tangential_stiffness_factor"}; }

FrictionSpec parse_friction(const Section& s) {
  FrictionSpec f;
  f.static_friction = s.number("static_friction", Quantity::Dimensionless, 0.0);
  if (!(f.static_friction >= 0)) fail(s, "static_friction", text_of(f.static_friction), "a friction coefficient mu_s >= 0");
  f.kinetic_friction = s.number("kinetic_friction", Quantity::Dimensionless, f.static_friction);
  if (!(f.kinetic_friction >= 0)) fail(s, "kinetic_friction", text_of(f.kinetic_friction), "a friction coefficient mu_k >= 0");
  if (f.kinetic_friction > f.static_friction)
    fail(s, "kinetic_friction", "mu_k = " + text_of(f.kinetic_friction) + " > mu_s = " + text_of(f.static_friction),
         "kinetic friction <= static friction");
  f.tangential_stiffness_factor = s.positive("tangential_stiffness_factor", Quantity::Dimensionless, 1.0);
  return f;
}

BodiesSpec parse_bodies(const Section& s) {
  s.allow_only({"dimension", "spacing", "thickness", "shapes"});
  BodiesSpec b;
  b.dimension = static_cast<int>(s.integer("dimension", 2));
  if (b.dimension != 2 && b.dimension != 3) fail(s, "dimension", std::to_string(b.dimension), "2 or 3");
  b.spacing_m = s.positive("spacing", Quantity::Length);
  b.thickness_m = s.positive("thickness", Quantity::Length, b.dimension == 2 ? b.spacing_m : 1.0);
  const auto shapes = s.list("shapes");
  if (shapes.empty()) fail(s, "shapes", "missing or empty", "a list of bodies, e.g. [{type: annulus, ...}]");
  for (size_t k = 0; k < shapes.size(); ++k) {
    const Section& e = shapes[k];
    e.allow_only({"name", "type", "box", "center", "inner_radius", "outer_radius", "radius", "length", "velocity"});
    BodyShapeSpec sh;
    sh.name = e.text("name", "body" + std::to_string(k));
    for (size_t m = 0; m < k; ++m)
      if (b.shapes[m].name == sh.name) fail(e, "name", "'" + sh.name + "' used twice", "a unique body name");
    sh.type = e.choice("type", {"box", "annulus", "cylinder"});
    if (sh.type != "cylinder")
      for (const char* key : {"radius", "length"})
        if (e.has(key)) fail(e, key, "given for a " + sh.type, "radius and length for type: cylinder only");
    if (sh.type == "box") {
      const auto v = e.numbers("box", Quantity::Length, b.dimension == 2 ? 4 : 6);
      sh.box_m = {0, 0, 0, 0, 0, 0};
      for (int a = 0; a < b.dimension; ++a) {
        sh.box_m[a] = v[a];
        sh.box_m[3 + a] = v[a + b.dimension];
        if (!(sh.box_m[3 + a] > sh.box_m[a]))
          fail(e, "box", "upper corner not above lower corner", "[x0, y0, x1, y1] with x1 > x0, y1 > y0");
        if (sh.box_m[3 + a] - sh.box_m[a] < b.spacing_m)
          fail(e, "box", "thinner than one spacing", "a box at least one particle spacing across");
      }
      for (const char* key : {"center", "inner_radius", "outer_radius"})
        if (e.has(key)) fail(e, key, "given for a box", "center and radii for type: annulus only");
    } else if (sh.type == "cylinder") {
      if (b.dimension != 3) fail(e, "type", "cylinder in a 2D model", "cylinder in 3D only (annulus in 2D)");
      for (const char* key : {"box", "inner_radius", "outer_radius"})
        if (e.has(key)) fail(e, key, "given for a cylinder", "center (of the lower end face), radius, length");
      sh.center_m = e.vec3("center", Quantity::Length);
      sh.outer_radius_m = e.positive("radius", Quantity::Length);
      sh.length_m = e.positive("length", Quantity::Length);
      if (sh.outer_radius_m < b.spacing_m)
        fail(e, "radius", text_of(sh.outer_radius_m) + " m", "at least one spacing (" + text_of(b.spacing_m) + " m)");
      if (sh.length_m < b.spacing_m)
        fail(e, "length", text_of(sh.length_m) + " m", "at least one spacing (" + text_of(b.spacing_m) + " m)");
    } else {
      if (b.dimension != 2) fail(e, "type", "annulus in a 3D model", "annulus in 2D only (box or cylinder in 3D)");
      if (e.has("box")) fail(e, "box", "given for an annulus", "center, inner_radius, outer_radius");
      sh.center_m = e.vec3("center", Quantity::Length);
      sh.inner_radius_m = e.number("inner_radius", Quantity::Length, 0.0);
      sh.outer_radius_m = e.positive("outer_radius", Quantity::Length);
      if (!(sh.inner_radius_m >= 0)) fail(e, "inner_radius", text_of(sh.inner_radius_m) + " m", "a radius >= 0");
      if (!(sh.outer_radius_m - sh.inner_radius_m >= b.spacing_m))
        fail(e, "outer_radius", text_of(sh.outer_radius_m) + " m",
             "at least one spacing above inner_radius (" + text_of(sh.inner_radius_m) + " m)");
    }
    if (e.has("velocity")) sh.velocity_m_s = e.vec3("velocity", Quantity::Velocity);
    b.shapes.push_back(sh);
  }
  return b;
}

ParticleContactSpec parse_particle_contact(const Section& s) {
  std::vector<std::string> keys{"distance_factor", "stiffness_factor", "normal"};
  for (const auto& k : friction_keys()) keys.push_back(k);
  s.allow_only(keys);
  ParticleContactSpec p;
  p.distance_factor = s.positive("distance_factor", Quantity::Dimensionless, 1.0);
  if (p.distance_factor > 2.0)
    fail(s, "distance_factor", text_of(p.distance_factor), "0 < distance_factor <= 2 (contact distance in spacings)");
  p.stiffness_factor = s.positive("stiffness_factor", Quantity::Dimensionless, 1.0);
  if (s.has("normal")) p.normal = s.choice("normal", {"pair", "neighbour_distribution"});
  p.friction = parse_friction(s);
  return p;
}

PrescribedMotion parse_motion(const Section& s, int dimension) {
  s.allow_only({"quantity", "direction", "history", "unit"});
  PrescribedMotion m;
  const std::string q = s.choice("quantity", {"acceleration", "velocity", "displacement"});
  m.quantity = q == "acceleration" ? PrescribedMotion::Quantity::Acceleration
               : q == "velocity"   ? PrescribedMotion::Quantity::Velocity
                                   : PrescribedMotion::Quantity::Displacement;
  if (s.has("direction")) m.direction = s.vec3("direction", Quantity::Dimensionless);
  // In 2D (plane strain) a z part moved the floor out of the plane: its slip there used up the
  // friction and its work was booked, while a polygon's motion silently lost it.
  if (dimension == 2 && m.direction[2] != 0.0)
    fail(s, "direction", "a z component in a 2D case", "an in-plane direction [x, y]");
  const double len = std::hypot(m.direction[0], m.direction[1], m.direction[2]);
  if (!(len > 0)) fail(s, "direction", "a zero vector", "a nonzero direction [x, y, z]");
  for (double& c : m.direction) c /= len;
  if (!s.has("history")) fail(s, "history", "missing", "a history {type: constant | ramp | double_exponential | table, ...}");
  const Quantity unit = m.quantity == PrescribedMotion::Quantity::Acceleration ? Quantity::Acceleration
                        : m.quantity == PrescribedMotion::Quantity::Velocity   ? Quantity::Velocity
                                                                               : Quantity::Length;
  m.history = solver::parse_history(s.section("history"), unit);
  // A displacement history is the motion's offset from the start: one not at 0 at t = 0 made
  // the floor jump in the first step, its work unbooked.
  if (m.quantity == PrescribedMotion::Quantity::Displacement && m.history.at(0.0) != 0.0)
    fail(s, "history", "a displacement of " + text_of(m.history.at(0.0)) + " m at t = 0",
         "a displacement history starting at 0 (the obstacle's place at the start is its point)");
  if (s.has("unit")) {
    // A table (or numbers) in g: the usual form of an accelerogram.
    const std::string u = s.choice("unit", {"g", "m/s2"});
    if (m.quantity != PrescribedMotion::Quantity::Acceleration)
      fail(s, "unit", "'" + u + "' for quantity: " + q, "unit only with quantity: acceleration");
    // unit: scales plain numbers and tables; a value given with its own unit ("0.1 g", read as
    // m/s2 already) was scaled again (9.8 times too large).
    const Section h = s.section("history");
    for (const char* key : {"value", "peak"})
      if (h.node()[key] && h.node()[key].IsScalar()) {
        const std::string text = h.node()[key].as<std::string>();
        char* end = nullptr;
        std::strtod(text.c_str(), &end);
        if (end == text.c_str() || *end != '\0')
          fail(h, key, "'" + text + "' with unit: " + u, "a plain number (unit: scales plain numbers and tables)");
      }
    const double scale = u == "g" ? 9.80665 : 1.0;
    m.history.value *= scale;
    for (double& v : m.history.table_value) v *= scale;
  }
  return m;
}

LameConstants lame_of_youngs(double youngs_modulus_pa, double poisson_ratio) {
  const double e = youngs_modulus_pa, nu = poisson_ratio;
  return {e * nu / ((1 + nu) * (1 - 2 * nu)), e / (2 * (1 + nu))};
}

double ContactLayerSpec::normal_stiffness_pa_m() const {
  const LameConstants l = lame_of_youngs(youngs_modulus_pa, poisson_ratio);
  return (l.lambda_pa + 2.0 * l.mu_pa) / thickness_m;
}

double ContactLayerSpec::tangential_stiffness_pa_m() const {
  return lame_of_youngs(youngs_modulus_pa, poisson_ratio).mu_pa / thickness_m;
}

RigidBodySpec parse_rigid_body(const Section& s, size_t index, int dimension) {
  std::vector<std::string> keys{"name",           "vertices",         "fixed",  "density", "velocity",
                                "angular_velocity", "stiffness_factor", "stiffness_length", "contact_layer", "restitution", "floor_restitution", "motion"};
  for (const auto& k : friction_keys()) keys.push_back(k);
  s.allow_only(keys);
  RigidBodySpec r;
  r.name = s.text("name", "rigid" + std::to_string(index));
  if (dimension != 2) fail(s, "vertices", "a rigid polygon in a 3D model", "rigid_bodies in 2D only (contact.floor in 3D)");
  if (!s.has("vertices")) fail(s, "vertices", "missing", "a closed polygon [[x0, y0], [x1, y1], [x2, y2], ...]");
  const YAML::Node v = s.node()["vertices"];
  if (!v.IsSequence()) fail(s, "vertices", "not a list of points", "[[x0, y0], [x1, y1], [x2, y2], ...]");
  for (size_t k = 0; k < v.size(); ++k) {
    YAML::Node wrapper;
    wrapper["point"] = v[k];
    const auto p = Section(wrapper, s.file(), s.field("vertices") + "[" + std::to_string(k) + "]").vec3("point", Quantity::Length);
    r.x_m.push_back(p[0]);
    r.y_m.push_back(p[1]);
  }
  // A repeated first vertex at the end closes the polygon explicitly; drop it.
  if (r.x_m.size() > 1 && r.x_m.front() == r.x_m.back() && r.y_m.front() == r.y_m.back()) {
    r.x_m.pop_back();
    r.y_m.pop_back();
  }
  const size_t n = r.x_m.size();
  if (n < 3)
    fail(s, "vertices", std::to_string(n) + " distinct vertices: not a closed polygon",
         "at least 3 vertices enclosing an area (the last joins the first)");
  for (size_t k = 0; k < n; ++k) {
    const size_t m = (k + 1) % n;
    if (r.x_m[k] == r.x_m[m] && r.y_m[k] == r.y_m[m])
      fail(s, "vertices", "vertex " + std::to_string(k) + " repeated: a degenerate edge", "distinct consecutive vertices");
  }
  for (size_t k = 0; k < n; ++k)
    for (size_t m = k + 1; m < n; ++m) {
      if (m == k + 1 || (k == 0 && m == n - 1)) continue;  // neighbouring edges share a vertex
      const double a[2] = {r.x_m[k], r.y_m[k]}, b[2] = {r.x_m[(k + 1) % n], r.y_m[(k + 1) % n]};
      const double c[2] = {r.x_m[m], r.y_m[m]}, d[2] = {r.x_m[(m + 1) % n], r.y_m[(m + 1) % n]};
      if (segments_cross(a, b, c, d))
        fail(s, "vertices", "edges " + std::to_string(k) + " and " + std::to_string(m) + " cross: a self-intersecting polygon",
             "a simple polygon (edges meet only at shared vertices)");
    }
  double area2 = 0.0, extent = 0.0;
  for (size_t k = 0, m = n - 1; k < n; m = k++) {
    area2 += r.x_m[m] * r.y_m[k] - r.x_m[k] * r.y_m[m];
    extent = std::max(extent, std::hypot(r.x_m[k] - r.x_m[0], r.y_m[k] - r.y_m[0]));
  }
  if (!(std::fabs(area2) > 1e-12 * extent * extent))
    fail(s, "vertices", "zero area (collinear vertices): a degenerate polygon", "vertices enclosing an area");
  r.fixed = s.boolean("fixed", true);
  if (s.has("motion")) {
    if (!r.fixed)
      fail(s, "motion", "given for a free body (fixed: false)",
           "fixed: true: a prescribed motion (ground motion) drives a fixed body; a free body moves under its "
           "contacts and gravity");
    r.motion = parse_motion(s.section("motion"), dimension);
  }
  if (r.fixed) {
    for (const char* key : {"density", "velocity", "angular_velocity"})
      if (s.has(key)) fail(s, key, "given for a fixed body", "fixed: false for a free rigid body");
  } else {
    if (!s.has("density")) fail(s, "density", "missing for a free body", "a density (kg/m^3): mass = density x area x thickness");
    r.density_kg_m3 = s.positive("density", Quantity::Density);
    if (s.has("velocity")) r.velocity_m_s = s.vec3("velocity", Quantity::Velocity);
    // rad/s; "1 Hz" is a turn a second (read as a frequency it was 1 rad/s, 2 pi too slow).
    r.angular_velocity_rad_s = s.number("angular_velocity", Quantity::AngularVelocity, 0.0);
  }
  r.stiffness_factor = s.positive("stiffness_factor", Quantity::Dimensionless, 1.0);
  if (s.has("stiffness_length")) r.stiffness_length_m = s.positive("stiffness_length", Quantity::Length, 0.0);
  if (auto l = s.optional_section("contact_layer")) {
    if (s.has("stiffness_length"))
      fail(s, "contact_layer", "given with stiffness_length",
           "one of them: contact_layer (the stiffness per unit area from a layer's material and thickness) or "
           "stiffness_length (a layer of the particles' material)");
    l->allow_only({"youngs_modulus", "poisson_ratio", "thickness"});
    for (const char* key : {"youngs_modulus", "poisson_ratio", "thickness"})
      if (!l->has(key))
        fail(*l, key, "missing",
             "contact_layer: {youngs_modulus: E, poisson_ratio: nu, thickness: t} (the polygon's material and the "
             "thickness of the layer that stands in for its compliance)");
    ContactLayerSpec c;
    c.youngs_modulus_pa = l->positive("youngs_modulus", Quantity::Pressure);
    c.poisson_ratio = l->number("poisson_ratio", Quantity::Dimensionless);
    if (!(c.poisson_ratio > -1.0 && c.poisson_ratio < 0.5)) fail(*l, "poisson_ratio", text_of(c.poisson_ratio), "-1 < nu < 0.5");
    c.thickness_m = l->positive("thickness", Quantity::Length);
    r.contact_layer = c;
  }
  // A coefficient of restitution: 0 < e <= 1 (1, the default: no dashpot).
  auto restitution = [&](const char* key) {
    if (!s.has(key)) return 1.0;
    const double e = s.number(key, Quantity::Dimensionless, 1.0);
    if (!(e > 0.0 && e <= 1.0))
      fail(s, key, text_of(e),
           "a coefficient of restitution 0 < e <= 1 (1: elastic, no dashpot; 0 would be a perfectly plastic impact, "
           "which a spring-dashpot cannot give)");
    return e;
  };
  r.restitution = restitution("restitution");
  r.floor_restitution = restitution("floor_restitution");
  if (r.fixed && s.has("floor_restitution"))
    fail(s, "floor_restitution", "given for a fixed body", "fixed: false (a free body's vertices rest on the floor)");
  r.friction = parse_friction(s);
  return r;
}

}  // namespace breccia::mps
