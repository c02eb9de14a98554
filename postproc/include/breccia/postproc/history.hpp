#pragma once
// RUN_DIR/history.csv: one row per history sample, columns by name.
#include <filesystem>
#include <string>
#include <vector>

namespace breccia::postproc {

struct History {
  std::filesystem::path path;
  std::vector<std::string> names;
  std::vector<std::vector<double>> columns;
  size_t rows() const { return columns.empty() ? 0 : columns.front().size(); }
  const std::vector<double>* find(const std::string& name) const;
  const std::vector<double>& column(const std::string& name) const;  // InputError if absent
  // Probe names from columns "probe_<name>_<component>", in order of appearance.
  std::vector<std::string> probe_names() const;
  std::vector<std::string> probe_columns(const std::string& probe) const;
};

History read_history(const std::filesystem::path& path);

}  // namespace breccia::postproc
