#pragma once
// A named facet group of particles.h5 used as a pre-crack: which bonds cross it.
// particles.h5 keeps each facet's centroid, normal, area and owning particle; when the model
// came from a mesh, the owner is the centroid of one mesh cell, so the facet's exact vertices
// are the face of that cell whose vertex mean is the stored centroid. Lattice models (no
// mesh) fall back to a disc of the facet's area in its plane.
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "breccia/common/particle_file.hpp"

namespace breccia::solver {

class SurfaceCut {
public:
  // max_bond_length_m: the longest bond that will be asked about (sizes the search grid).
  SurfaceCut(const ParticleModel& model, const SurfaceFacets& facets, double max_bond_length_m);
  // Does the segment p -> q (reference positions, 3 components) cross the surface?
  bool crosses(const double* p, const double* q) const;
  // True when every facet's vertices were recovered from the mesh.
  bool exact() const { return exact_; }

private:
  bool crosses_facet(size_t f, const double* p, const double* q) const;

  int dimension_ = 3;
  double thickness_m_ = 1.0;
  const SurfaceFacets* facets_ = nullptr;
  bool exact_ = false;
  std::vector<double> vertices_m_;  // F x 3 vertices x 3 (3D) or F x 2 x 3 (2D) when exact
  // Uniform grid of cell >= the longest bond over the facets' bounding boxes: a bond can
  // only cross facets registered in the 27 cells around its midpoint.
  double cell_m_ = 1.0, origin_m_[3] = {0, 0, 0};
  // The facets' bounding box: a bond entirely on one side of it is rejected before the grid
  // (most bonds of a body are far from its pre-crack).
  double box_lo_[3] = {1e300, 1e300, 1e300}, box_hi_[3] = {-1e300, -1e300, -1e300};
  std::unordered_map<int64_t, std::vector<int32_t>> grid_;
  int64_t key(int64_t x, int64_t y, int64_t z) const { return (x * 2097152 + y) * 2097152 + z; }
};

}  // namespace breccia::solver
