#include "breccia/mesher/mesher.hpp"

#include <gmsh.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>

#include "breccia/common/error.hpp"
#include "breccia/common/output_file.hpp"
#include "gmsh_session.hpp"
#include "specimen_geometry.hpp"
#include "specimen_model.hpp"

namespace breccia::mesher {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

long long count_nodes() {
  std::vector<std::size_t> tags;
  std::vector<double> coords, params;
  gmsh::model::mesh::getNodes(tags, coords, params, -1, -1, false, false);
  return static_cast<long long>(tags.size());
}

long long count_elements(int dim, int tag = -1) {
  std::vector<int> types;
  std::vector<std::vector<std::size_t>> elements, nodes;
  gmsh::model::mesh::getElements(types, elements, nodes, dim, tag);
  long long n = 0;
  for (const auto& e : elements) n += static_cast<long long>(e.size());
  return n;
}

// One line per stage, on stderr, so stdout stays free for the summary.
class StageLog {
public:
  explicit StageLog(bool verbose) : verbose_(verbose) {}
  void begin(const std::string& stage) {
    stage_ = stage;
    t0_ = Clock::now();
    if (verbose_) std::fprintf(stderr, "[%s] ...\n", stage.c_str());
  }
  void done(const std::string& what = "", long long items = 0, const char* unit = "") {
    if (!verbose_) return;
    const double t = seconds_since(t0_);
    if (items > 0)
      std::fprintf(stderr, "[%s] done in %.2f s: %s (%.3g %s/s)\n", stage_.c_str(), t, what.c_str(), items / std::max(t, 1e-9), unit);
    else
      std::fprintf(stderr, "[%s] done in %.2f s%s%s\n", stage_.c_str(), t, what.empty() ? "" : ": ", what.c_str());
    std::fflush(stderr);
  }

private:
  bool verbose_;
  std::string stage_;
  Clock::time_point t0_;
};

// Runs a gmsh step; a gmsh failure becomes a RunError carrying gmsh's own message.
template <class F>
void gmsh_step(const GmshSession& session, const std::string& what, F&& step) {
  try {
    step();
  } catch (const InputError&) {
    throw;
  } catch (const RunError&) {
    throw;
  } catch (const std::exception& e) {
    const std::string log = session.errors();
    throw RunError("gmsh failed while " + what + ": " + (log.empty() ? std::string(e.what()) : log));
  } catch (const std::string& e) {  // gmsh 4.8 throws its message as a std::string
    const std::string log = session.errors();
    throw RunError("gmsh failed while " + what + ": " + (log.empty() ? e : log));
  } catch (...) {
    const std::string log = session.errors();
    throw RunError("gmsh failed while " + what + (log.empty() ? std::string() : ": " + log));
  }
}

// Per-element size (longest edge), total measure, counts and groups of the current mesh.
MeshSummary summarize(int dim) {
  MeshSummary s;
  s.dimension = dim;
  s.nodes = count_nodes();
  std::vector<int> types;
  std::vector<std::vector<std::size_t>> elements, element_nodes;
  gmsh::model::mesh::getElements(types, elements, element_nodes, dim, -1);
  std::vector<std::size_t> node_tags;
  std::vector<double> coords, params;
  gmsh::model::mesh::getNodes(node_tags, coords, params, -1, -1, false, false);
  std::size_t max_tag = 0;
  for (auto t : node_tags) max_tag = std::max(max_tag, t);
  std::vector<std::size_t> index_of(max_tag + 1, 0);
  for (std::size_t i = 0; i < node_tags.size(); ++i) index_of[node_tags[i]] = i;
  const auto position = [&](std::size_t tag) {
    const std::size_t i = index_of[tag];
    return Vec3{coords[3 * i], coords[3 * i + 1], coords[3 * i + 2]};
  };
  double hmin = std::numeric_limits<double>::max(), hmax = 0;
  const int per = dim == 3 ? 4 : 3;
  for (size_t k = 0; k < types.size(); ++k) {
    const auto& en = element_nodes[k];
    s.elements += static_cast<long long>(elements[k].size());
    if (types[k] != (dim == 3 ? 4 : 2)) continue;  // sizes and measure for linear simplices only
    std::array<Vec3, 4> x{};
    for (size_t e = 0; e < elements[k].size(); ++e) {
      for (int i = 0; i < per; ++i) x[i] = position(en[e * per + i]);
      double longest = 0;
      for (int i = 0; i < per; ++i)
        for (int j = i + 1; j < per; ++j) longest = std::max(longest, norm(sub(x[j], x[i])));
      hmin = std::min(hmin, longest);
      hmax = std::max(hmax, longest);
      const Vec3 a = sub(x[1], x[0]), b = sub(x[2], x[0]);
      s.measure += dim == 3 ? std::abs(dot(cross(a, b), sub(x[3], x[0]))) / 6 : norm(cross(a, b)) / 2;
    }
  }
  s.min_element_size_m = s.elements ? hmin : 0;
  s.max_element_size_m = hmax;
  gmsh::vectorpair physicals;
  gmsh::model::getPhysicalGroups(physicals);
  for (const auto& [d, tag] : physicals) {
    GroupSummary g;
    g.dim = d;
    gmsh::model::getPhysicalName(d, tag, g.name);
    std::vector<int> entities;
    gmsh::model::getEntitiesForPhysicalGroup(d, tag, entities);
    g.entities = static_cast<long long>(entities.size());
    for (int e : entities) g.elements += count_elements(d, e);
    s.groups.push_back(g);
  }
  return s;
}

void generate(const GmshSession& session, int dim, bool optimize, StageLog& log) {
  gmsh::option::setNumber("Mesh.Optimize", 0);  // run separately below, to time it
  const char* names[] = {"", "mesh 1D", "mesh 2D", "mesh 3D"};
  const char* units[] = {"", "line elements", "triangles", "tetrahedra"};
  for (int d = 1; d <= dim; ++d) {
    log.begin(names[d]);
    gmsh_step(session, std::string("meshing in ") + std::to_string(d) + "D", [&] { gmsh::model::mesh::generate(d); });
    const long long n = count_elements(d);
    log.done(std::to_string(n) + " " + units[d] + ", " + std::to_string(count_nodes()) + " nodes", n, "elements");
  }
  if (!optimize) return;
  log.begin("optimising");
  gmsh_step(session, "optimising", [&] {
    if (dim == 3) gmsh::model::mesh::optimize("", false, 1);
    else gmsh::model::mesh::optimize("Laplace2D", false, 1);
  });
  log.done();
}

void write_msh(const GmshSession& session, const std::string& output, StageLog& log) {
  log.begin("writing");
  gmsh::option::setNumber("Mesh.MshFileVersion", 4.1);
  gmsh::option::setNumber("Mesh.SaveAll", 0);
  gmsh::option::setNumber("Mesh.Binary", 0);
  OutputFile out(output);
  // gmsh picks the format from the extension, so write "<out>.partial" through a
  // ".msh" name in the same directory, then move it into place.
  const std::string gmsh_name = out.temp_path().string() + ".msh";
  gmsh_step(session, "writing " + output, [&] { gmsh::write(gmsh_name); });
  std::error_code ec;
  std::filesystem::rename(gmsh_name, out.temp_path(), ec);
  if (ec) throw RunError("cannot move " + gmsh_name + " to " + out.temp_path().string() + ": " + ec.message());
  out.commit();
  log.done(output + " (" + std::to_string(std::filesystem::file_size(output) / 1024) + " KiB)");
}

int model_dimension() { return gmsh::model::getDimension(); }

// The faces (edges in 2D) of the linear cells of dimension `dim` that belong to one cell
// only, added as a new discrete entity; returns its tag, or nothing when there are none.
// A mesh file without a boundary representation (msh 2.2, whose entities are discrete
// and unconnected) gives getBoundary nothing to work with, so the boundary is found from
// the elements themselves. Each facet is ordered to face out of its cell.
std::vector<int> add_boundary_facets(int dim) {
  const int cell_type = dim == 3 ? 4 : 2, facet_type = dim == 3 ? 2 : 1;
  std::vector<std::size_t> cells, cell_nodes;
  gmsh::model::mesh::getElementsByType(cell_type, cells, cell_nodes);
  std::vector<std::size_t> node_tags;
  std::vector<double> coords, params;
  gmsh::model::mesh::getNodes(node_tags, coords, params, -1, -1, false, false);
  std::map<std::size_t, Vec3> position;
  for (std::size_t i = 0; i < node_tags.size(); ++i) position[node_tags[i]] = {coords[3 * i], coords[3 * i + 1], coords[3 * i + 2]};

  const std::size_t per = static_cast<std::size_t>(dim) + 1;
  std::map<std::vector<std::size_t>, std::pair<std::vector<std::size_t>, int>> facets;  // sorted nodes -> (oriented, count)
  for (std::size_t e = 0; e + per <= cell_nodes.size(); e += per) {
    for (std::size_t skip = 0; skip < per; ++skip) {
      std::vector<std::size_t> facet;
      for (std::size_t i = 0; i < per; ++i)
        if (i != skip) facet.push_back(cell_nodes[e + i]);
      const Vec3 inward = sub(position[cell_nodes[e + skip]], position[facet[0]]);
      const Vec3 a = sub(position[facet[1]], position[facet[0]]);
      // 3D: the triangle's normal; 2D: the edge's normal in the x-y plane.
      const Vec3 normal = dim == 3 ? cross(a, sub(position[facet[2]], position[facet[0]])) : Vec3{a[1], -a[0], 0};
      if (dot(normal, inward) > 0) std::swap(facet[0], facet[1]);
      auto key = facet;
      std::sort(key.begin(), key.end());
      auto& entry = facets[key];
      if (entry.second++ == 0) entry.first = facet;
    }
  }
  std::vector<std::size_t> nodes;
  for (const auto& [key, entry] : facets)
    if (entry.second == 1) nodes.insert(nodes.end(), entry.first.begin(), entry.first.end());
  if (nodes.empty()) return {};
  const int entity = gmsh::model::addDiscreteEntity(dim - 1);
  gmsh::model::mesh::addElementsByType(entity, facet_type, {}, nodes);  // gmsh numbers them
  return {entity};
}

}  // namespace

