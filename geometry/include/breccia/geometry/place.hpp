#pragma once
// Mesh -> particles: one particle per cell (tetrahedron in 3D, triangle in 2D), at the
// cell centroid, carrying the exact cell volume (2D: area x thickness). Physical volume
// groups give materials and particle sets; physical surface groups (2D: curve groups)
// give boundary facets and the sets of particles that own them. See docs/formats.md.
#include <optional>
#include <string>
#include <vector>

#include "breccia/common/particle_file.hpp"
#include "breccia/geometry/gmsh_mesh.hpp"

namespace breccia::geometry {

struct PlaceOptions {
  // Out-of-plane thickness for 2D meshes [m]. Required for a 2D mesh (a silent 1 m would
  // make every particle mass wrong by the plate thickness); ignored for a 3D mesh.
  std::optional<double> thickness_m;
  // Physical groups of the mesh dimension that define materials. Empty: every such group.
  // Needed when volume groups overlap (e.g. "all" plus "concrete"): a cell may have only
  // one material.
  std::vector<std::string> volume_groups;
  // Physical groups that must exist and map to at least one particle.
  std::vector<std::string> required_groups;
  // Progress lines (stage, count, rate) on stderr.
  bool progress = false;
};

// Build the particle model of a mesh. Throws InputError naming the file and the entity
// (element tag, group name) for: inverted or zero-volume cells, element types other than
// linear tetrahedra (3D) / triangles (2D), no cells at all, a 2D mesh without thickness,
// overlapping material groups, surface facets that are not faces of any cell, and
// missing or empty required groups.
ParticleModel particles_from_mesh(const GmshMesh& mesh, const PlaceOptions& options);

// read_gmsh_mesh + particles_from_mesh.
ParticleModel place_particles(const std::string& msh_path, const PlaceOptions& options);

}  // namespace breccia::geometry
