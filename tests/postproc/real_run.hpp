#pragma once
// Helpers of the tests that run breccia-solve and breccia-post on a real case and read
// post.json: run both tools in a scratch folder, and pick numbers out of the JSON.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

namespace breccia::postproc::testing {

inline std::string read_text(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The first number under "key" in document order, within the first object named `from`
// (quoted, as "\"cracks\"") when given; NaN when absent or null. The text is parsed strictly
// first, so a file that is not JSON (NaN tokens, bad escapes) fails the test that reads it.
inline double json_number(const std::string& json, const std::string& key, const std::string& from = "") {
  std::function<const nlohmann::ordered_json*(const nlohmann::ordered_json&, const std::string&)> first;
  first = [&](const nlohmann::ordered_json& j, const std::string& name) -> const nlohmann::ordered_json* {
    if (j.is_object())
      for (const auto& [k, v] : j.items()) {
        if (k == name) return &v;
        if (const auto* found = first(v, name)) return found;
      }
    if (j.is_array())
      for (const auto& v : j)
        if (const auto* found = first(v, name)) return found;
    return nullptr;
  };
  nlohmann::ordered_json doc;
  EXPECT_NO_THROW(doc = nlohmann::ordered_json::parse(json)) << json;
  const nlohmann::ordered_json* scope = &doc;
  if (!from.empty()) {
    scope = first(doc, from.size() > 2 && from.front() == '"' ? from.substr(1, from.size() - 2) : from);
    if (!scope) return NAN;
  }
  const auto* v = first(*scope, key);
  return v && v->is_number() ? v->get<double>() : NAN;
}

// The ratio of harmonic `order` in the first spectrum of post.json (NaN when absent).
inline double first_spectrum_harmonic_ratio(const std::string& json, int order) {
  nlohmann::ordered_json doc;
  EXPECT_NO_THROW(doc = nlohmann::ordered_json::parse(json)) << json;
  if (!doc.contains("spectra") || doc["spectra"].empty()) return NAN;
  for (const auto& h : doc["spectra"][0].value("harmonics", nlohmann::ordered_json::array()))
    if (h.value("order", -1) == order && h["ratio"].is_number()) return h["ratio"].get<double>();
  return NAN;
}

// In a fresh scratch folder `tag`_<pid>: `prepare(dir)` writes case.yaml (and whatever it
// needs), then breccia-solve and breccia-post --no-plots run on it. Returns post.json, or an
// empty string when either tool failed (their logs stay in the folder then).
inline std::string solve_and_post(const std::string& tag, const std::function<void(const std::filesystem::path&)>& prepare) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / (tag + "_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  prepare(dir);
  auto quoted = [](const fs::path& p) { return "'" + p.string() + "'"; };
  auto run = [](const std::string& cmd) {
    const int status = std::system(cmd.c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  };
  if (run(quoted(BRECCIA_SOLVE_EXE) + " " + quoted(dir / "case.yaml") + " -o " + quoted(dir / "run") + " --quiet > " +
          quoted(dir / "solve.log") + " 2>&1") != 0)
    return std::string();
  if (run(quoted(BRECCIA_POST_EXE) + " " + quoted(dir / "run") + " --no-plots --quiet > " + quoted(dir / "post.log") +
          " 2>&1") != 0)
    return std::string();
  std::string out = read_text(dir / "run" / "post" / "post.json");
  fs::remove_all(dir);
  return out;
}

}  // namespace breccia::postproc::testing
