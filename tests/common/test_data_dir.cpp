// data_dir.hpp: the tools' run-time files are found beside the running executable's bin/,
// with environment overrides. The build tree must offer the same share/breccia as an install
// (cmake/BrecciaInstall.cmake links it to the sources), or every tool run from build/bin loses
// its chart scripts and planner data; scripts/check-package.sh checks the installed side.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "breccia/common/data_dir.hpp"

namespace fs = std::filesystem;
using namespace breccia;

namespace {
// Sets (or, with nullptr, unsets) a variable for one scope and restores what was there.
class ScopedEnv {
public:
  ScopedEnv(const char* name, const char* value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old, had_ = true;
    value ? setenv(name, value, 1) : unsetenv(name);
  }
  ~ScopedEnv() { had_ ? setenv(name_, old_.c_str(), 1) : unsetenv(name_); }

private:
  const char* name_;
  std::string old_;
  bool had_ = false;
};
}  // namespace

TEST(DataDir, IsShareBrecciaBesideTheExecutablesBinAndHoldsWhatTheToolsRead) {
  const ScopedEnv none("BRECCIA_DATA_DIR", nullptr);
  const fs::path exe = fs::read_symlink("/proc/self/exe");
  EXPECT_EQ(data_dir(), exe.parent_path().parent_path() / "share" / "breccia");
  // This test runs from build/bin: the build tree's share/breccia must hold the installed names.
  for (const char* f : {"plan/throughputs.yaml", "plan/atlas.csv", "postproc/scripts/plot_energy.py",
                        "cases/concrete-blast/run.sh", "scripts/case_env.sh"})
    EXPECT_TRUE(fs::is_regular_file(data_dir() / f)) << data_dir() / f;
}

TEST(DataDir, EnvironmentOverridesTheFolderAndSingleFilesButNotWhenEmpty) {
  const ScopedEnv none("BRECCIA_DATA_DIR", nullptr);
  const fs::path beside = data_dir();
  {
    const ScopedEnv dir("BRECCIA_DATA_DIR", "/opt/breccia-data");
    EXPECT_EQ(data_dir(), fs::path("/opt/breccia-data"));
    EXPECT_EQ(data_path("BRECCIA_TEST_NO_SUCH_VARIABLE", "plan/atlas.csv"), fs::path("/opt/breccia-data/plan/atlas.csv"));
    const ScopedEnv file("BRECCIA_TEST_ATLAS", "/tmp/my-atlas.csv");
    EXPECT_EQ(data_path("BRECCIA_TEST_ATLAS", "plan/atlas.csv"), fs::path("/tmp/my-atlas.csv"));
  }
  const ScopedEnv empty("BRECCIA_DATA_DIR", "");  // an empty value is "not set", not the working directory
  EXPECT_EQ(data_dir(), beside);
  EXPECT_EQ(data_path(nullptr, "plan/atlas.csv"), beside / "plan" / "atlas.csv");
}
