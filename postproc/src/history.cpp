#include "breccia/postproc/history.hpp"

#include <cstdlib>
#include <fstream>
#include <sstream>

#include "breccia/common/error.hpp"

namespace breccia::postproc {

const std::vector<double>* History::find(const std::string& name) const {
  for (size_t k = 0; k < names.size(); ++k)
    if (names[k] == name) return &columns[k];
  return nullptr;
}

const std::vector<double>& History::column(const std::string& name) const {
  if (const auto* c = find(name)) return *c;
  throw InputError(path.string(), "header", "no column '" + name + "'", "a history.csv written by breccia-solve");
}

std::vector<std::string> History::probe_names() const {
  std::vector<std::string> out;
  for (const auto& n : names) {
    if (n.rfind("probe_", 0) != 0) continue;
    const size_t last = n.rfind('_');
    if (last <= 6) continue;
    const std::string probe = n.substr(6, last - 6);
    bool seen = false;
    for (const auto& p : out) seen = seen || p == probe;
    if (!seen) out.push_back(probe);
  }
  return out;
}

std::vector<std::string> History::probe_columns(const std::string& probe) const {
  std::vector<std::string> out;
  const std::string prefix = "probe_" + probe + "_";
  for (const auto& n : names)
    if (n.rfind(prefix, 0) == 0 && n.find('_', prefix.size()) == std::string::npos) out.push_back(n);
  return out;
}

History read_history(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path.string(), "", "cannot be opened", "history.csv written by breccia-solve");
  History h;
  h.path = path;
  std::string line;
  if (!std::getline(in, line)) throw InputError(path.string(), "header", "empty file", "a CSV header line");
  {
    std::stringstream ss(line);
    std::string name;
    while (std::getline(ss, name, ',')) {
      while (!name.empty() && (name.back() == '\r' || name.back() == ' ')) name.pop_back();
      h.names.push_back(name);
    }
  }
  h.columns.resize(h.names.size());
  size_t row = 1;
  while (std::getline(in, line)) {
    ++row;
    if (line.empty() || line == "\r") continue;
    std::stringstream ss(line);
    std::string cell;
    size_t col = 0;
    while (std::getline(ss, cell, ',')) {
      if (col >= h.names.size()) break;
      char* end = nullptr;
      const double v = std::strtod(cell.c_str(), &end);
      if (end == cell.c_str())
        throw InputError(path.string(), "line " + std::to_string(row) + ", column " + h.names[col],
                         "'" + cell + "'", "a number");
      h.columns[col++].push_back(v);
    }
    if (col != h.names.size())
      throw InputError(path.string(), "line " + std::to_string(row), std::to_string(col) + " values",
                       std::to_string(h.names.size()) + " (one per header column)");
  }
  return h;
}

}  // namespace breccia::postproc
