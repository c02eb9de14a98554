#pragma once
// Exact orientation tests (CGAL, exact predicates with a floating-point filter), kept in
// one translation unit so that only it pays CGAL's compile time.
namespace breccia::geometry::detail {

// Sign of det[b - a, c - a, d - a]: +1 positively oriented tetrahedron, 0 flat, -1 inverted.
int tetrahedron_orientation(const double* a, const double* b, const double* c, const double* d);

// Sign of the 2D cross product (b - a) x (c - a), using x and y only: 0 means collinear.
int triangle_orientation_xy(const double* a, const double* b, const double* c);

}  // namespace breccia::geometry::detail
