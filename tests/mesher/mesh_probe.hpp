#pragma once
// Test-side reader for .msh files (through the gmsh API): nodes and the elements of each
// physical group, plus the small measures the tests need.
#include <array>
#include <map>
#include <string>
#include <vector>

namespace breccia::mesher::testing {

using Point = std::array<double, 3>;
using Element = std::vector<std::size_t>;  // node tags

struct Group {
  int dim = 0;
  int entities = 0;
  std::vector<Element> elements;
};

struct MeshProbe {
  std::string version;
  std::map<std::size_t, Point> nodes;
  std::map<std::string, Group> groups;

  const Group& group(const std::string& name) const;
  Point centroid(const Element& e) const;
  double measure(const Element& e) const;           // tet volume / triangle area
  double longest_edge(const Element& e) const;
  double total_measure(const std::string& name) const;
};

MeshProbe read_msh(const std::string& path);

// Write `text` to a fresh file under the test's temp directory and return its path.
std::string write_temp_file(const std::string& name, const std::string& text);

}  // namespace breccia::mesher::testing
