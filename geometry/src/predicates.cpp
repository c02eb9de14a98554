#include "predicates.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

namespace breccia::geometry::detail {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;

int tetrahedron_orientation(const double* a, const double* b, const double* c, const double* d) {
  const auto p = [](const double* x) { return Kernel::Point_3(x[0], x[1], x[2]); };
  return static_cast<int>(CGAL::orientation(p(a), p(b), p(c), p(d)));
}

int triangle_orientation_xy(const double* a, const double* b, const double* c) {
  const auto p = [](const double* x) { return Kernel::Point_2(x[0], x[1]); };
  return static_cast<int>(CGAL::orientation(p(a), p(b), p(c)));
}

}  // namespace breccia::geometry::detail
