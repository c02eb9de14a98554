#pragma once
// Plain-data meshes and their VTK XML writers (written through OutputFile: a reader never
// sees a half-written file). VTK types stay inside the .cpp.
#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace breccia::postproc {

struct Field {
  std::string name;
  int components = 1;
  std::vector<double> values;  // tuples * components
  bool integer = false;        // written as Int32
};

// One cell type throughout: VTK type id and nodes per cell (VTK_VERTEX 1/1, VTK_LINE 3/2,
// VTK_TRIANGLE 5/3, VTK_QUAD 9/4, VTK_TETRA 10/4, VTK_HEXAHEDRON 12/8).
struct Mesh {
  std::vector<double> points_m;   // 3P
  std::vector<int64_t> cells;     // C * nodes_per_cell
  int vtk_cell_type = 1;
  int nodes_per_cell = 1;
  std::vector<Field> point_data, cell_data;
  size_t cell_count() const { return nodes_per_cell ? cells.size() / nodes_per_cell : 0; }
};

void write_vtu(const std::filesystem::path& path, const Mesh& mesh);
// PolyData: lines (2 nodes) or polygons (3, 4 nodes).
void write_vtp(const std::filesystem::path& path, const Mesh& mesh);
// Isosurface (3D tets) or isoline (2D triangles) of a point field at `value`
// (vtkContourFilter on the unstructured grid), written as PolyData. Returns the number of
// output cells.
size_t write_contour_vtp(const std::filesystem::path& path, const Mesh& mesh,
                         const std::string& point_field, double value);
// ParaView collection: (time_s, file name relative to the .pvd).
void write_pvd(const std::filesystem::path& path, const std::vector<std::pair<double, std::string>>& entries);

}  // namespace breccia::postproc
