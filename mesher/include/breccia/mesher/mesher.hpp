#pragma once
// Meshing with gmsh (OpenCASCADE kernel): a parametric specimen, or an existing
// .geo/.step/.msh file, to a gmsh 4.1 .msh holding physical groups only. The output is
// written as OUT.msh.partial and renamed when complete.
#include <cstdio>
#include <string>
#include <vector>

#include "breccia/mesher/specimen.hpp"

namespace breccia::mesher {

struct MeshOptions {
  std::string output;              // OUT.msh
  double size_factor = 1.0;        // multiplies every element size of a spec
  double size_m = 0;               // for .geo/.step input: maximum element size (0 = gmsh default)
  int threads = 1;
  bool verbose = true;             // progress lines on stderr
};

struct GroupSummary {
  int dim = 0;
  std::string name;
  long long entities = 0;
  long long elements = 0;
};

struct MeshSummary {
  int dimension = 0;
  long long nodes = 0;
  long long elements = 0;          // top-dimension elements (tets / triangles)
  double min_element_size_m = 0;   // longest edge of the smallest element
  double max_element_size_m = 0;   // longest edge of the largest element
  double measure = 0;              // total volume (3D) or area (2D) of the elements, SI
  std::vector<GroupSummary> groups;
  double seconds = 0;
};

// Build the specimen's geometry, mesh it and write options.output.
MeshSummary mesh_specimen(const Specimen& spec, const MeshOptions& options);

// Read INPUT (.geo, .step/.stp, .msh); mesh it if it is geometry, validate it if it is a
// mesh; write options.output as msh 4.1. Throws InputError for unreadable or unsuitable input.
MeshSummary mesh_file(const std::string& input, const MeshOptions& options);

void print_summary(const MeshSummary& summary, std::FILE* out);

}  // namespace breccia::mesher
