#include "breccia/common/yaml_input.hpp"

#include <algorithm>
#include <charconv>
#include <cstdint>
#include <filesystem>
#include <map>

#include "breccia/common/error.hpp"
#include "breccia/common/units.hpp"

namespace breccia {

Section::Section(YAML::Node node, std::string file, std::string path)
    : node_(std::move(node)), file_(std::move(file)), path_(std::move(path)) {
  if (!node_.IsMap())
    throw InputError(file_, path_.empty() ? "(top level)" : path_,
                     "is not a mapping of keys to values", "a YAML map");
}

namespace {
// yaml-cpp keeps a repeated key as a second entry and answers lookups with the first, so a
// second `model:` block would be dropped without a word: refuse it, naming both lines.
// Also refuses keys that are not plain names ({[1, 2]: 3}) and nesting deeper than any case
// needs: an alias inside its own anchor (`a: &d [*d]`) is a node that contains itself, and a
// walk down it would never end.
void reject_duplicate_keys(const YAML::Node& node, const std::string& file, const std::string& path, int depth = 0) {
  constexpr int kDeepest = 64;
  if (depth > kDeepest)
    throw InputError(file, path.substr(0, path.find('[', path.find('[') + 1)) + "...",
                     "nested more than " + std::to_string(kDeepest) + " levels deep",
                     "a case of plain nesting (an alias inside its own anchor, such as &d [*d], contains itself)");
  if (node.IsMap()) {
    std::map<std::string, int> seen;  // key -> line (1-based)
    for (auto it = node.begin(); it != node.end(); ++it) {
      if (!it->first.IsScalar())
        throw InputError(file, path.empty() ? "(top level)" : path,
                         "a key that is a list or a map, on line " + std::to_string(it->first.Mark().line + 1),
                         "keys that are plain names");
      const std::string key = it->first.Scalar();
      const int line = it->first.Mark().line + 1;
      const std::string field = path.empty() ? key : path + "." + key;
      if (auto [at, inserted] = seen.emplace(key, line); !inserted)
        throw InputError(file, field, "given twice, on lines " + std::to_string(at->second) + " and " + std::to_string(line),
                         "each key once (merge the two)");
      reject_duplicate_keys(it->second, file, field, depth + 1);
    }
  } else if (node.IsSequence()) {
    for (size_t k = 0; k < node.size(); ++k)
      reject_duplicate_keys(node[k], file, path + "[" + std::to_string(k) + "]", depth + 1);
  }
}
}  // namespace

namespace {
struct Overrides {
  std::string file;  // canonical path
  std::vector<std::string> assignments;
  std::string variant;        // a name of the file's variants block ("" none)
  std::string output_folder;  // where relative input files are looked for first ("" none)
};
Overrides& registered_overrides() {
  static Overrides o;
  return o;
}

std::string canonical_or_same(const std::string& file) {
  std::error_code ec;
  const auto p = std::filesystem::weakly_canonical(file, ec);
  return ec ? file : p.string();
}

// KEY = value into root: KEY's parts are map keys and [index] list entries. `origin` names
// where the override came from in errors: "--set" or "variants.NAME".
void apply_override(YAML::Node& root, const std::string& key, const YAML::Node& value, const std::string& file,
                    const std::string& origin) {
  // Walk the path; yaml-cpp nodes are handles, so `node = node[k]` would rebind, not assign:
  // collect the handles and assign at the end.
  std::vector<YAML::Node> chain{root};
  std::string done;
  size_t pos = 0;
  while (pos < key.size()) {
    if (key[pos] == '.') {
      ++pos;
      continue;
    }
    YAML::Node at = chain.back();
    if (key[pos] == '[') {
      const size_t close = key.find(']', pos);
      if (close == std::string::npos) throw InputError(file, origin + " " + key, "an unclosed '['", "KEY[INDEX] with a whole number");
      const std::string digits = key.substr(pos + 1, close - pos - 1);
      if (digits.empty() || digits.find_first_not_of("0123456789") != std::string::npos)
        throw InputError(file, origin + " " + key, "index '" + digits + "'", "a whole number in [ ]");
      // More digits than any list has entries: no entry (stoul would overflow past 20 digits).
      const size_t index = digits.size() > 9 ? SIZE_MAX : std::stoul(digits);
      if (!at.IsSequence() || index >= at.size())
        throw InputError(file, origin + " " + key,
                         "'" + (done.empty() ? std::string("(top level)") : done) + "' has no entry [" + digits + "]" +
                             (at.IsSequence() ? " (it has " + std::to_string(at.size()) + ")" : " (it is not a list)"),
                         "an existing list entry");
      chain.push_back(at[index]);
      done += "[" + digits + "]";
      pos = close + 1;
    } else {
      const size_t end = key.find_first_of(".[", pos);
      const std::string name = key.substr(pos, end == std::string::npos ? std::string::npos : end - pos);
      if (at.IsDefined() && !at.IsNull() && !at.IsMap())
        throw InputError(file, origin + " " + key, "'" + done + "' is not a map of keys", "a path through maps and lists");
      chain.push_back(at[name]);
      done += (done.empty() ? "" : ".") + name;
      pos = end == std::string::npos ? key.size() : end;
    }
  }
  if (chain.size() < 2) throw InputError(file, origin + " " + key, "no key", "KEY=VALUE");
  chain.back() = YAML::Clone(value);
}

// KEY=VALUE (a --set option) into root.
void apply_override(YAML::Node& root, const std::string& assignment, const std::string& file) {
  const size_t eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0)
    throw InputError("--set", assignment, "not KEY=VALUE", "--set time.end=\"100 us\" (a field path, '=', a value)");
  const std::string key = assignment.substr(0, eq), text = assignment.substr(eq + 1);
  YAML::Node value;
  try {
    value = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw InputError("--set", key, "value '" + text + "': " + e.msg, "a YAML value (a number, text, or [a, b, c])");
  }
  reject_duplicate_keys(value, "--set", key);  // a map given whole ({steps: 3, steps: 4}) as the file's are
  apply_override(root, key, value, file, "--set");
}

// The names of the file's variants block, for error messages.
std::string variant_names(const YAML::Node& variants) {
  std::string names;
  for (auto it = variants.begin(); it != variants.end(); ++it) names += (names.empty() ? "" : ", ") + it->first.Scalar();
  return names;
}

// Applies variants.NAME (a map of KEY: VALUE, in order; or a list of such one-entry maps) to
// root, then drops the variants block, which no case parser knows. Without a variant chosen
// the block is only checked for its shape (and dropped).
void apply_variant(YAML::Node& root, const std::string& name, const std::string& file) {
  const YAML::Node variants = root["variants"];
  if (!variants.IsDefined() || variants.IsNull()) {
    if (!name.empty())
      throw InputError(file, "--variant " + name, "the case file has no 'variants' block",
                       "a case file with variants: {" + name + ": {KEY: VALUE, ...}}, or no --variant");
    return;
  }
  if (!variants.IsMap())
    throw InputError(file, "variants", "is not a map", "variants: {NAME: {KEY: VALUE, ...}, ...}");
  if (!name.empty()) {
    const YAML::Node chosen = variants[name];
    if (!chosen.IsDefined())
      throw InputError(file, "--variant " + name, "no variant '" + name + "'", "one of: " + variant_names(variants));
    const std::string where = "variants." + name;
    // Each entry is applied as `--set KEY=VALUE` would be; a map keeps the file's order.
    auto apply_map = [&](const YAML::Node& m, const std::string& at) {
      if (!m.IsMap()) throw InputError(file, at, "is not a map of KEY: VALUE", "KEY: VALUE entries (time.end: 100 us)");
      for (auto it = m.begin(); it != m.end(); ++it) apply_override(root, it->first.Scalar(), it->second, file, where);
    };
    if (chosen.IsSequence()) {
      for (size_t k = 0; k < chosen.size(); ++k) apply_map(chosen[k], where + "[" + std::to_string(k) + "]");
    } else if (!chosen.IsNull()) {
      apply_map(chosen, where);
    }
  }
  root.remove("variants");
}
}  // namespace

