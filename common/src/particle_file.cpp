#include "breccia/common/particle_file.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iterator>
#include <sstream>
#include <stdexcept>

#include "breccia/common/error.hpp"
#include "breccia/common/h5.hpp"
#include "breccia/common/output_file.hpp"
#include "breccia/common/xdmf.hpp"

namespace breccia {

const ParticleSet* ParticleModel::find_set(const std::string& name) const {
  for (const auto& s : sets)
    if (s.name == name) return &s;
  return nullptr;
}

void require_indexable_particle_count(double count, const std::string& file, const std::string& field,
                                      const std::string& found) {
  if (count > kMostParticles)
    throw InputError(file, field, found, "at most 2^31 - 1 points (32-bit particle indices): a larger spacing");
}

std::optional<size_t> held_position(const std::vector<int64_t>& held, int64_t index) {
  const auto it = std::lower_bound(held.begin(), held.end(), index);
  if (it == held.end() || *it != index) return std::nullopt;
  return static_cast<size_t>(it - held.begin());
}

const int64_t* ParticleModel::cell_nodes(int64_t cell) const {
  size_t row = static_cast<size_t>(cell);
  if (!held_cells.empty()) {
    const std::optional<size_t> at = held_position(held_cells, cell);
    if (!at) throw std::out_of_range("particle model: mesh cell " + std::to_string(cell) + " is not held");
    row = *at;
  }
  if (nodes_per_cell <= 0 || (row + 1) * static_cast<size_t>(nodes_per_cell) > mesh_cells.size())
    throw std::out_of_range("particle model: no mesh cell " + std::to_string(cell));
  return &mesh_cells[row * static_cast<size_t>(nodes_per_cell)];
}

const double* ParticleModel::node_position(int64_t node) const {
  size_t row = static_cast<size_t>(node);
  if (!held_nodes.empty()) {
    const std::optional<size_t> at = held_position(held_nodes, node);
    if (!at) throw std::out_of_range("particle model: mesh node " + std::to_string(node) + " is not held");
    row = *at;
  }
  if (node < 0 || 3 * (row + 1) > mesh_nodes_m.size()) throw std::out_of_range("particle model: no mesh node " + std::to_string(node));
  return &mesh_nodes_m[3 * row];
}

const SurfaceFacets* ParticleModel::find_surface(const std::string& name) const {
  for (const auto& s : surfaces)
    if (s.name == name) return &s;
  return nullptr;
}

void ContentHash::add(const void* data, size_t bytes) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < bytes; ++i) {  // FNV-1a
    h_ ^= p[i];
    h_ *= 1099511628211ull;
  }
}

std::string ContentHash::hex() const {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h_));
  return buf;
}

std::string compute_content_id(const ParticleModel& model) {
  ContentHash h;
  h.add(model.position_m.data(), model.position_m.size() * sizeof(double));
  h.add(model.volume_m3.data(), model.volume_m3.size() * sizeof(double));
  return h.hex();
}

