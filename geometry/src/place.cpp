#include "breccia/geometry/place.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <unordered_map>

#include "breccia/common/error.hpp"
#include "breccia/common/progress.hpp"
#include "breccia/common/units.hpp"
#include "predicates.hpp"

namespace breccia::geometry {
namespace {

constexpr int kGmshLine2 = 1;
constexpr int kGmshTriangle3 = 2;
constexpr int kGmshTetrahedron4 = 4;
constexpr long long kProgressEvery = 1 << 16;

const char* dim_word(int dim) {
  static const char* words[] = {"point", "curve", "surface", "volume"};
  return (dim >= 0 && dim <= 3) ? words[dim] : "entity";
}

// The name a group gets as a particle set / surface: its physical name, or
// "<kind>_<tag>" for an unnamed group.
std::string group_label(const PhysicalGroup& g) {
  return g.name.empty() ? std::string(dim_word(g.dim)) + "_" + std::to_string(g.tag) : g.name;
}

std::string list_labels(const std::vector<PhysicalGroup>& groups) {
  std::string s;
  for (const auto& g : groups) s += (s.empty() ? "" : ", ") + group_label(g) + " (" + dim_word(g.dim) + ")";
  return s.empty() ? "none" : s;
}

// The cells of the mesh, renumbered: nodes compact and 0-based in gmsh tag order.
struct Cells {
  int dim = 3;
  int nodes_per_cell = 4;
  std::vector<double> nodes_m;          // 3 Nn
  std::vector<int64_t> cell_nodes;      // npc N
  std::vector<std::size_t> element_tag; // N
  std::vector<int> entity;              // N
  std::vector<int64_t> index_of_tag;    // gmsh node tag -> compact index, -1 if unused
  size_t size() const { return element_tag.size(); }
  const double* node(int64_t i) const { return &nodes_m[3 * i]; }
  int64_t compact(std::size_t tag) const {
    return tag < index_of_tag.size() ? index_of_tag[tag] : -1;
  }
};

int mesh_dimension(const GmshMesh& mesh) {
  int top = -1;
  for (const auto& b : mesh.blocks)
    if (b.size() > 0) top = std::max(top, b.dim);
  if (top == 3) return 3;
  if (top < 2)
    throw InputError(mesh.path, "elements",
                     top < 0 ? "the mesh has no elements" : "the mesh has only point/line elements",
                     "volume elements: 4-node tetrahedra (3D) or 3-node triangles in the plane z = 0 (2D)");
  // Only surface elements: a 2D model if it lies in z = 0, else a 3D surface mesh whose
  // volume was never meshed.
  double extent = 0, max_abs_z = 0;
  for (size_t i = 0; i < mesh.node_coords_m.size(); i += 3) {
    for (int k = 0; k < 3; ++k) extent = std::max(extent, std::abs(mesh.node_coords_m[i + k]));
    max_abs_z = std::max(max_abs_z, std::abs(mesh.node_coords_m[i + 2]));
  }
  if (max_abs_z > 1e-9 * std::max(extent, 1e-300))  // round-off of a planar mesher
    throw InputError(mesh.path, "elements",
                     "no volume elements (only surface elements, not all in the plane z = 0; max |z| = " +
                         short_number(max_abs_z) + " m)",
                     "4-node tetrahedra (mesh the volume, e.g. gmsh -3, and put it in a Physical Volume: "
                     "gmsh saves only elements of physical groups) or a 2D mesh in z = 0");
  return 2;
}

void check_cell_types(const GmshMesh& mesh, int dim) {
  const int wanted = dim == 3 ? kGmshTetrahedron4 : kGmshTriangle3;
  std::map<std::string, size_t> found;
  bool other = false;
  for (const auto& b : mesh.blocks) {
    if (b.dim != dim || b.size() == 0) continue;
    found[b.type_name] += b.size();
    other |= b.type != wanted;
  }
  if (!other) return;
  std::string list;
  for (const auto& [name, count] : found) list += (list.empty() ? "" : ", ") + std::to_string(count) + " x " + name;
  throw InputError(mesh.path, std::string(dim_word(dim)) + " elements",
                   "mixed or unsupported element types: " + list,
                   dim == 3 ? "only linear tetrahedra (gmsh type 4, 'Tetrahedron 4')"
                            : "only linear triangles (gmsh type 2, 'Triangle 3')");
}

Cells collect_cells(const GmshMesh& mesh, int dim) {
  Cells cells;
  cells.dim = dim;
  cells.nodes_per_cell = dim == 3 ? 4 : 3;
  size_t n = 0;
  for (const auto& b : mesh.blocks)
    if (b.dim == dim) n += b.size();
  cells.element_tag.reserve(n);
  cells.entity.reserve(n);
  cells.cell_nodes.reserve(n * cells.nodes_per_cell);

  std::size_t max_tag = 0;
  for (auto t : mesh.node_tags) max_tag = std::max(max_tag, t);
  std::vector<int64_t> coord_of_tag(max_tag + 1, -1);
  for (size_t i = 0; i < mesh.node_tags.size(); ++i) coord_of_tag[mesh.node_tags[i]] = static_cast<int64_t>(i);

  std::vector<char> used(max_tag + 1, 0);
  for (const auto& b : mesh.blocks) {
    if (b.dim != dim) continue;
    for (size_t e = 0; e < b.size(); ++e) {
      for (int k = 0; k < cells.nodes_per_cell; ++k) {
        const std::size_t tag = b.node_tags[e * cells.nodes_per_cell + k];
        if (tag > max_tag || coord_of_tag[tag] < 0)
          throw InputError(mesh.path, "element " + std::to_string(b.element_tags[e]),
                           "refers to node " + std::to_string(tag) + ", which is not in $Nodes",
                           "every element node defined in the file");
        used[tag] = 1;
      }
      cells.element_tag.push_back(b.element_tags[e]);
      cells.entity.push_back(b.entity);
    }
  }
  cells.index_of_tag.assign(max_tag + 1, -1);
  int64_t next = 0;
  for (std::size_t tag = 0; tag <= max_tag; ++tag) {
    if (!used[tag]) continue;
    cells.index_of_tag[tag] = next++;
    const double* x = &mesh.node_coords_m[3 * coord_of_tag[tag]];
    cells.nodes_m.insert(cells.nodes_m.end(), x, x + 3);
  }
  if (dim == 2)
    for (size_t i = 2; i < cells.nodes_m.size(); i += 3) cells.nodes_m[i] = 0.0;
  for (const auto& b : mesh.blocks)
    if (b.dim == dim)
      for (auto tag : b.node_tags) cells.cell_nodes.push_back(cells.index_of_tag[tag]);
  return cells;
}

// Centroid, exact volume (2D: area x thickness) and spacing of every cell; rejects
// inverted and flat cells with the exact orientation predicate (a floating-point
// determinant can have the wrong sign for a nearly flat cell).
void measure_cells(const Cells& cells, const std::string& path, double thickness_m,
                   ParticleModel& model, std::FILE* log) {
  const size_t n = cells.size();
  const int npc = cells.nodes_per_cell;
  model.position_m.resize(3 * n);
  model.volume_m3.resize(n);
  model.spacing_m.resize(n);
  Progress progress("cells", static_cast<long long>(n), 2.0, log ? log : stderr);
  for (size_t c = 0; c < n; ++c) {
    const int64_t* v = &cells.cell_nodes[npc * c];
    const double* a = cells.node(v[0]);
    const double* b = cells.node(v[1]);
    const double* p = cells.node(v[2]);
    double measure = 0;  // signed volume (3D) or signed area (2D)
    int orientation = 0;
    if (npc == 4) {
      const double* d = cells.node(v[3]);
      const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
      const double w[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]};
      const double z[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
      measure = (u[0] * (w[1] * z[2] - w[2] * z[1]) - u[1] * (w[0] * z[2] - w[2] * z[0]) +
                 u[2] * (w[0] * z[1] - w[1] * z[0])) / 6.0;
      orientation = detail::tetrahedron_orientation(a, b, p, d);
      for (int k = 0; k < 3; ++k) model.position_m[3 * c + k] = 0.25 * (a[k] + b[k] + p[k] + d[k]);
    } else {
      measure = 0.5 * ((b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]));
      orientation = detail::triangle_orientation_xy(a, b, p);
      // A 2D model's triangles may be wound either way (it depends on the surface
      // normal the CAD chose); only a flat triangle is a defect.
      if (orientation != 0) orientation = 1;
      measure = std::abs(measure);
      for (int k = 0; k < 3; ++k) model.position_m[3 * c + k] = (a[k] + b[k] + p[k]) / 3.0;
    }
    if (orientation <= 0) {
      const char* what = npc == 4 ? (orientation < 0 ? "inverted tetrahedron" : "zero-volume (flat) tetrahedron")
                                  : "zero-area (degenerate) triangle";
      throw InputError(path, "element " + std::to_string(cells.element_tag[c]) + " (" + dim_word(cells.dim) +
                                 " entity " + std::to_string(cells.entity[c]) + ")",
                       std::string(what) + ", signed " + (npc == 4 ? "volume " : "area ") + short_number(measure) +
                           (npc == 4 ? " m^3" : " m^2"),
                       npc == 4 ? "positively oriented tetrahedra with nonzero volume"
                                : "triangles with nonzero area");
    }
    if (npc == 4) {
      model.volume_m3[c] = measure;
      model.spacing_m[c] = std::cbrt(measure);
    } else {
      model.volume_m3[c] = measure * thickness_m;
      model.spacing_m[c] = std::sqrt(measure);
    }
    if (log && c % kProgressEvery == 0) progress.update(static_cast<long long>(c));
  }
  if (log) progress.finish();
}

void assign_materials(const GmshMesh& mesh, const Cells& cells, const PlaceOptions& options,
                      ParticleModel& model, std::FILE* log) {
  std::vector<const PhysicalGroup*> material_groups;
  for (const auto& g : mesh.groups)
    if (g.dim == cells.dim && (options.volume_groups.empty() ||
                               std::count(options.volume_groups.begin(), options.volume_groups.end(), group_label(g))))
      material_groups.push_back(&g);
  for (const auto& wanted : options.volume_groups)
    if (std::none_of(material_groups.begin(), material_groups.end(),
                     [&](const PhysicalGroup* g) { return group_label(*g) == wanted; }))
      throw InputError(mesh.path, "--volume-groups", "'" + wanted + "' is not a physical " + dim_word(cells.dim) +
                                                         " group of the mesh (groups: " + list_labels(mesh.groups) + ")",
                       std::string("names of physical ") + dim_word(cells.dim) + " groups");

  std::map<int, int> material_of_entity;
  for (size_t m = 0; m < material_groups.size(); ++m) {
    model.material_names.push_back(group_label(*material_groups[m]));
    for (int e : material_groups[m]->entities) {
      auto [it, inserted] = material_of_entity.emplace(e, static_cast<int>(m));
      if (!inserted)
        throw InputError(mesh.path, std::string(dim_word(cells.dim)) + " entity " + std::to_string(e),
                         "belongs to two material groups, '" + model.material_names[it->second] + "' and '" +
                             model.material_names[m] + "'",
                         "each cell in exactly one material group (choose them with --volume-groups)");
    }
  }
  int default_id = -1;
  size_t unassigned = 0;
  model.material_id.resize(cells.size());
  for (size_t c = 0; c < cells.size(); ++c) {
    const auto it = material_of_entity.find(cells.entity[c]);
    if (it != material_of_entity.end()) {
      model.material_id[c] = it->second;
      continue;
    }
    if (default_id < 0) {
      default_id = static_cast<int>(model.material_names.size());
      model.material_names.push_back("default");
    }
    model.material_id[c] = default_id;
    ++unassigned;
  }
  if (log && unassigned > 0 && !material_groups.empty())
    std::fprintf(log, "warning: %zu cells are in no material group; they get material 'default'\n", unassigned);
}

// A cell face, as its sorted compact node indices (third = -1 for a 2D edge).
using FaceKey = std::array<int64_t, 3>;
struct FaceKeyHash {
  size_t operator()(const FaceKey& k) const {
    uint64_t h = 1469598103934665603ull;
    for (int64_t v : k) h = (h ^ static_cast<uint64_t>(v)) * 1099511628211ull;
    return static_cast<size_t>(h ^ (h >> 29));
  }
};

FaceKey make_key(const int64_t* nodes, int count) {
  int64_t a = nodes[0], b = nodes[1], c = count == 3 ? nodes[2] : -1;
  if (a > b) std::swap(a, b);
  if (count == 3) {
    if (b > c) std::swap(b, c);
    if (a > b) std::swap(a, b);
  }
  return {a, b, c};
}

struct FaceCells {
  int count = 0;
  int64_t cell[2] = {-1, -1};
  int64_t opposite_node[2] = {-1, -1};  // the cell's vertex not on the face
};

struct FacetRef {
  size_t surface;               // index into model.surfaces
  std::size_t element_tag;
  std::array<int64_t, 3> nodes; // compact, gmsh order (third unused in 2D)
  size_t face;                  // index into the FaceCells table
};

void build_surfaces(const GmshMesh& mesh, const Cells& cells, double thickness_m,
                    ParticleModel& model, std::FILE* log) {
  const int facet_dim = cells.dim - 1;
  const int facet_nodes = cells.dim;  // 3 (triangle) or 2 (edge)
  const int facet_type = cells.dim == 3 ? kGmshTriangle3 : kGmshLine2;
  std::unordered_map<FaceKey, size_t, FaceKeyHash> face_index;
  std::vector<FaceCells> faces;
  std::vector<FacetRef> refs;

  for (const auto& g : mesh.groups) {
    if (g.dim != facet_dim) continue;
    const size_t surface = model.surfaces.size();
    model.surfaces.emplace_back();
    model.surfaces.back().name = group_label(g);
    for (const auto& b : mesh.blocks) {
      if (b.dim != facet_dim || std::find(g.entities.begin(), g.entities.end(), b.entity) == g.entities.end())
        continue;
      if (b.type != facet_type)
        throw InputError(mesh.path, "physical group '" + group_label(g) + "', " + dim_word(b.dim) + " entity " +
                                        std::to_string(b.entity),
                         std::to_string(b.size()) + " x " + b.type_name + " elements",
                         cells.dim == 3 ? "3-node triangles on a tetrahedral mesh" : "2-node lines on a triangle mesh");
      for (size_t e = 0; e < b.size(); ++e) {
        FacetRef ref{surface, b.element_tags[e], {-1, -1, -1}, 0};
        for (int k = 0; k < facet_nodes; ++k) {
          ref.nodes[k] = cells.compact(b.node_tags[e * facet_nodes + k]);
          if (ref.nodes[k] < 0)
            throw InputError(mesh.path, "physical group '" + group_label(g) + "', element " + std::to_string(ref.element_tag),
                             "has a node that belongs to no " + std::string(dim_word(cells.dim)) + " element",
                             "surface facets that are faces of the volume mesh (a conforming mesh)");
        }
        auto [it, inserted] = face_index.emplace(make_key(ref.nodes.data(), facet_nodes), faces.size());
        if (inserted) faces.emplace_back();
        ref.face = it->second;
        refs.push_back(ref);
      }
    }
  }
  if (refs.empty()) return;

  // One pass over the cells finds, for every surface facet, the one or two cells it bounds.
  const int npc = cells.nodes_per_cell;
  Progress progress("facets", static_cast<long long>(cells.size()), 2.0, log ? log : stderr);
  for (size_t c = 0; c < cells.size(); ++c) {
    const int64_t* v = &cells.cell_nodes[npc * c];
    for (int opposite = 0; opposite < npc; ++opposite) {
      int64_t face_nodes[3];
      int k = 0;
      for (int j = 0; j < npc; ++j)
        if (j != opposite) face_nodes[k++] = v[j];
      const auto it = face_index.find(make_key(face_nodes, facet_nodes));
      if (it == face_index.end()) continue;
      FaceCells& f = faces[it->second];
      if (f.count < 2) {
        f.cell[f.count] = static_cast<int64_t>(c);
        f.opposite_node[f.count] = v[opposite];
      }
      ++f.count;
    }
    if (log && c % kProgressEvery == 0) progress.update(static_cast<long long>(c));
  }
  if (log) progress.finish(std::to_string(refs.size()) + " facets");

  for (const auto& ref : refs) {
    SurfaceFacets& s = model.surfaces[ref.surface];
    const FaceCells& f = faces[ref.face];
    const std::string where = "physical group '" + s.name + "', element " + std::to_string(ref.element_tag);
    if (f.count == 0)
      throw InputError(mesh.path, where, "is not a face of any " + std::string(cells.dim == 3 ? "tetrahedron" : "triangle"),
                       "surface facets that are faces of the volume mesh (a conforming mesh)");
    if (f.count > 2)
      throw InputError(mesh.path, where, "is shared by " + std::to_string(f.count) + " cells (non-manifold mesh)",
                       "at most two cells per face");
    const double* a = cells.node(ref.nodes[0]);
    const double* b = cells.node(ref.nodes[1]);
    double normal[3], measure, centroid[3];
    if (cells.dim == 3) {
      const double* p = cells.node(ref.nodes[2]);
      const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
      const double w[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]};
      normal[0] = u[1] * w[2] - u[2] * w[1];
      normal[1] = u[2] * w[0] - u[0] * w[2];
      normal[2] = u[0] * w[1] - u[1] * w[0];
      const double twice_area = std::sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]);
      measure = 0.5 * twice_area;
      for (int k = 0; k < 3; ++k) {
        normal[k] /= twice_area;
        centroid[k] = (a[k] + b[k] + p[k]) / 3.0;
      }
    } else {
      // The right-hand normal of the gmsh edge direction a -> b.
      const double length = std::hypot(b[0] - a[0], b[1] - a[1]);
      normal[0] = (b[1] - a[1]) / length;
      normal[1] = -(b[0] - a[0]) / length;
      normal[2] = 0.0;
      measure = length * thickness_m;
      for (int k = 0; k < 3; ++k) centroid[k] = 0.5 * (a[k] + b[k]);
    }
    // side[i] > 0: cell i lies on the side the (gmsh-oriented) normal points to.
    double side[2] = {0, 0};
    for (int i = 0; i < std::min(f.count, 2); ++i) {
      const double* q = cells.node(f.opposite_node[i]);
      for (int k = 0; k < 3; ++k) side[i] += normal[k] * (q[k] - a[k]);
    }
    int owner = 0;
    if (f.count == 2) {
      // Embedded surface (pre-crack): keep gmsh's orientation; the owner is the cell
      // behind the facet, so the normal points away from it, into the other cell.
      owner = side[0] < side[1] ? 0 : 1;
    }
    const bool flip = side[owner] > 0;  // the normal must point away from the owner
    for (int k = 0; k < 3; ++k) {
      s.normal.push_back(flip ? -normal[k] : normal[k]);
      s.centroid_m.push_back(centroid[k]);
    }
    s.area_m2.push_back(measure);
    s.particle.push_back(f.cell[owner]);
    // The facet's own vertices (gmsh order): the solver cuts bonds against these triangles
    // and measures distances to them; nothing else in the file gives a facet's shape.
    for (int v = 0; v < facet_nodes; ++v) {
      const double* x = cells.node(ref.nodes[v]);
      s.vertices_m.insert(s.vertices_m.end(), x, x + 3);
    }
  }
}

