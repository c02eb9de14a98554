#pragma once
// Where the tools find the files they read at run time (the planner's measured rates and
// atlas, the post-processor's chart scripts): <prefix>/share/breccia beside the <prefix>/bin
// that holds the running executable. An install (`cmake --install`), an unpacked .deb and the
// build tree all look the same from there - CMake gives the build tree a share/breccia of links
// into the source tree (cmake/BrecciaInstall.cmake) - so no source path is compiled in and a
// moved prefix keeps working.
#include <filesystem>
#include <string_view>

namespace breccia {

// $BRECCIA_DATA_DIR when set and not empty, else <folder of the running executable>/../share/breccia.
std::filesystem::path data_dir();

// The value of the environment variable `env_override` when set and not empty (a per-file
// override, e.g. BRECCIA_PLAN_ATLAS), else `relative` under data_dir().
std::filesystem::path data_path(const char* env_override, std::string_view relative);

// The executable's own folder's parent, the prefix (/proc/self/exe: Linux); data_dir()'s base.
// Empty when the executable cannot be located, so data_dir() falls back to "share/breccia"
// relative to the working directory and the caller's error names that path.
std::filesystem::path executable_prefix();

}  // namespace breccia
