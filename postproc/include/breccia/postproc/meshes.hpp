#pragma once
// Meshes built for viewing: the source mesh with particle fields, the deformed mesh split
// into fragments, crack faces, damage interpolated to mesh nodes.
#include <span>
#include <vector>

#include "breccia/common/particle_file.hpp"
#include "breccia/postproc/cracks.hpp"
#include "breccia/postproc/vtk_output.hpp"

namespace breccia::postproc {

// Per-node value: volume-weighted mean of the values of the node's incident cells.
std::vector<double> cell_to_node_average(const ParticleModel& particles, std::span<const double> cell_value);

// The source mesh (reference coordinates), cells = particles, no fields yet.
Mesh source_mesh(const ParticleModel& particles);

// Deformed mesh split along fragment boundaries: a node shared by cells of k different
// components gets k copies; each copy moves by the weighted (volume) least-squares affine
// fit u(x) = u0 + F (x - x_node) of the displacements of its component's incident cells;
// when those do not determine an affine field (fewer than d + 1, or coplanar centroids),
// the stencil is widened to the cells around them, and failing that the weighted mean is used.
// Lattices (no mesh): one cube/square of side spacing per particle, translated rigidly.
Mesh deformed_mesh(const ParticleModel& particles, std::span<const double> displacement_m,
                   std::span<const int32_t> component);

// Crack faces as PolyData cells (reference positions), with cell fields state (1 fracture,
// 2 pre-crack), crack_id, area_m2.
Mesh crack_mesh(const CandidateFaces& faces, const CrackResult& cracks);

}  // namespace breccia::postproc