void Section::set_overrides(const std::string& file, std::vector<std::string> assignments, std::string variant,
                            std::string output_folder) {
  registered_overrides() = {canonical_or_same(file), std::move(assignments), std::move(variant), std::move(output_folder)};
}

Section Section::load_file(const std::string& file) {
  if (!std::filesystem::exists(file))
    throw InputError(file, "", "file does not exist", "a readable YAML file");
  YAML::Node root;
  try {
    root = YAML::LoadFile(file);
  } catch (const YAML::Exception& e) {
    throw InputError(file, "line " + std::to_string(e.mark.line + 1),
                     "YAML syntax error: " + e.msg, "valid YAML");
  }
  if (!root.IsMap()) throw InputError(file, "(top level)", "is not a YAML map", "a map of sections");
  reject_duplicate_keys(root, file, "");
  const Overrides& o = registered_overrides();
  const bool registered = o.file == canonical_or_same(file);
  apply_variant(root, registered ? o.variant : std::string(), file);
  if (registered)
    for (const auto& a : o.assignments) apply_override(root, a, file);
  return Section(root, file, "");
}

std::string Section::text_as_loaded(const std::string& file) {
  YAML::Emitter out;
  out << load_file(file).node();
  return std::string(out.c_str()) + "\n";
}

std::string Section::field(const std::string& key) const {
  return path_.empty() ? key : path_ + "." + key;
}

