#pragma once
// Reading a gmsh .msh file (format 2.2 or 4.1) into plain arrays, through the gmsh C++
// API. This is the only file of the geometry stage that talks to gmsh; everything after
// it (particles_from_mesh) works on the GmshMesh value and can be tested without files.
#include <cstddef>
#include <string>
#include <vector>

namespace breccia::geometry {

// All elements of one gmsh element type on one geometric entity, as gmsh returns them.
struct ElementBlock {
  int dim = 0;          // dimension of the entity (0 point, 1 curve, 2 surface, 3 volume)
  int entity = 0;       // entity tag
  int type = 0;         // gmsh element type (2 = 3-node triangle, 4 = 4-node tetrahedron, ...)
  std::string type_name;  // gmsh's name for the type ("Tetrahedron 4", "Prism 6", ...)
  int nodes_per_element = 0;
  std::vector<std::size_t> element_tags;  // E
  std::vector<std::size_t> node_tags;     // E * nodes_per_element, gmsh node order
  std::size_t size() const { return element_tags.size(); }
};

struct PhysicalGroup {
  int dim = 0;
  int tag = 0;
  std::string name;           // as in the file; may be empty (unnamed group)
  std::vector<int> entities;  // tags of the entities of dimension `dim` in the group
};

struct GmshMesh {
  std::string path;                     // the file it was read from (for messages)
  std::vector<std::size_t> node_tags;   // Nn
  std::vector<double> node_coords_m;    // 3 Nn, aligned with node_tags
  std::vector<ElementBlock> blocks;     // every element block of every entity
  std::vector<PhysicalGroup> groups;    // every physical group, sorted by (dim, tag)
};

// Throws InputError naming the file for an unreadable or non-.msh file, an unsupported
// format version, or any error gmsh reports while reading. Initialises gmsh if needed
// (a second gmsh::initialize is a no-op) and removes the model it opened before returning.
GmshMesh read_gmsh_mesh(const std::string& path);

}  // namespace breccia::geometry
