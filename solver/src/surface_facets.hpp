#pragma once
// The real shape of a named surface of particles.h5 (triangles in 3D, edges in 2D) for the
// set-up's geometric queries: which bonds a `surface` pre-crack cuts and which particles a
// `near_surface` set holds, both through CGAL's AABB tree (cgal/facet_tree.hpp).
#include <memory>
#include <string>
#include <vector>

#include "breccia/common/particle_file.hpp"
#include "cgal/facet_tree.hpp"

namespace breccia::solver {

struct FacetVertices {
  // File: /surfaces/<name>/vertices (format version 2). Mesh: recovered from the owner cells
  // of /mesh (older files). Squares: neither; each facet a square of its area in its plane
  // (2D: an edge of its length), edges along the axes when the normal is an axis, which is
  // a lattice's facets exactly.
  enum class Source { File, Mesh, Squares } source = Source::File;
  std::vector<double> vertices_m;  // F x 3 x 3 (triangles; Squares: 2F triangles) or F x 2 x 3 (2D)
  std::string why_approximate;     // Squares only: why the real facets are unknown
};

FacetVertices facet_vertices(const ParticleModel& model, const SurfaceFacets& facets);

// The tree over a surface's facets. When only the squares are known and the model is not a
// lattice (whose facets they are), `note` receives a line saying so (the caller prints it
// once, naming its field); otherwise it is left empty.
std::unique_ptr<FacetTree> surface_facet_tree(const ParticleModel& model, const SurfaceFacets& facets,
                                              std::string& note);

}  // namespace breccia::solver