bool Section::has(const std::string& key) const { return node_[key].IsDefined() && !node_[key].IsNull(); }

YAML::Node Section::child(const std::string& key) const { return node_[key]; }

void Section::fail(const std::string& key, const std::string& found, const std::string& expected) const {
  throw InputError(file_, field(key), found, expected);
}

void Section::allow_only(const std::vector<std::string>& allowed) const {
  for (const auto& kv : node_) {
    const std::string key = kv.first.as<std::string>();
    if (std::find(allowed.begin(), allowed.end(), key) != allowed.end()) continue;
    std::string list;
    for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
    fail(key, "unknown key '" + key + "'", "one of: " + list);
  }
}

Section Section::section(const std::string& key) const {
  if (!has(key)) fail(key, "missing", "a section '" + key + "'");
  if (!child(key).IsMap()) fail(key, "is not a map", "a map of keys to values");
  return Section(child(key), file_, field(key));
}

std::optional<Section> Section::optional_section(const std::string& key) const {
  if (!has(key)) return std::nullopt;
  return section(key);
}

std::vector<Section> Section::list(const std::string& key) const {
  std::vector<Section> out;
  if (!has(key)) return out;
  const YAML::Node n = child(key);
  if (!n.IsSequence()) fail(key, "is not a list", "a YAML list of maps");
  for (size_t i = 0; i < n.size(); ++i) {
    const std::string p = field(key) + "[" + std::to_string(i) + "]";
    if (!n[i].IsMap()) throw InputError(file_, p, "is not a map", "a map of keys to values");
    out.emplace_back(n[i], file_, p);
  }
  return out;
}

double Section::scalar_quantity(const YAML::Node& n, const std::string& fieldname, Quantity q) const {
  if (!n.IsScalar())
    throw InputError(file_, fieldname, "is not a single value",
                     std::string(quantity_name(q)) + " (a number, SI, or '<number> <unit>')");
  return parse_quantity(n.Scalar(), q, file_, fieldname);
}

double Section::number(const std::string& key, Quantity q) const {
  if (!has(key)) fail(key, "missing", std::string(quantity_name(q)) + " (SI or '<number> <unit>')");
  return scalar_quantity(child(key), field(key), q);
}

double Section::number(const std::string& key, Quantity q, double fallback) const {
  return has(key) ? number(key, q) : fallback;
}

std::optional<double> Section::optional_number(const std::string& key, Quantity q) const {
  if (!has(key)) return std::nullopt;
  return number(key, q);
}

double Section::positive(const std::string& key, Quantity q) const {
  const double v = number(key, q);
  if (!(v > 0.0)) fail(key, "value " + short_number(v) + " is not positive", "a value > 0");
  return v;
}

double Section::positive(const std::string& key, Quantity q, double fallback) const {
  return has(key) ? positive(key, q) : fallback;
}

long long Section::integer(const std::string& key) const {
  if (!has(key)) fail(key, "missing", "an integer");
  const YAML::Node n = child(key);
  try {
    if (!n.IsScalar()) throw YAML::Exception(YAML::Mark(), "");
    // Base 10 only: yaml-cpp reads a leading 0 as octal (010 was 8 steps) and 0x as hex.
    const std::string& t = n.Scalar();
    long long v = 0;
    const char* begin = t.data() + (!t.empty() && t[0] == '+' ? 1 : 0);
    const auto [end, ec] = std::from_chars(begin, t.data() + t.size(), v, 10);
    if (ec != std::errc() || end != t.data() + t.size() || begin == t.data() + t.size())
      throw YAML::Exception(YAML::Mark(), "");
    return v;
  } catch (const YAML::Exception&) {
    fail(key, "'" + (n.IsScalar() ? n.Scalar() : std::string("non-scalar")) + "' is not an integer", "an integer");
  }
}

