#include "breccia/postproc/history.hpp"

#include "breccia/common/csv.hpp"
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
  CsvColumns table = read_csv_columns(path, {.expected = "history.csv written by breccia-solve"});
  History h;
  h.path = path;
  h.names = std::move(table.names);
  h.columns = std::move(table.columns);
  return h;
}

}  // namespace breccia::postproc