std::vector<int64_t> sorted_unique(std::vector<int64_t> v) {
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
  return v;
}

// Every physical group becomes a set of the same name: cells of a volume group, owners of
// a surface group's facets, and for lower-dimensional groups (points, curves in 3D) the
// cells that touch one of the group's nodes.
void build_sets(const GmshMesh& mesh, const Cells& cells, ParticleModel& model, std::FILE* log) {
  for (const auto& g : mesh.groups) {
    ParticleSet set{group_label(g), {}};
    const auto in_group = [&](int entity) {
      return std::find(g.entities.begin(), g.entities.end(), entity) != g.entities.end();
    };
    if (g.dim == cells.dim) {
      for (size_t c = 0; c < cells.size(); ++c)
        if (in_group(cells.entity[c])) set.indices.push_back(static_cast<int64_t>(c));
    } else if (g.dim == cells.dim - 1) {
      const SurfaceFacets* s = model.find_surface(set.name);
      if (s) set.indices = sorted_unique(s->particle);
    } else {
      std::vector<char> marked(cells.nodes_m.size() / 3, 0);
      for (const auto& b : mesh.blocks)
        if (b.dim == g.dim && in_group(b.entity))
          for (auto tag : b.node_tags)
            if (const int64_t i = cells.compact(tag); i >= 0) marked[i] = 1;
      const int npc = cells.nodes_per_cell;
      for (size_t c = 0; c < cells.size(); ++c)
        for (int k = 0; k < npc; ++k)
          if (marked[cells.cell_nodes[npc * c + k]]) {
            set.indices.push_back(static_cast<int64_t>(c));
            break;
          }
    }
    if (set.indices.empty()) {
      if (log) std::fprintf(log, "warning: physical group '%s' maps to no particles; no set written\n", set.name.c_str());
      continue;
    }
    model.sets.push_back(std::move(set));
  }
  // A surface with no facets is left out as well (its set is already left out above).
  std::erase_if(model.surfaces, [](const SurfaceFacets& s) { return s.size() == 0; });
}

