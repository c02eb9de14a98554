#include "breccia/geometry/gmsh_mesh.hpp"

#include <gmsh.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "breccia/common/error.hpp"

namespace breccia::geometry {
namespace {

constexpr const char* kExpectedFile = "a gmsh mesh file (.msh format 2.2 or 4.1)";

std::string trim(std::string s) {
  while (!s.empty() && (s.back() == '\r' || s.back() == ' ' || s.back() == '\t')) s.pop_back();
  size_t first = 0;
  while (first < s.size() && (s[first] == ' ' || s[first] == '\t')) ++first;
  return s.substr(first);
}

// gmsh happily "opens" a missing file or a file of another kind (it would even run a
// text file as a .geo script), so the header is checked here first.
void check_msh_header(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path, "", "file does not exist", kExpectedFile);
  if (fs::is_directory(path, ec)) throw InputError(path, "", "is a directory", kExpectedFile);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "", "file cannot be opened for reading", kExpectedFile);
  std::string first, second;
  if (!std::getline(in, first)) throw InputError(path, "", "file is empty", kExpectedFile);
  first = trim(first);
  if (first != "$MeshFormat") {
    if (first.size() > 40) first = first.substr(0, 40) + "...";
    throw InputError(path, "line 1", "'" + first + "' is not a gmsh mesh header",
                     std::string(kExpectedFile) + " starting with $MeshFormat");
  }
  std::getline(in, second);
  std::istringstream version_line(second);
  double version = 0;
  if (!(version_line >> version))
    throw InputError(path, "$MeshFormat", "no version number", kExpectedFile);
  const int major = static_cast<int>(version);
  if (major != 2 && major != 4)
    throw InputError(path, "$MeshFormat", "format version " + trim(second).substr(0, 10),
                     "version 2.2 or 4.1");
}

std::string first_gmsh_error(const std::vector<std::string>& log) {
  for (const auto& line : log)
    if (line.rfind("Error", 0) == 0) return line;
  return {};
}

// gmsh keeps global state; restore the terminal option and the current model afterwards
// so a caller that uses gmsh itself (the tests build their meshes with it) is not disturbed.
class GmshReadScope {
public:
  GmshReadScope() {
    gmsh::initialize();  // no-op (with a warning we silence) when already initialised
    gmsh::option::getNumber("General.Terminal", terminal_);
    gmsh::option::setNumber("General.Terminal", 0);
    gmsh::model::getCurrent(previous_model_);
    gmsh::logger::start();
  }
  ~GmshReadScope() {
    gmsh::logger::stop();
    try {
      std::string current;
      gmsh::model::getCurrent(current);
      if (opened_) gmsh::model::remove();
      std::vector<std::string> models;
      gmsh::model::list(models);
      if (std::find(models.begin(), models.end(), previous_model_) != models.end())
        gmsh::model::setCurrent(previous_model_);
      gmsh::option::setNumber("General.Terminal", terminal_);
    } catch (...) {
    }
  }
  void mark_opened() { opened_ = true; }

private:
  double terminal_ = 0;
  std::string previous_model_;
  bool opened_ = false;
};

}  // namespace

GmshMesh read_gmsh_mesh(const std::string& path) {
  check_msh_header(path);
  GmshReadScope scope;
  // gmsh reports a malformed file by logging an error and throwing the message as a
  // std::string (or by only logging it); both become an InputError naming the file.
  std::string gmsh_error;
  try {
    scope.mark_opened();
    gmsh::open(path);
  } catch (const std::string& message) {
    gmsh_error = message;
  } catch (const std::exception& e) {
    gmsh_error = e.what();
  }
  std::vector<std::string> log;
  gmsh::logger::get(log);
  if (const std::string logged = first_gmsh_error(log); !logged.empty()) gmsh_error = logged;
  if (!gmsh_error.empty())
    throw InputError(path, "", "gmsh could not read the mesh: " + gmsh_error, kExpectedFile);

  GmshMesh mesh;
  mesh.path = path;
  std::vector<double> parametric;
  gmsh::model::mesh::getNodes(mesh.node_tags, mesh.node_coords_m, parametric, -1, -1, false, false);

  gmsh::vectorpair entities;
  gmsh::model::getEntities(entities);
  for (const auto& [dim, tag] : entities) {
    std::vector<int> types;
    std::vector<std::vector<std::size_t>> element_tags, node_tags;
    gmsh::model::mesh::getElements(types, element_tags, node_tags, dim, tag);
    for (size_t t = 0; t < types.size(); ++t) {
      ElementBlock block;
      block.dim = dim;
      block.entity = tag;
      block.type = types[t];
      int type_dim = 0, order = 0, primary = 0;
      std::vector<double> local;
      gmsh::model::mesh::getElementProperties(types[t], block.type_name, type_dim, order,
                                              block.nodes_per_element, local, primary);
      block.element_tags = std::move(element_tags[t]);
      block.node_tags = std::move(node_tags[t]);
      mesh.blocks.push_back(std::move(block));
    }
  }

  gmsh::vectorpair groups;
  gmsh::model::getPhysicalGroups(groups);
  for (const auto& [dim, tag] : groups) {
    PhysicalGroup group;
    group.dim = dim;
    group.tag = tag;
    gmsh::model::getPhysicalName(dim, tag, group.name);
    gmsh::model::getEntitiesForPhysicalGroup(dim, tag, group.entities);
    mesh.groups.push_back(std::move(group));
  }
  std::sort(mesh.groups.begin(), mesh.groups.end(),
            [](const PhysicalGroup& a, const PhysicalGroup& b) {
              return a.dim != b.dim ? a.dim < b.dim : a.tag < b.tag;
            });
  return mesh;
}

}  // namespace breccia::geometry