namespace {

std::string xdmf_sidecar(const std::string& h5_name, const ParticleModel& m) {
  const size_t n = m.size();
  auto hdf = [&](const char* dataset) { return h5_name + ":" + dataset; };
  std::ostringstream x;
  x << xdmf_document_begin() << "  <Grid Name=\"particles\" GridType=\"Uniform\">\n"
    << "   " << xdmf_polyvertex_topology(n) << "\n"
    << "   <Geometry GeometryType=\"XYZ\">\n"
    << "    " << xdmf_data_item(xdmf_dimensions(n, 3), false, 8, hdf("/particles/position")) << "\n   </Geometry>\n";
  auto attr = [&](const char* name, const char* path, bool integer, int prec) {
    x << "   " << xdmf_attribute_begin(name, "Scalar", "Node") << "\n"
      << "    " << xdmf_data_item(xdmf_dimensions(n), integer, prec, hdf(path)) << "\n   </Attribute>\n";
  };
  attr("volume", "/particles/volume", false, 8);
  attr("spacing", "/particles/spacing", false, 8);
  attr("material_id", "/particles/material_id", true, 4);
  x << "  </Grid>\n";
  if (m.nodes_per_cell > 0) {
    const char* topo = m.nodes_per_cell == 4 ? "Tetrahedron" : "Triangle";
    x << "  <Grid Name=\"mesh\" GridType=\"Uniform\">\n"
      << "   <Topology TopologyType=\"" << topo << "\" NumberOfElements=\"" << n << "\">\n"
      << "    " << xdmf_data_item(xdmf_dimensions(n, m.nodes_per_cell), true, 8, hdf("/mesh/cells")) << "\n"
      << "   </Topology>\n   <Geometry GeometryType=\"XYZ\">\n"
      << "    " << xdmf_data_item(xdmf_dimensions(m.mesh_nodes_m.size() / 3, 3), false, 8, hdf("/mesh/nodes"))
      << "\n   </Geometry>\n"
      << "   " << xdmf_attribute_begin("material_id", "Scalar", "Cell") << "\n"
      << "    " << xdmf_data_item(xdmf_dimensions(n), true, 4, hdf("/particles/material_id"))
      << "\n   </Attribute>\n  </Grid>\n";
  }
  x << xdmf_document_end();
  return x.str();
}

// Rows' volumes and material ids (row k is file row `file_row(k)`), as every reader checks them.
template <class FileRow>
void check_rows(const std::string& file, const std::vector<double>& volume, const std::vector<int32_t>& material_id,
                size_t material_names, FileRow&& file_row) {
  for (size_t k = 0; k < volume.size(); ++k) {
    // Built in two steps: GCC 12 warns falsely (-Wrestrict) on "[" + std::to_string(...).
    std::string row = std::to_string(file_row(k));
    row = '[' + row + ']';
    if (!(volume[k] > 0.0) || !std::isfinite(volume[k]))
      throw InputError(file, "/particles/volume" + row, "value " + std::to_string(volume[k]), "a positive finite volume");
    if (material_id[k] < 0 || static_cast<size_t>(material_id[k]) >= std::max<size_t>(material_names, 1))
      throw InputError(file, "/particles/material_id" + row, "value " + std::to_string(material_id[k]),
                       "an index into /materials/names");
  }
}

// The dimension and the count of n particles.
void check_dimension_and_count(const ParticleModel& m, size_t n, const std::string& file) {
  if (m.dimension != 2 && m.dimension != 3)
    throw InputError(file, "/@dimension", "value " + std::to_string(m.dimension), "2 or 3");
  if (n == 0) throw InputError(file, "/particles/volume", "no particles", "at least one particle");
}

// The surfaces' lists against n particles.
void check_surfaces(const ParticleModel& m, size_t n, const std::string& file) {
  for (const auto& s : m.surfaces) {
    const size_t f = s.size();
    if (s.normal.size() != 3 * f || s.centroid_m.size() != 3 * f || s.particle.size() != f)
      throw InputError(file, "/surfaces/" + s.name, "inconsistent dataset sizes", "area F, normal F x 3, centroid F x 3, particle F");
    const size_t per_facet = static_cast<size_t>(m.dimension);  // vertices of a facet: 3 or 2
    if (s.has_vertices() && s.vertices_m.size() != f * per_facet * 3)
      throw InputError(file, "/surfaces/" + s.name + "/vertices", "size " + std::to_string(s.vertices_m.size()),
                       std::to_string(f) + " x " + std::to_string(per_facet) + " x 3 (each facet's vertices)");
    for (auto p : s.particle)
      if (p < 0 || static_cast<size_t>(p) >= n)
        throw InputError(file, "/surfaces/" + s.name + "/particle", "index " + std::to_string(p), "a particle index");
  }
}

void check_set_index(const std::string& file, const std::string& set, int64_t idx, size_t n) {
  if (idx < 0 || static_cast<size_t>(idx) >= n)
    throw InputError(file, "/sets/" + set, "index " + std::to_string(idx), "0 <= index < " + std::to_string(n));
}

void validate(const ParticleModel& m, const std::string& file) {
  const size_t n = m.size();
  check_dimension_and_count(m, n, file);
  if (m.position_m.size() != 3 * n)
    throw InputError(file, "/particles/position", "size " + std::to_string(m.position_m.size()),
                     "3 x " + std::to_string(n) + " (one row per particle)");
  if (m.material_id.size() != n)
    throw InputError(file, "/particles/material_id", "size " + std::to_string(m.material_id.size()),
                     std::to_string(n));
  if (m.spacing_m.size() != n)
    throw InputError(file, "/particles/spacing", "size " + std::to_string(m.spacing_m.size()), std::to_string(n));
  check_rows(file, m.volume_m3, m.material_id, m.material_names.size(), [](size_t k) { return k; });
  for (const auto& s : m.sets)
    for (auto idx : s.indices) check_set_index(file, s.name, idx, n);
  check_surfaces(m, n, file);
}

}  // namespace

