// breccia-atlas --backends cuda: the time-stepping problems on the GPU beside the CPU. Without
// a device the option is refused as bad input naming it, before anything is written; with one,
// a GPU row must carry the same error as its CPU row (the same kernels, rounding alike:
// docs/cuda.md) and say `cuda` in the backend column.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "breccia/solver/cuda_device.hpp"
#include "cli_command.hpp"

namespace {

struct Command {
  int exit_code;
  std::string output;
};

Command run_atlas(const std::string& args, const std::string& dir) {
  std::filesystem::create_directories(dir);
  const std::string log = dir + "/atlas.log";
  const std::string cmd = breccia::cuda_test::cli_command("BRECCIA_ATLAS_EXE", BRECCIA_ATLAS_EXE) + " " + args + " > " + log + " 2>&1";
  const int status = std::system(cmd.c_str());
  std::ifstream in(log);
  std::stringstream text;
  text << in.rdbuf();
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, text.str()};
}

// The smallest sweep: wave speed bar, PMB, lattice, m = 3, the two quick spacings.
std::string quick_args(const std::string& dir, const std::string& backends) {
  return "--quick --no-stability --problems wave_speed_bar --models pmb --kinds lattice --m 3 --threads 2 --backends " +
         backends + " --work " + dir + "/work --csv " + dir + "/atlas.csv";
}

}  // namespace

TEST(AtlasBackends, CudaWithoutADeviceIsBadInputNamingTheOptionAndWritesNoTable) {
  if (breccia::solver::cuda_device_available()) GTEST_SKIP() << "a CUDA device is present; this checks the no-device path";
  const std::string dir = ::testing::TempDir() + "/atlas_backends_no_device";
  std::filesystem::remove_all(dir);
  const Command c = run_atlas(quick_args(dir, "cpu,cuda"), dir);
  EXPECT_EQ(c.exit_code, 2) << c.output;
  EXPECT_NE(c.output.find("--backends"), std::string::npos) << c.output;
  EXPECT_NE(c.output.find("no CUDA device"), std::string::npos) << c.output;
  EXPECT_FALSE(std::filesystem::exists(dir + "/atlas.csv"));
}

TEST(AtlasBackends, UnknownBackendIsBadInputNamingTheChoices) {
  const std::string dir = ::testing::TempDir() + "/atlas_backends_unknown";
  std::filesystem::remove_all(dir);
  const Command c = run_atlas(quick_args(dir, "cpu,tpu"), dir);
  EXPECT_EQ(c.exit_code, 2) << c.output;
  EXPECT_NE(c.output.find("cpu, cuda"), std::string::npos) << c.output;
}

// With a GPU: one CPU and one GPU row per spacing, equal errors (1e-9 relative: the modal
// zero crossing is interpolated from the same displacements).
TEST(AtlasBackends, GpuRowsCarryTheCpuRowsErrors) {
  if (!breccia::solver::cuda_device_available()) GTEST_SKIP() << "no CUDA device: the GPU rows need an NVIDIA GPU and driver";
  const std::string dir = ::testing::TempDir() + "/atlas_backends_gpu";
  std::filesystem::remove_all(dir);
  const Command c = run_atlas(quick_args(dir, "cpu,cuda"), dir);
  ASSERT_EQ(c.exit_code, 0) << c.output;
  std::ifstream in(dir + "/atlas.csv");
  std::string line;
  std::getline(in, line);  // header
  std::map<std::string, std::map<std::string, double>> error;  // spacing -> backend -> error
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    std::stringstream cells(line);
    for (std::string cell; std::getline(cells, cell, ',');) f.push_back(cell);
    ASSERT_GE(f.size(), 14u) << line;
    error[f[5]][f[7]] = std::stod(f[13]);
  }
  ASSERT_EQ(error.size(), 2u) << "two quick spacings";
  for (const auto& [spacing, by_backend] : error) {
    ASSERT_EQ(by_backend.count("cpu"), 1u) << spacing;
    ASSERT_EQ(by_backend.count("cuda"), 1u) << spacing;
    EXPECT_NEAR(by_backend.at("cuda"), by_backend.at("cpu"), 1e-9 * by_backend.at("cpu")) << "spacing " << spacing;
  }
}
