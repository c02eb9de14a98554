#pragma once
// The frame of the smallest box around a point set, from CGAL: in 3D the minimal-volume
// oriented bounding box (CGAL::oriented_bounding_box: convex hull, then an evolutionary
// search over rotations with a fixed seed, so the answer repeats); in 2D (points in z = 0)
// the minimal-area rectangle of the convex hull (CGAL::min_rectangle_2, exact). Compiled
// in its own library (postproc/src/cgal/) so that CGAL's flags stay out of postproc's other
// sources.
#include <array>
#include <optional>
#include <span>

namespace breccia::postproc {

// Columns (axis k = frame[3k..3k+2]) of an orthonormal frame; nullopt when the points do
// not span the dimension (fewer than dimension + 1 of them, or all on a line/plane).
std::optional<std::array<double, 9>> oriented_box_frame(std::span<const double> points_xyz, int dimension);

}  // namespace breccia::postproc