void write_particle_file(const std::string& path, ParticleModel m) {
  // The XDMF sidecar takes the file's name with .xdmf: a particle file named .xdmf was
  // overwritten by its own sidecar (exit 0, the particles gone); and the sidecar names the
  // file as file:/dataset, which a ':' in the name would split.
  const std::string name = std::filesystem::path(path).filename().string();
  if (std::filesystem::path(path).extension() == ".xdmf" || name.find(':') != std::string::npos)
    throw InputError(path, "", std::filesystem::path(path).extension() == ".xdmf" ? "a particle file named .xdmf"
                                                                                  : "a ':' in the file name",
                     "an HDF5 file name such as particles.h5 (its XDMF sidecar takes the same name with .xdmf)");
  if (m.spacing_m.empty()) {
    m.spacing_m.resize(m.size());
    for (size_t i = 0; i < m.size(); ++i)
      m.spacing_m[i] = m.dimension == 3 ? std::cbrt(m.volume_m3[i]) : std::sqrt(m.volume_m3[i] / m.thickness_m);
  }
  if (m.material_names.empty()) m.material_names.push_back("default");
  validate(m, path);
  m.content_id = compute_content_id(m);
  const size_t n = m.size();
  OutputFile out(path);
  {
    h5::File f(out.temp_path().string(), h5::File::Mode::Create);
    f.set_attr("/", "format", std::string("breccia-particles"));
    // 2: /surfaces/<name>/vertices added (version-1 files stay readable without it).
    f.set_attr("/", "format_version", 2LL);
    f.set_attr("/", "dimension", static_cast<long long>(m.dimension));
    f.set_attr("/", "thickness_m", m.thickness_m);
    f.set_attr("/", "units", std::string("SI (m, m3, kg, s)"));
    f.set_attr("/", "source", m.source);
    f.set_attr("/", "content_id", m.content_id);
    f.write("/particles/position", m.position_m, {n, 3});
    f.write("/particles/volume", m.volume_m3, {n});
    f.write("/particles/spacing", m.spacing_m, {n});
    f.write("/particles/material_id", m.material_id, {n});
    f.write_strings("/materials/names", m.material_names);
    f.create_group("/sets");
    for (const auto& s : m.sets) f.write("/sets/" + s.name, s.indices, {s.indices.size()});
    f.create_group("/surfaces");
    for (const auto& s : m.surfaces) {
      const std::string g = "/surfaces/" + s.name;
      f.write(g + "/area", s.area_m2, {s.size()});
      f.write(g + "/normal", s.normal, {s.size(), 3});
      f.write(g + "/centroid", s.centroid_m, {s.size(), 3});
      f.write(g + "/particle", s.particle, {s.size()});
      if (s.has_vertices())
        f.write(g + "/vertices", s.vertices_m, {s.size(), static_cast<hsize_t>(m.dimension), 3});
    }
    if (m.nodes_per_cell > 0) {
      f.write("/mesh/nodes", m.mesh_nodes_m, {m.mesh_nodes_m.size() / 3, 3});
      f.write("/mesh/cells", m.mesh_cells, {n, static_cast<hsize_t>(m.nodes_per_cell)});
      f.set_attr("/mesh", "nodes_per_cell", static_cast<long long>(m.nodes_per_cell));
    }
  }
  out.commit();
  const std::filesystem::path p(path);
  std::filesystem::path xdmf = p;
  xdmf.replace_extension(".xdmf");
  write_text_file(xdmf, xdmf_sidecar(p.filename().string(), m));
}

namespace {

// The file, checked to be a particle file (shared by the whole and the by-rows readers).
h5::File open_particle_file(const std::string& path) {
  if (!std::filesystem::exists(path))
    throw InputError(path, "", "file does not exist", "a particles.h5 written by breccia-place");
  h5::File f(path, h5::File::Mode::Read);
  if (!f.has_attr("/", "format") || f.attr_string("/", "format") != "breccia-particles")
    throw InputError(path, "/@format", "missing or not 'breccia-particles'", "a particles.h5 written by breccia-place");
  return f;
}

}  // namespace

