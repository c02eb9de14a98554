#pragma once
// Small analytic geometry used to validate a spec and to recognise the faces of the
// meshed model (vector algebra, signed distance to the body).
#include <algorithm>
#include <cmath>

#include "breccia/mesher/specimen.hpp"

namespace breccia::mesher {

inline Vec3 add(const Vec3& a, const Vec3& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
inline Vec3 sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
inline Vec3 scale(const Vec3& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }
inline double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
inline double norm(const Vec3& a) { return std::sqrt(dot(a, a)); }
inline Vec3 normalized(const Vec3& a) { return scale(a, 1.0 / norm(a)); }

// Largest extent of the body; sets the scale of geometric tolerances.
inline double body_extent(const Body& b) {
  switch (b.shape) {
    case BodyShape::Box:
    case BodyShape::Rectangle: return std::max({b.size[0], b.size[1], b.size[2]});
    case BodyShape::Cylinder: return std::max(2 * b.radius_m, b.height_m);
    case BodyShape::Disc: return 2 * b.radius_m;
  }
  return 1.0;
}

// OpenCASCADE works to ~1e-7 of the model size; 1e-6 keeps face recognition well clear
// of that while staying far below any feature a spec can meaningfully ask for.
inline double geometric_tolerance(const Specimen& s) { return 1e-6 * body_extent(s.body); }

// Distance from p to the body's boundary, positive inside, negative outside (exact
// inside; outside it is a lower bound on the distance, enough for inside/outside tests).
inline double signed_distance_inside(const Body& b, const Vec3& p) {
  const Vec3 q = sub(p, b.origin);
  switch (b.shape) {
    case BodyShape::Box:
      return std::min({q[0], b.size[0] - q[0], q[1], b.size[1] - q[1], q[2], b.size[2] - q[2]});
    case BodyShape::Rectangle:
      return std::min({q[0], b.size[0] - q[0], q[1], b.size[1] - q[1]});
    case BodyShape::Cylinder:
      return std::min({b.radius_m - std::hypot(q[0], q[1]), q[2], b.height_m - q[2]});
    case BodyShape::Disc:
      return b.radius_m - std::hypot(q[0], q[1]);
  }
  return 0;
}

// Distance from p to the segment start + t * axis, t in [0, length] (axis a unit vector).
inline double distance_to_segment(const Vec3& p, const Vec3& start, const Vec3& axis, double length) {
  const double t = std::clamp(dot(sub(p, start), axis), 0.0, length);
  return norm(sub(p, add(start, scale(axis, t))));
}

}  // namespace breccia::mesher
