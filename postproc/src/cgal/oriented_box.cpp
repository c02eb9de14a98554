#include "oriented_box.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/convex_hull_2.h>
#include <CGAL/min_quadrilateral_2.h>
#include <CGAL/optimal_bounding_box.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <vector>

namespace breccia::postproc {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;

// The direction of the first edge of the minimal-area rectangle around plane points.
std::optional<std::array<double, 2>> rectangle_direction(const std::vector<Kernel::Point_2>& points) {
  std::vector<Kernel::Point_2> hull, rectangle;
  CGAL::convex_hull_2(points.begin(), points.end(), std::back_inserter(hull));
  if (hull.size() < 3) return std::nullopt;  // all on a line
  CGAL::min_rectangle_2(hull.begin(), hull.end(), std::back_inserter(rectangle));
  if (rectangle.size() < 2) return std::nullopt;
  const double ex = CGAL::to_double(rectangle[1].x() - rectangle[0].x());
  const double ey = CGAL::to_double(rectangle[1].y() - rectangle[0].y());
  const double len = std::hypot(ex, ey);
  if (!(len > 0)) return std::nullopt;
  return std::array<double, 2>{ex / len, ey / len};
}

std::optional<std::array<double, 9>> frame_2d(std::span<const double> xyz) {
  std::vector<Kernel::Point_2> points;
  for (size_t i = 0; i + 2 < xyz.size(); i += 3) points.emplace_back(xyz[i], xyz[i + 1]);
  const auto e = rectangle_direction(points);
  if (!e) return std::nullopt;
  return std::array<double, 9>{(*e)[0], (*e)[1], 0, -(*e)[1], (*e)[0], 0, 0, 0, 1};
}

// Points in one plane of normal n (a fragment one particle layer thick, to round-off): the
// rectangle in that plane, in the in-plane basis u, n x u; the third axis is n.
std::optional<std::array<double, 9>> frame_in_plane(const std::vector<Kernel::Point_3>& points, const Kernel::Vector_3& n,
                                                    const Kernel::Vector_3& u) {
  const Kernel::Vector_3 v = CGAL::cross_product(n, u);
  std::vector<Kernel::Point_2> planar;
  for (const auto& p : points) planar.emplace_back((p - points[0]) * u, (p - points[0]) * v);
  const auto e = rectangle_direction(planar);
  if (!e) return std::nullopt;
  const Kernel::Vector_3 a0 = (*e)[0] * u + (*e)[1] * v, a1 = CGAL::cross_product(n, a0);
  return std::array<double, 9>{a0.x(), a0.y(), a0.z(), a1.x(), a1.y(), a1.z(), n.x(), n.y(), n.z()};
}

std::optional<std::array<double, 9>> frame_3d(std::span<const double> xyz) {
  std::vector<Kernel::Point_3> points;
  for (size_t i = 0; i + 2 < xyz.size(); i += 3) points.emplace_back(xyz[i], xyz[i + 1], xyz[i + 2]);
  if (points.size() < 4 || points[0] == points[1]) return std::nullopt;
  // Exactly collinear or coplanar points (an unturned line or layer) would give the search
  // a degenerate hull: decide them first with exact predicates.
  size_t third = 2;
  while (third < points.size() && CGAL::collinear(points[0], points[1], points[third])) ++third;
  if (third == points.size()) return std::nullopt;
  bool spans = false;
  for (size_t k = third + 1; k < points.size() && !spans; ++k)
    spans = !CGAL::coplanar(points[0], points[1], points[third], points[k]);
  if (!spans) {
    Kernel::Vector_3 u = points[1] - points[0], n = CGAL::cross_product(u, points[third] - points[0]);
    u = u / std::sqrt(CGAL::to_double(u.squared_length()));
    n = n / std::sqrt(CGAL::to_double(n.squared_length()));
    return frame_in_plane(points, n, u);
  }
  CGAL::Aff_transformation_3<Kernel> rotation;  // sends the box to an axis-aligned one
  CGAL::oriented_bounding_box(points, rotation, CGAL::parameters::random_seed(0));
  std::array<Kernel::Vector_3, 3> axis;
  std::array<double, 3> extent{};
  for (int k = 0; k < 3; ++k) {
    axis[k] = Kernel::Vector_3(rotation.m(k, 0), rotation.m(k, 1), rotation.m(k, 2));  // row k = axis k
    double lo = HUGE_VAL, hi = -HUGE_VAL;
    for (const auto& p : points) {
      const double t = CGAL::to_double((p - CGAL::ORIGIN) * axis[k]);
      lo = std::min(lo, t), hi = std::max(hi, t);
    }
    extent[k] = hi - lo;
  }
  const int thin = static_cast<int>(std::min_element(extent.begin(), extent.end()) - extent.begin());
  const double widest = *std::max_element(extent.begin(), extent.end());
  if (!(widest > 0)) return std::nullopt;
  // Flat to round-off (one particle layer, turned): the volume the search minimises is
  // round-off too and leaves the in-plane turn arbitrary, so take the plane's rectangle.
  if (extent[thin] <= 1e-9 * widest) return frame_in_plane(points, axis[thin], axis[(thin + 1) % 3]);
  std::array<double, 9> frame{};
  for (int k = 0; k < 3; ++k)
    for (int d = 0; d < 3; ++d) frame[3 * k + d] = CGAL::to_double(axis[k][d]);
  return frame;
}

}  // namespace

std::optional<std::array<double, 9>> oriented_box_frame(std::span<const double> points_xyz, int dimension) {
  return dimension == 2 ? frame_2d(points_xyz) : frame_3d(points_xyz);
}

}  // namespace breccia::postproc