void check_group_names(const GmshMesh& mesh) {
  std::map<std::string, const PhysicalGroup*> seen;
  for (const auto& g : mesh.groups) {
    const std::string label = group_label(g);
    if (label.find('/') != std::string::npos)
      throw InputError(mesh.path, "physical group '" + label + "'", "name contains '/'",
                       "names without '/' (they become HDF5 dataset names)");
    auto [it, inserted] = seen.emplace(label, &g);
    if (!inserted)
      throw InputError(mesh.path, "physical group '" + label + "'",
                       std::string("used for a ") + dim_word(it->second->dim) + " group and a " + dim_word(g.dim) + " group",
                       "unique physical group names (each becomes a particle set)");
  }
}

void check_required(const GmshMesh& mesh, const PlaceOptions& options, const ParticleModel& model) {
  for (const auto& name : options.required_groups) {
    const bool exists = std::any_of(mesh.groups.begin(), mesh.groups.end(),
                                    [&](const PhysicalGroup& g) { return group_label(g) == name; });
    if (!exists)
      throw InputError(mesh.path, "physical group '" + name + "'",
                       "missing (the mesh has: " + list_labels(mesh.groups) + ")",
                       "a non-empty physical group of that name (--require-groups)");
    if (!model.find_set(name))
      throw InputError(mesh.path, "physical group '" + name + "'", "is empty (it maps to no particles)",
                       "a non-empty physical group of that name (--require-groups)");
  }
}

}  // namespace

