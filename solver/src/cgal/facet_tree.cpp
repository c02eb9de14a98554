#include "facet_tree.hpp"

#include <CGAL/AABB_segment_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace breccia::solver {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Segment = Kernel::Segment_3;
using Triangle = Kernel::Triangle_3;
using TriangleTree =
    CGAL::AABB_tree<CGAL::AABB_traits<Kernel, CGAL::AABB_triangle_primitive<Kernel, std::vector<Triangle>::const_iterator>>>;
using SegmentTree =
    CGAL::AABB_tree<CGAL::AABB_traits<Kernel, CGAL::AABB_segment_primitive<Kernel, std::vector<Segment>::const_iterator>>>;

Point point(const double* x) { return Point(x[0], x[1], x[2]); }

}  // namespace

struct FacetTree::Impl {
  int dimension = 3;
  std::vector<Triangle> triangles;  // 3D
  std::vector<Segment> segments;    // 2D
  TriangleTree triangle_tree;
  SegmentTree segment_tree;
  double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
};

FacetTree::FacetTree(int dimension, const std::vector<double>& vertices_m) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.dimension = dimension;
  const size_t per_facet = static_cast<size_t>(dimension);
  if (dimension != 2 && dimension != 3) throw std::invalid_argument("FacetTree: dimension must be 2 or 3");
  const size_t nf = vertices_m.size() / (3 * per_facet);
  for (size_t f = 0; f < nf; ++f) {
    const double* v = &vertices_m[f * per_facet * 3];
    if (dimension == 3) {
      const Triangle t(point(v), point(v + 3), point(v + 6));
      if (!t.is_degenerate()) m.triangles.push_back(t);
    } else {
      const Segment s(point(v), point(v + 3));
      if (!s.is_degenerate()) m.segments.push_back(s);
    }
  }
  // Build both the tree and the distance queries' search tree now: queries from several
  // threads must find them ready (their lazy construction is not thread-safe).
  if (dimension == 3 && !m.triangles.empty()) {
    m.triangle_tree.insert(m.triangles.begin(), m.triangles.end());
    m.triangle_tree.build();
    m.triangle_tree.accelerate_distance_queries();
  } else if (dimension == 2 && !m.segments.empty()) {
    m.segment_tree.insert(m.segments.begin(), m.segments.end());
    m.segment_tree.build();
    m.segment_tree.accelerate_distance_queries();
  }
  if (size() > 0) {
    const CGAL::Bbox_3 b = dimension == 3 ? m.triangle_tree.bbox() : m.segment_tree.bbox();
    for (int d = 0; d < 3; ++d) m.lo[d] = b.min(d), m.hi[d] = b.max(d);
  }
}

FacetTree::~FacetTree() = default;

size_t FacetTree::size() const { return impl_->dimension == 3 ? impl_->triangles.size() : impl_->segments.size(); }

bool FacetTree::crosses(const double* p, const double* q) const {
  const Impl& m = *impl_;
  if (size() == 0) return false;
  for (int d = 0; d < 3; ++d)  // most bonds are far from the surface: reject before the tree
    if (std::max(p[d], q[d]) < m.lo[d] || std::min(p[d], q[d]) > m.hi[d]) return false;
  const Segment bond(point(p), point(q));
  if (bond.is_degenerate()) return false;
  return m.dimension == 3 ? m.triangle_tree.do_intersect(bond) : m.segment_tree.do_intersect(bond);
}

double FacetTree::distance(const double* p) const {
  const Impl& m = *impl_;
  if (size() == 0) return HUGE_VAL;
  const double d2 = CGAL::to_double(m.dimension == 3 ? m.triangle_tree.squared_distance(point(p))
                                                     : m.segment_tree.squared_distance(point(p)));
  return std::sqrt(d2);
}

double FacetTree::box_distance_squared(const double* p) const {
  const Impl& m = *impl_;
  if (size() == 0) return HUGE_VAL;
  double d2 = 0.0;
  for (int d = 0; d < 3; ++d) {
    const double out = std::max({m.lo[d] - p[d], 0.0, p[d] - m.hi[d]});
    d2 += out * out;
  }
  return d2;
}

}  // namespace breccia::solver
