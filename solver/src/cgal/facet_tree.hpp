#pragma once
// CGAL's AABB tree over the facets of one surface: triangles in 3D, edges (segments in
// z = 0) in 2D. Exact predicates (Epick): a bond through a shared edge or vertex of two
// facets is never missed by round-off, as a floating-point ray test can. Compiled in its
// own library (solver/src/cgal/) so that CGAL's -frounding-math and compile time stay out
// of the solver's physics.
#include <cstddef>
#include <memory>
#include <vector>

namespace breccia::solver {

class FacetTree {
public:
  // vertices_m: F x dimension x 3 (see FacetVertices). Degenerate facets (zero area or
  // length) are left out: they separate nothing and have no distance of their own.
  FacetTree(int dimension, const std::vector<double>& vertices_m);
  ~FacetTree();
  FacetTree(const FacetTree&) = delete;
  FacetTree& operator=(const FacetTree&) = delete;

  // Does the closed segment p -> q touch a facet? Symmetric in p and q. Thread-safe.
  bool crosses(const double* p, const double* q) const;
  // Distance from p to the nearest facet (m). Thread-safe.
  double distance(const double* p) const;
  // Squared distance from p to the facets' bounding box: a cheap lower bound of distance^2.
  double box_distance_squared(const double* p) const;
  size_t size() const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace breccia::solver