long long Section::integer(const std::string& key, long long fallback) const {
  return has(key) ? integer(key) : fallback;
}

bool Section::boolean(const std::string& key, bool fallback) const {
  if (!has(key)) return fallback;
  const YAML::Node n = child(key);
  try {
    if (!n.IsScalar()) throw YAML::Exception(YAML::Mark(), "");
    return n.as<bool>();
  } catch (const YAML::Exception&) {
    fail(key, "'" + (n.IsScalar() ? n.Scalar() : std::string("non-scalar")) + "' is not a boolean", "true or false");
  }
}

std::string Section::text(const std::string& key) const {
  if (!has(key)) fail(key, "missing", "a text value");
  const YAML::Node n = child(key);
  if (!n.IsScalar()) fail(key, "is not a single text value", "a text value");
  return n.Scalar();
}

std::string Section::text(const std::string& key, const std::string& fallback) const {
  return has(key) ? text(key) : fallback;
}

std::string Section::choice(const std::string& key, const std::vector<std::string>& choices,
                            const std::string& fallback) const {
  if (!has(key)) return fallback;
  return choice(key, choices);
}

std::string Section::choice(const std::string& key, const std::vector<std::string>& choices) const {
  const std::string v = text(key);
  if (std::find(choices.begin(), choices.end(), v) != choices.end()) return v;
  std::string list;
  for (const auto& c : choices) list += (list.empty() ? "" : ", ") + c;
  fail(key, "'" + v + "' is not a valid choice", "one of: " + list);
}

std::vector<double> Section::numbers(const std::string& key, Quantity q, size_t expected_size) const {
  if (!has(key)) fail(key, "missing", "a list of " + std::string(quantity_name(q)) + " values");
  const YAML::Node n = child(key);
  if (!n.IsSequence()) fail(key, "is not a list", "a list like [1, 2, 3]");
  if (expected_size && n.size() != expected_size)
    fail(key, "has " + std::to_string(n.size()) + " entries", std::to_string(expected_size) + " entries");
  std::vector<double> out;
  for (size_t i = 0; i < n.size(); ++i)
    out.push_back(scalar_quantity(n[i], field(key) + "[" + std::to_string(i) + "]", q));
  return out;
}

std::array<double, 3> Section::vec3(const std::string& key, Quantity q) const {
  auto v = numbers(key, q);
  if (v.size() != 2 && v.size() != 3)
    fail(key, "has " + std::to_string(v.size()) + " entries", "2 or 3 coordinates");
  return {v[0], v[1], v.size() == 3 ? v[2] : 0.0};
}

std::vector<std::string> Section::texts(const std::string& key) const {
  std::vector<std::string> out;
  if (!has(key)) return out;
  const YAML::Node n = child(key);
  if (n.IsScalar()) return {n.Scalar()};
  if (!n.IsSequence()) fail(key, "is not a list", "a list of names");
  for (size_t i = 0; i < n.size(); ++i) {
    if (!n[i].IsScalar()) fail(key, "entry " + std::to_string(i) + " is not a name", "a list of names");
    out.push_back(n[i].Scalar());
  }
  return out;
}

std::string Section::input_path(const std::string& key) const {
  const std::filesystem::path given = text(key);
  if (given.is_absolute()) {
    if (!std::filesystem::exists(given)) fail(key, "'" + given.string() + "' does not exist", "an existing file");
    return given.string();
  }
  // The run's output folder first: a run's own inputs (breccia-place -o RUN/particles.h5)
  // take precedence over files shipped next to the case.
  std::vector<std::filesystem::path> places;
  const Overrides& o = registered_overrides();
  if (!o.output_folder.empty() && o.file == canonical_or_same(file_)) places.push_back(o.output_folder);
  places.push_back(std::filesystem::path(file_).parent_path());
  std::string looked;
  for (const auto& dir : places) {
    const std::filesystem::path candidate = dir / given;
    if (std::filesystem::exists(candidate)) return candidate.string();
    looked += (looked.empty() ? "" : " and ") + candidate.string();
  }
  fail(key, "'" + given.string() + "' does not exist (looked for " + looked + ")",
       places.size() > 1 ? "the file in the output folder (e.g. written there by breccia-place -o) or next to the case file"
                         : "the file next to the case file (a relative path is relative to the case file)");
}

}  // namespace breccia