MeshSummary mesh_specimen(const Specimen& spec, const MeshOptions& options) {
  const auto t0 = Clock::now();
  StageLog log(options.verbose);
  GmshSession session(options.threads);
  log.begin("geometry");
  GroupMap groups;
  gmsh_step(session, "building the geometry of " + spec.file, [&] { groups = build_specimen_model(spec); });
  gmsh_step(session, "setting mesh sizes", [&] { apply_size_fields(spec, groups, options.size_factor); });
  gmsh::option::setNumber("Mesh.ElementOrder", 1);
  gmsh::option::setNumber("Mesh.Algorithm", 6);  // Frontal-Delaunay 2D
  gmsh::option::setNumber("Mesh.Algorithm3D", spec.mesh.algorithm_3d == Algorithm3D::Hxt ? 10 : 1);
  log.done(std::to_string(groups.size()) + " named groups");
  generate(session, spec.dimension, spec.mesh.optimize, log);
  MeshSummary summary = summarize(spec.dimension);
  write_msh(session, options.output, log);
  summary.seconds = seconds_since(t0);
  return summary;
}

MeshSummary mesh_file(const std::string& input, const MeshOptions& options) {
  const auto t0 = Clock::now();
  namespace fs = std::filesystem;
  if (!fs::exists(input)) throw InputError(input, "", "file does not exist", "a readable .geo, .step, .stp or .msh file");
  std::string ext = fs::path(input).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  if (ext != ".geo" && ext != ".step" && ext != ".stp" && ext != ".msh")
    throw InputError(input, "", "unknown file extension '" + ext + "'",
                     ".yaml/.yml (specimen), .geo, .step, .stp or .msh");
  StageLog log(options.verbose);
  GmshSession session(options.threads);
  log.begin("reading");
  try {
    if (ext == ".step" || ext == ".stp") {
      gmsh::model::add("imported");
      // CAD files carry their own length unit (mm mostly); convert to metres, our SI contract.
      gmsh::option::setString("Geometry.OCCTargetUnit", "M");
      gmsh::vectorpair shapes;
      gmsh::model::occ::importShapes(input, shapes);
      gmsh::model::occ::synchronize();
    } else {
      gmsh::open(input);
    }
  } catch (...) {  // gmsh 4.8 throws std::string; its log holds the reason either way
    const std::string why = session.errors();
    throw InputError(input, "", "gmsh cannot read it" + (why.empty() ? std::string() : ": " + why),
                     "a valid " + ext.substr(1) + " file");
  }
  if (ext == ".msh") {
    const int dim = model_dimension();
    if (dim < 2 || count_elements(dim) == 0)
      throw InputError(input, "", "contains no 2D or 3D elements", "a mesh of triangles or tetrahedra");
    log.done(std::to_string(count_elements(dim)) + " elements of dimension " + std::to_string(dim));
  } else {
    const int dim = model_dimension();
    if (dim < 2) throw InputError(input, "", "defines no surface or volume", "a 2D or 3D geometry");
    log.done("geometry of dimension " + std::to_string(dim));
    if (options.size_m > 0) {
      gmsh::option::setNumber("Mesh.MeshSizeMax", options.size_m);
      gmsh::option::setNumber("Mesh.MeshSizeFactor", options.size_factor);
    }
    gmsh::option::setNumber("Mesh.ElementOrder", 1);
    generate(session, dim, true, log);
  }
  // Without physical groups gmsh would save every element; name the cells and the
  // boundary so that the contract "physical groups only" holds for imported geometry too.
  gmsh::vectorpair physicals;
  gmsh::model::getPhysicalGroups(physicals);
  if (physicals.empty()) {
    const int dim = model_dimension();
    gmsh::vectorpair cells, boundary;
    gmsh::model::getEntities(cells, dim);
    std::vector<int> cell_tags, boundary_tags;
    for (const auto& c : cells) cell_tags.push_back(c.second);
    gmsh::model::getBoundary(cells, boundary, true, false, false);
    for (const auto& b : boundary) boundary_tags.push_back(std::abs(b.second));
    if (boundary_tags.empty()) boundary_tags = add_boundary_facets(dim);
    gmsh::model::setPhysicalName(dim, gmsh::model::addPhysicalGroup(dim, cell_tags), "body");
    if (!boundary_tags.empty())
      gmsh::model::setPhysicalName(dim - 1, gmsh::model::addPhysicalGroup(dim - 1, boundary_tags), "outer");
  }
  MeshSummary summary = summarize(model_dimension());
  write_msh(session, options.output, log);
  summary.seconds = seconds_since(t0);
  return summary;
}

void print_summary(const MeshSummary& s, std::FILE* out) {
  std::fprintf(out, "mesh summary (%dD)\n", s.dimension);
  std::fprintf(out, "  elements        %lld %s\n", s.elements, s.dimension == 3 ? "tetrahedra" : "triangles");
  std::fprintf(out, "  nodes           %lld\n", s.nodes);
  std::fprintf(out, "  element size    %.4g .. %.4g mm (longest edge)\n", s.min_element_size_m * 1e3, s.max_element_size_m * 1e3);
  if (s.dimension == 3) std::fprintf(out, "  volume          %.6g m3\n", s.measure);
  else std::fprintf(out, "  area            %.6g m2\n", s.measure);
  std::fprintf(out, "  physical groups:\n");
  for (const auto& g : s.groups)
    std::fprintf(out, "    %-16s dim %d  %4lld entities  %9lld elements\n", g.name.c_str(), g.dim, g.entities, g.elements);
  std::fprintf(out, "  time            %.2f s\n", s.seconds);
}

}  // namespace breccia::mesher