ParticleRows read_particle_rows(const std::string& path, int64_t first, int64_t count) {
  h5::File f = open_particle_file(path);
  ParticleRows r;
  const std::vector<hsize_t> dims = f.dims("/particles/volume");
  r.total = dims.empty() ? 0 : static_cast<int64_t>(dims[0]);
  if (first < 0 || count < 0)
    throw InputError(path, "/particles", "rows from " + std::to_string(first) + ", " + std::to_string(count) + " of them",
                     "a range of rows >= 0");
  r.first = first;
  r.dimension = static_cast<int>(f.attr_int("/", "dimension"));
  r.content_id = f.attr_string("/", "content_id");
  const auto b = static_cast<hsize_t>(first), c = static_cast<hsize_t>(count);
  r.volume_m3 = f.read_double_rows("/particles/volume", b, c);
  r.position_m = f.read_double_rows("/particles/position", b, c);
  r.spacing_m = f.read_double_rows("/particles/spacing", b, c);
  r.material_id = f.read_int32_rows("/particles/material_id", b, c);
  r.material_names = f.read_strings("/materials/names");
  if (r.position_m.size() != 3 * r.size())
    throw InputError(path, "/particles/position", "not 3 numbers a row", "3 x N (one row per particle)");
  check_rows(path, r.volume_m3, r.material_id, r.material_names.size(), [first](size_t k) { return first + static_cast<int64_t>(k); });
  return r;
}

namespace {
// Every named surface's facets (area, normal, centroid, particle, vertices): the whole file's
// reader and the lists' reader alike (a surface is sized like the boundary, not the body).
void read_surfaces(h5::File& f, ParticleModel& m) {
  for (const auto& name : f.children("/surfaces")) {
    const std::string g = "/surfaces/" + name;
    SurfaceFacets s;
    s.name = name;
    s.area_m2 = f.read_doubles(g + "/area");
    s.normal = f.read_doubles(g + "/normal");
    s.centroid_m = f.read_doubles(g + "/centroid");
    s.particle = f.read_int64(g + "/particle");
    if (f.exists(g + "/vertices")) s.vertices_m = f.read_doubles(g + "/vertices");
    m.surfaces.push_back(std::move(s));
  }
}

}  // namespace

ParticleModel read_particle_lists(const std::string& path, int64_t& rows) {
  h5::File f = open_particle_file(path);
  ParticleModel m;
  m.dimension = static_cast<int>(f.attr_int("/", "dimension"));
  m.thickness_m = f.attr_double("/", "thickness_m");
  m.source = f.attr_string("/", "source");
  m.content_id = f.attr_string("/", "content_id");
  const std::vector<hsize_t> dims = f.dims("/particles/volume");
  rows = dims.empty() ? 0 : static_cast<int64_t>(dims[0]);
  m.material_names = f.read_strings("/materials/names");
  for (const auto& name : f.children("/sets")) {
    const std::vector<hsize_t> d = f.dims("/sets/" + name);
    m.sets.push_back({name, {}, d.empty() ? 0 : static_cast<int64_t>(d[0])});
  }
  read_surfaces(f, m);
  if (f.exists("/mesh/cells")) m.nodes_per_cell = static_cast<int>(f.attr_int("/mesh", "nodes_per_cell"));
  // The whole reader's checks that need no row (validate): the datasets' lengths, the lists.
  const size_t n = static_cast<size_t>(rows);
  auto rows_of = [&](const char* d) {
    const std::vector<hsize_t> dd = f.dims(d);
    size_t count = dd.empty() ? 0 : 1;
    for (const hsize_t x : dd) count *= static_cast<size_t>(x);
    return count;
  };
  if (const size_t got = rows_of("/particles/position"); got != 3 * n)
    throw InputError(path, "/particles/position", "size " + std::to_string(got), "3 x " + std::to_string(n) + " (one row per particle)");
  if (const size_t got = rows_of("/particles/material_id"); got != n)
    throw InputError(path, "/particles/material_id", "size " + std::to_string(got), std::to_string(n));
  if (const size_t got = rows_of("/particles/spacing"); got != n)
    throw InputError(path, "/particles/spacing", "size " + std::to_string(got), std::to_string(n));
  check_dimension_and_count(m, n, path);
  check_surfaces(m, n, path);
  return m;
}

void check_particle_rows(const ParticleModel& m, const std::string& path) {
  check_rows(path, m.volume_m3, m.material_id, m.material_names.size(), [&m](size_t k) { return m.file_row(k); });
}

