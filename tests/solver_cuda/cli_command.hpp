#pragma once
// The command line that starts a CLI from a test. The build's path is compiled in, but the GPU
// kit (scripts/device-check.sh prepare) carries the binaries to another machine and folder, so
// an environment variable of the same name (e.g. BRECCIA_ATLAS_EXE) overrides it there; it may
// hold a prefix too (a loader and its --library-path) since the command goes through the shell.
#include <cstdlib>
#include <string>

namespace breccia::cuda_test {

inline std::string cli_command(const char* variable, const char* built_path) {
  const char* set = std::getenv(variable);
  return (set && *set) ? set : built_path;
}

}  // namespace breccia::cuda_test
