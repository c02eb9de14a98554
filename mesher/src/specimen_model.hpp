#pragma once
// Turns a Specimen into a gmsh OpenCASCADE model with named physical groups, and sets
// the mesh-size fields. Needs an open GmshSession.
#include <map>
#include <string>
#include <vector>

#include "breccia/mesher/specimen.hpp"

namespace breccia::mesher {

struct PhysicalGroup {
  int dim = 0;
  std::vector<int> tags;
};
using GroupMap = std::map<std::string, PhysicalGroup>;

// Build the geometry (booleans in OCC), recognise each feature's entities geometrically,
// and add one physical group per name. Throws InputError if a named group ends up empty.
GroupMap build_specimen_model(const Specimen& spec);

// Size field: mesh.size everywhere, finer near each refine entry (Distance + Threshold
// fields combined with Min). All sizes are multiplied by size_factor.
void apply_size_fields(const Specimen& spec, const GroupMap& groups, double size_factor);

}  // namespace breccia::mesher
