#include "breccia/common/data_dir.hpp"

#include <cstdlib>
#include <system_error>

namespace breccia {
namespace fs = std::filesystem;

fs::path executable_prefix() {
  std::error_code ec;
  // The kernel's link names the executable's real path (symbolic links resolved), so a
  // /usr/local/bin link to <prefix>/bin/breccia-solve still finds <prefix>/share/breccia.
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec || exe.empty()) return {};
  return exe.parent_path().parent_path();
}

fs::path data_dir() {
  if (const char* env = std::getenv("BRECCIA_DATA_DIR"); env && *env) return env;
  return executable_prefix() / "share" / "breccia";
}

fs::path data_path(const char* env_override, std::string_view relative) {
  if (env_override) {
    if (const char* env = std::getenv(env_override); env && *env) return env;
  }
  return data_dir() / fs::path(relative);
}

}  // namespace breccia