namespace {

// Rows `wanted` (ascending) of a dataset of `width` values a row, in blocks of at most
// `block` consecutive rows from each wanted row.
template <class T, class Read>
std::vector<T> rows_at(const std::vector<int64_t>& wanted, size_t width, Read&& read) {
  constexpr int64_t block = 65536;
  std::vector<T> out;
  out.reserve(width * wanted.size());
  for (size_t q = 0; q < wanted.size();) {
    const int64_t first = wanted[q];
    size_t last = q;  // the wanted rows within [first, first + block)
    while (last < wanted.size() && wanted[last] < first + block) ++last;
    const int64_t count = wanted[last - 1] - first + 1;
    const std::vector<T> got = read(static_cast<hsize_t>(first), static_cast<hsize_t>(count));
    for (; q < last; ++q)
      out.insert(out.end(), got.begin() + static_cast<int64_t>(width) * (wanted[q] - first),
                 got.begin() + static_cast<int64_t>(width) * (wanted[q] - first + 1));
  }
  return out;
}

}  // namespace

void read_particle_rows_at(const std::string& path, const std::vector<int64_t>& rows, const std::vector<int64_t>& cells,
                           ParticleModel& m) {
  h5::File f = open_particle_file(path);
  for (size_t q = 1; q < rows.size(); ++q)
    if (rows[q] <= rows[q - 1]) throw std::invalid_argument("read_particle_rows_at: rows not ascending");
  auto doubles = [&](const char* d) {
    return [&f, d](hsize_t b, hsize_t c) { return f.read_double_rows(d, b, c); };
  };
  m.position_m = rows_at<double>(rows, 3, doubles("/particles/position"));
  m.volume_m3 = rows_at<double>(rows, 1, doubles("/particles/volume"));
  m.spacing_m = rows_at<double>(rows, 1, doubles("/particles/spacing"));
  m.material_id = rows_at<int32_t>(rows, 1, [&f](hsize_t b, hsize_t c) { return f.read_int32_rows("/particles/material_id", b, c); });
  m.held_rows = rows;
  constexpr int64_t block = 65536;
  const std::vector<hsize_t> dims = f.dims("/particles/volume");
  const size_t total = dims.empty() ? 0 : static_cast<size_t>(dims[0]);
  for (ParticleSet& set : m.sets) {  // (read_particle_lists': whole_count, no members yet)
    std::vector<int64_t> held;
    for (int64_t first = 0; first < set.whole_count; first += block) {
      const std::vector<int64_t> part = f.read_int64_rows("/sets/" + set.name, static_cast<hsize_t>(first),
                                                          static_cast<hsize_t>(std::min(block, set.whole_count - first)));
      for (const int64_t idx : part) check_set_index(path, set.name, idx, total);  // (every reader reads the whole list)
      std::set_intersection(part.begin(), part.end(), rows.begin(), rows.end(), std::back_inserter(held));
    }
    set.indices.swap(held);
  }
  if (m.nodes_per_cell > 0 && f.exists("/mesh/cells")) {
    m.mesh_cells = rows_at<int64_t>(cells, static_cast<size_t>(m.nodes_per_cell),
                                    [&f](hsize_t b, hsize_t c) { return f.read_int64_rows("/mesh/cells", b, c); });
    m.held_cells = cells;
    std::vector<int64_t> nodes(m.mesh_cells);
    std::sort(nodes.begin(), nodes.end());
    nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
    m.mesh_nodes_m = rows_at<double>(nodes, 3, [&f](hsize_t b, hsize_t c) { return f.read_double_rows("/mesh/nodes", b, c); });
    m.held_nodes = std::move(nodes);
  }
}

ParticleModel read_particle_file(const std::string& path) {
  h5::File f = open_particle_file(path);
  ParticleModel m;
  m.dimension = static_cast<int>(f.attr_int("/", "dimension"));
  m.thickness_m = f.attr_double("/", "thickness_m");
  m.source = f.attr_string("/", "source");
  m.content_id = f.attr_string("/", "content_id");
  m.position_m = f.read_doubles("/particles/position");
  m.volume_m3 = f.read_doubles("/particles/volume");
  m.spacing_m = f.read_doubles("/particles/spacing");
  m.material_id = f.read_int32("/particles/material_id");
  m.material_names = f.read_strings("/materials/names");
  for (const auto& name : f.children("/sets")) m.sets.push_back({name, f.read_int64("/sets/" + name)});
  read_surfaces(f, m);
  if (f.exists("/mesh/cells")) {
    m.nodes_per_cell = static_cast<int>(f.attr_int("/mesh", "nodes_per_cell"));
    m.mesh_nodes_m = f.read_doubles("/mesh/nodes");
    m.mesh_cells = f.read_int64("/mesh/cells");
  }
  validate(m, path);
  return m;
}

}  // namespace breccia
