#pragma once
// One place that validates YAML input. A Section wraps a YAML map with its file name and
// path ("loads[2].history"), rejects unknown keys naming the allowed ones, and converts
// values with their units (units.hpp). Every error is an InputError naming file and field.
#include <yaml-cpp/yaml.h>

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "breccia/common/units.hpp"

namespace breccia {

class Section {
public:
  Section(YAML::Node node, std::string file, std::string path);

  // Load a YAML file; throws InputError for a missing file or a syntax error (with line).
  // Overrides registered for the file (set_overrides) are applied before anything reads it.
  static Section load_file(const std::string& file);
  // Command-line overrides of one file's values (`breccia-solve CASE --set KEY=VALUE`, the
  // documented way to run a case's variants): KEY a path as error messages name fields,
  // `time.end`, `loads[0].history.peak`; VALUE read as YAML (`4 MPa`, `[0, 1, 0]`). Missing
  // map keys are created (the case's own validation then checks them); a list index must
  // exist. Applied, in order, every time this process loads that file.
  // `variant` (`breccia-solve CASE --variant NAME`) first applies the file's own
  // `variants: {NAME: {KEY: VALUE, ...}}` entry, exactly as the same --set options would, then
  // the assignments (so --set wins); the `variants` block itself is removed from the loaded
  // tree, so that case parsers never see it. `output_folder` (the run's -o) is where
  // input_path looks first for a relative input file.
  static void set_overrides(const std::string& file, std::vector<std::string> assignments,
                            std::string variant = "", std::string output_folder = "");

  // The file as this process reads it (variant and --set applied, the variants block
  // dropped), as YAML text: what a run records next to its results (case_as_run.yaml), so
  // that a variant's values can be read back. Comments are not kept.
  static std::string text_as_loaded(const std::string& file);

  const std::string& file() const { return file_; }
  const std::string& path() const { return path_; }
  const YAML::Node& node() const { return node_; }
  std::string field(const std::string& key) const;  // "path.key"

  bool has(const std::string& key) const;
  // Throws for any key not in `allowed`.
  void allow_only(const std::vector<std::string>& allowed) const;

  Section section(const std::string& key) const;                    // required map
  std::optional<Section> optional_section(const std::string& key) const;
  std::vector<Section> list(const std::string& key) const;          // list of maps (empty if absent)

  double number(const std::string& key, Quantity q) const;          // required
  double number(const std::string& key, Quantity q, double fallback) const;
  std::optional<double> optional_number(const std::string& key, Quantity q) const;
  double positive(const std::string& key, Quantity q) const;        // required, > 0
  double positive(const std::string& key, Quantity q, double fallback) const;
  long long integer(const std::string& key) const;
  long long integer(const std::string& key, long long fallback) const;
  bool boolean(const std::string& key, bool fallback) const;
  std::string text(const std::string& key) const;
  std::string text(const std::string& key, const std::string& fallback) const;
  // A string that must be one of `choices`.
  std::string choice(const std::string& key, const std::vector<std::string>& choices,
                     const std::string& fallback) const;
  std::string choice(const std::string& key, const std::vector<std::string>& choices) const;
  std::vector<double> numbers(const std::string& key, Quantity q, size_t expected_size = 0) const;
  std::array<double, 3> vec3(const std::string& key, Quantity q) const;  // 2 or 3 entries, z = 0
  std::vector<std::string> texts(const std::string& key) const;
  // An input file named by `key` (e.g. specimen.particles). An absolute path is taken as it
  // is; a relative one is looked for in the run's output folder (set_overrides) first, then
  // next to this file. Throws InputError naming the file, the key and both places looked
  // when it is in neither.
  std::string input_path(const std::string& key) const;

private:
  YAML::Node child(const std::string& key) const;
  [[noreturn]] void fail(const std::string& key, const std::string& found,
                         const std::string& expected) const;
  double scalar_quantity(const YAML::Node& n, const std::string& fieldname, Quantity q) const;

  YAML::Node node_;
  std::string file_;
  std::string path_;
};

}  // namespace breccia
