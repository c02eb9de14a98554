#pragma once
// particles.h5: the contract between geometry/ (writer) and solver/ and postproc/
// (readers). Layout and units are documented in docs/formats.md; SI throughout.
// Particle i is the centroid of source-mesh cell i (when the model came from a mesh).
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace breccia {

struct ParticleSet {
  std::string name;
  std::vector<int64_t> indices;  // particle indices, sorted, unique
  // A model holding a part of the rows (ParticleModel::held_rows): indices are the held
  // members alone and this is the whole set's count. -1: indices is the whole set.
  int64_t whole_count = -1;
  bool empty_in_file() const { return whole_count >= 0 ? whole_count == 0 : indices.empty(); }
};

// Boundary facets of one named surface group (triangles in 3D, edges in 2D).
struct SurfaceFacets {
  std::string name;
  std::vector<double> area_m2;     // F; in 2D: edge length times thickness
  std::vector<double> normal;      // 3F, unit, outward from the body
  std::vector<double> centroid_m;  // 3F
  std::vector<int64_t> particle;   // F, the particle whose cell owns the facet
  // F x 3 x 3 (3D triangles) or F x 2 x 3 (2D edges): the facet's vertices in the source
  // mesh's node order. Empty when unknown: lattices (square facets) and files written
  // before format version 2 (readers then recover them from /mesh, see facet_vertices.hpp
  // in the solver, or fall back to a disc of the facet's area).
  std::vector<double> vertices_m;
  size_t size() const { return area_m2.size(); }
  bool has_vertices() const { return !vertices_m.empty(); }
};

// Particle indices are 32-bit (the bond lists' partners): a model of more particles cannot
// be indexed. A lattice that large is a unit slip in its spacing ("1 um" for "1 mm"): its
// writers (breccia-place --lattice, a case's specimen.lattice) refuse it by this rule
// (InputError naming `file` and `field`, the count in `found`) rather than as an
// allocation failure.
inline constexpr double kMostParticles = 2147483647.0;  // 2^31 - 1
void require_indexable_particle_count(double count, const std::string& file, const std::string& field,
                                      const std::string& found);

// The position of file index `index` in `held` (ascending file indices: a model's held rows,
// cells or nodes), or none where it is not held: the one lookup behind every held-row read.
std::optional<size_t> held_position(const std::vector<int64_t>& held, int64_t index);

struct ParticleModel {
  int dimension = 3;             // 2 or 3
  double thickness_m = 1.0;      // 2D only: out-of-plane thickness; volume = area * thickness
  std::vector<double> position_m;  // 3N (z = 0 in 2D)
  std::vector<double> volume_m3;   // N
  std::vector<double> spacing_m;   // N, local particle spacing (cube/square root of cell size)
  std::vector<int32_t> material_id;  // N, index into material_names
  std::vector<std::string> material_names;
  std::vector<ParticleSet> sets;
  std::vector<SurfaceFacets> surfaces;
  // Source mesh (empty for lattices): nodes 3*Nn, cells nodes_per_cell*N, 0-based.
  std::vector<double> mesh_nodes_m;
  std::vector<int64_t> mesh_cells;
  int nodes_per_cell = 0;  // 4 (tet), 3 (triangle), 0 (no mesh)
  std::string source;      // what the model was made from (mesh path or "lattice ...")
  std::string content_id;  // hash of positions and volumes; results files quote it
  // A part of the file's rows (a distributed run's window: the solver's plan_window_system):
  // when held_rows is not empty the per-particle arrays hold those file rows alone
  // (ascending), when held_cells is not empty mesh_cells holds those cells' rows alone
  // (ascending), and when held_nodes is not empty mesh_nodes_m holds those nodes alone
  // (ascending). The sets then hold their members among held_rows (ParticleSet::whole_count);
  // the surfaces stay whole. Empty: every row.
  std::vector<int64_t> held_rows;
  std::vector<int64_t> held_cells;
  std::vector<int64_t> held_nodes;

  size_t size() const { return volume_m3.size(); }
  // The file index of held row k (k itself when every row is held).
  int64_t file_row(size_t k) const { return held_rows.empty() ? static_cast<int64_t>(k) : held_rows[k]; }
  // The mesh nodes of cell `cell` (a file index): nodes_per_cell of them. Throws
  // std::out_of_range for a cell not held.
  const int64_t* cell_nodes(int64_t cell) const;
  // The position of mesh node `node` (3 values). Throws std::out_of_range for a node not held.
  const double* node_position(int64_t node) const;
  const ParticleSet* find_set(const std::string& name) const;
  const SurfaceFacets* find_surface(const std::string& name) const;
};

// Stable 64-bit hash of positions and volumes, as hex: the provenance key.
std::string compute_content_id(const ParticleModel& model);
// That hash fed in parts, in its order (every position, then every volume): a model made in
// pieces (a distributed run's lattice) takes the whole model's id without holding it.
class ContentHash {
public:
  void add(const void* data, size_t bytes);
  std::string hex() const;

private:
  uint64_t h_ = 1469598103934665603ull;  // FNV-1a's offset basis
};

// Write particles.h5 (atomically) and its ParaView sidecar particles.xdmf next to it.
void write_particle_file(const std::string& path, ParticleModel model);

// Read and validate; throws InputError naming the file and the dataset on any defect.
ParticleModel read_particle_file(const std::string& path);

// A distributed run's ranks (the solver's setup_system): the file's attributes, material
// names and surfaces, none of its per-particle rows or mesh (nodes_per_cell set), its sets by
// name and whole count alone (no members yet: read_particle_rows_at). `rows`: the file's
// particle count. Checked as read_particle_file checks what needs no row (the datasets'
// lengths, the surfaces); check_particle_rows and read_particle_rows_at check the rest.
ParticleModel read_particle_lists(const std::string& path, int64_t& rows);
// The held rows' volumes and material ids, as read_particle_file checks them (InputError
// naming the file row).
void check_particle_rows(const ParticleModel& m, const std::string& path);
// The per-particle datasets' rows `rows` (ascending, unique) into m (its per-particle arrays,
// in that order; held_rows = rows), each of m's sets' members among them (read_particle_lists'
// sets), and, when m has a mesh (nodes_per_cell > 0), /mesh/cells' rows `cells` (ascending,
// unique; held_cells) and the nodes those cells name (held_nodes). The sets' indices are
// checked as a whole read checks them (every one is read); the rows are not
// (check_particle_rows: a distributed set-up checks each rank's block of them).
// Read through hyperslabs of at most 65,536 consecutive rows from each wanted row (a set's
// list in blocks of 65,536 entries), so memory holds the rows asked for and one block, never
// a whole dataset.
void read_particle_rows_at(const std::string& path, const std::vector<int64_t>& rows, const std::vector<int64_t>& cells,
                           ParticleModel& m);

// Particles [first, first + count) of a particles.h5, in the file's order: what one process
// of a distributed run reads of the per-particle datasets (hyperslabs), never the whole.
// Sets, surfaces and the mesh are not read (lists, not per-particle rows).
struct ParticleRows {
  int64_t first = 0;               // the file index of the first row
  int64_t total = 0;               // particles in the whole file
  int dimension = 3;
  std::vector<double> position_m;  // 3 x count
  std::vector<double> volume_m3;   // count
  std::vector<double> spacing_m;   // count
  std::vector<int32_t> material_id;  // count, index into material_names
  std::vector<std::string> material_names;
  std::string content_id;          // of the whole file
  size_t size() const { return volume_m3.size(); }
};
// Checks the rows as read_particle_file checks them; throws InputError naming the file and
// the dataset (rows past the end included).
ParticleRows read_particle_rows(const std::string& path, int64_t first, int64_t count);

}  // namespace breccia
