#include "mesh_probe.hpp"

#include <gmsh.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include <unistd.h>

namespace breccia::mesher::testing {
namespace {

Point minus(const Point& a, const Point& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Point cross(const Point& a, const Point& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double dot(const Point& a, const Point& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

}  // namespace

const Group& MeshProbe::group(const std::string& name) const {
  const auto it = groups.find(name);
  if (it == groups.end()) throw std::runtime_error("mesh has no physical group '" + name + "'");
  return it->second;
}

Point MeshProbe::centroid(const Element& e) const {
  Point c{0, 0, 0};
  for (auto t : e)
    for (int k = 0; k < 3; ++k) c[k] += nodes.at(t)[k] / e.size();
  return c;
}

double MeshProbe::measure(const Element& e) const {
  const Point a = minus(nodes.at(e[1]), nodes.at(e[0])), b = minus(nodes.at(e[2]), nodes.at(e[0]));
  if (e.size() == 4) return std::abs(dot(cross(a, b), minus(nodes.at(e[3]), nodes.at(e[0])))) / 6;
  const Point n = cross(a, b);
  return std::sqrt(dot(n, n)) / 2;
}

double MeshProbe::longest_edge(const Element& e) const {
  double longest = 0;
  for (size_t i = 0; i < e.size(); ++i)
    for (size_t j = i + 1; j < e.size(); ++j) {
      const Point d = minus(nodes.at(e[i]), nodes.at(e[j]));
      longest = std::max(longest, std::sqrt(dot(d, d)));
    }
  return longest;
}

double MeshProbe::total_measure(const std::string& name) const {
  double sum = 0;
  for (const auto& e : group(name).elements) sum += measure(e);
  return sum;
}

MeshProbe read_msh(const std::string& path) {
  MeshProbe probe;
  {
    std::ifstream f(path);
    std::string header;
    f >> header >> probe.version;
  }
  gmsh::initialize(0, nullptr, false);
  gmsh::option::setNumber("General.Terminal", 0);
  gmsh::open(path);
  std::vector<std::size_t> tags;
  std::vector<double> coords, params;
  gmsh::model::mesh::getNodes(tags, coords, params, -1, -1, false, false);
  for (size_t i = 0; i < tags.size(); ++i) probe.nodes[tags[i]] = {coords[3 * i], coords[3 * i + 1], coords[3 * i + 2]};
  gmsh::vectorpair physicals;
  gmsh::model::getPhysicalGroups(physicals);
  for (const auto& [dim, tag] : physicals) {
    std::string name;
    gmsh::model::getPhysicalName(dim, tag, name);
    Group& g = probe.groups[name];
    g.dim = dim;
    std::vector<int> entities;
    gmsh::model::getEntitiesForPhysicalGroup(dim, tag, entities);
    g.entities = static_cast<int>(entities.size());
    for (int entity : entities) {
      std::vector<int> types;
      std::vector<std::vector<std::size_t>> elements, element_nodes;
      gmsh::model::mesh::getElements(types, elements, element_nodes, dim, entity);
      for (size_t k = 0; k < types.size(); ++k) {
        const size_t per = element_nodes[k].size() / elements[k].size();
        for (size_t e = 0; e < elements[k].size(); ++e)
          g.elements.emplace_back(element_nodes[k].begin() + e * per, element_nodes[k].begin() + (e + 1) * per);
      }
    }
  }
  gmsh::finalize();
  return probe;
}

std::string write_temp_file(const std::string& name, const std::string& text) {
  const auto dir = std::filesystem::temp_directory_path() / ("breccia-mesher-test-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto path = dir / name;
  std::ofstream(path) << text;
  return path.string();
}

}  // namespace breccia::mesher::testing