ParticleModel particles_from_mesh(const GmshMesh& mesh, const PlaceOptions& options) {
  std::FILE* log = options.progress ? stderr : nullptr;
  const int dim = mesh_dimension(mesh);
  check_cell_types(mesh, dim);
  check_group_names(mesh);
  double thickness_m = 1.0;
  if (dim == 2) {
    if (!options.thickness_m)
      throw InputError(mesh.path, "--thickness", "a 2D (triangle) mesh and no thickness given",
                       "--thickness T for a 2D mesh: particle volume = triangle area x T");
    thickness_m = *options.thickness_m;
    if (!(thickness_m > 0) || !std::isfinite(thickness_m))
      throw InputError(mesh.path, "--thickness", "value " + short_number(thickness_m), "a positive length in metres");
  } else if (options.thickness_m && log) {
    std::fprintf(log, "warning: --thickness is ignored for a 3D mesh\n");
  }

  ParticleModel model;
  model.dimension = dim;
  model.thickness_m = thickness_m;
  model.source = mesh.path;
  const Cells cells = collect_cells(mesh, dim);
  measure_cells(cells, mesh.path, thickness_m, model, log);
  assign_materials(mesh, cells, options, model, log);
  build_surfaces(mesh, cells, thickness_m, model, log);
  build_sets(mesh, cells, model, log);
  check_required(mesh, options, model);
  model.nodes_per_cell = cells.nodes_per_cell;
  model.mesh_nodes_m = cells.nodes_m;
  model.mesh_cells = cells.cell_nodes;
  return model;
}

ParticleModel place_particles(const std::string& msh_path, const PlaceOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const GmshMesh mesh = read_gmsh_mesh(msh_path);
  if (options.progress) {
    size_t elements = 0;
    for (const auto& b : mesh.blocks) elements += b.size();
    std::fprintf(stderr, "[read mesh] %zu nodes, %zu elements, %zu physical groups in %.2f s\n",
                 mesh.node_tags.size(), elements, mesh.groups.size(),
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  return particles_from_mesh(mesh, options);
}

}  // namespace breccia::geometry
