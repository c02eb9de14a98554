#pragma once
// Helpers of the tests that run breccia-solve and breccia-post on a real case and read
// post.json: run both tools in a scratch folder, and pick numbers out of the JSON.
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>

namespace breccia::postproc::testing {

inline std::string read_text(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The number after the first "key": at or after `from` (NaN when absent).
inline double json_number(const std::string& json, const std::string& key, const std::string& from = "") {
  const size_t start = from.empty() ? 0 : json.find(from);
  const size_t at = json.find("\"" + key + "\": ", start == std::string::npos ? 0 : start);
  if (at == std::string::npos) return NAN;
  return std::strtod(json.c_str() + at + key.size() + 4, nullptr);
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
