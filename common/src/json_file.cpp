#include "breccia/common/json_file.hpp"

#include <cmath>
#include <fstream>

#include "breccia/common/error.hpp"
#include "breccia/common/output_file.hpp"

namespace breccia {

Json json_number(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }

void set_json_number(Json& j, const std::string& key, double v, std::vector<std::string>* non_finite) {
  j[key] = json_number(v);
  if (!std::isfinite(v) && non_finite) non_finite->push_back(key);
}

std::string json_text(const Json& j) { return j.dump(2, ' ', false, Json::error_handler_t::replace) + "\n"; }

void write_json_file(const std::filesystem::path& path, const Json& j) { write_text_file(path, json_text(j)); }

Json read_json_file(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path.string(), "", "cannot be opened", "a JSON file");
  try {
    return Json::parse(in);
  } catch (const Json::parse_error& e) {
    throw InputError(path.string(), "", e.what(), "valid JSON");
  }
}

}  // namespace breccia
