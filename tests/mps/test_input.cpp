// Bad input is an InputError naming the field (library), and exit code 2 with
// "error: <file>: <field>: ..." from the CLI.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "../common/cli_contract.hpp"
#include "breccia/common/error.hpp"
#include "breccia/common/json_file.hpp"
#include "breccia/common/particle_file.hpp"
#include "breccia/mps/case_spec.hpp"
#include "breccia/mps/simulation.hpp"
#include "mps_test_util.hpp"

using namespace breccia::mps;

namespace {

const std::string kGood = R"(
specimen:
  lattice: {dimension: 2, box: [0, 0, 10 mm, 10 mm], spacing: 0.5 mm}
model: {type: mps, equation: navier}
materials:
  - {name: steel, density: 7850, C13: 121.1 GPa, C55: 80.8 GPa}
cracks:
  - {name: c, segment: [[4 mm, 5 mm], [6 mm, 5 mm]], static_friction: 0.6, kinetic_friction: 0.5, normal_stress: 1 MPa}
time: {end: 1 us}
)";

std::string replaced(const std::string& from, const std::string& to) { return test::replace_once(kGood, from, to); }

// The message of the InputError thrown while parsing and building the case ("" if none).
std::string error_of(const std::string& yaml) {
  return test::input_error_of([&] { Simulation sim(parse_case_text(yaml, "case.yaml")); });
}

}  // namespace

TEST(MpsInput, GoodCaseBuilds) { EXPECT_EQ(error_of(kGood), ""); }

TEST(MpsInput, CrackOutsideTheBodyIsRejected) {
  const auto msg = error_of(replaced("[[4 mm, 5 mm], [6 mm, 5 mm]]", "[[14 mm, 5 mm], [16 mm, 5 mm]]"));
  EXPECT_NE(msg.find("cracks[0].segment"), std::string::npos) << msg;
  EXPECT_NE(msg.find("outside"), std::string::npos) << msg;
}

TEST(MpsInput, CrackThroughParticleCentresIsRejected) {
  const auto msg = error_of(replaced("[[4 mm, 5 mm], [6 mm, 5 mm]]", "[[4 mm, 5.25 mm], [6 mm, 5.25 mm]]"));
  EXPECT_NE(msg.find("particle centres"), std::string::npos) << msg;
}

TEST(MpsInput, NegativeFrictionCoefficientsAreRejected) {
  auto msg = error_of(replaced("static_friction: 0.6", "static_friction: -0.1"));
  EXPECT_NE(msg.find("static_friction"), std::string::npos) << msg;
  msg = error_of(replaced("kinetic_friction: 0.5", "kinetic_friction: -0.5"));
  EXPECT_NE(msg.find("kinetic_friction"), std::string::npos) << msg;
}

TEST(MpsInput, KineticFrictionAboveStaticIsRejected) {
  const auto msg = error_of(replaced("kinetic_friction: 0.5", "kinetic_friction: 0.7"));
  EXPECT_NE(msg.find("kinetic_friction"), std::string::npos) << msg;
  EXPECT_NE(msg.find("kinetic friction <= static friction"), std::string::npos) << msg;
}

TEST(MpsInput, NonPositiveModuliAndDensityAreRejected) {
  auto msg = error_of(replaced("density: 7850", "density: 0"));
  EXPECT_NE(msg.find("materials[0].density"), std::string::npos) << msg;
  msg = error_of(replaced("C55: 80.8 GPa", "C55: -80.8 GPa"));
  EXPECT_NE(msg.find("C55"), std::string::npos) << msg;
  msg = error_of(replaced("C13: 121.1 GPa, C55: 80.8 GPa", "youngs_modulus: 0, poisson_ratio: 0.3"));
  EXPECT_NE(msg.find("youngs_modulus"), std::string::npos) << msg;
}

TEST(MpsInput, UnknownKeysAreRejectedNamingTheAllowedOnes) {
  auto msg = error_of(replaced("model: {type: mps, equation: navier}", "model: {type: mps, equation: navier, viscosity: 1}"));
  EXPECT_NE(msg.find("viscosity"), std::string::npos) << msg;
  EXPECT_NE(msg.find("re_over_spacing"), std::string::npos) << msg;  // allowed keys listed
  msg = error_of(replaced("normal_stress: 1 MPa", "normal_stres: 1 MPa"));
  EXPECT_NE(msg.find("normal_stres"), std::string::npos) << msg;
  msg = error_of(kGood + "loads: []\n");
  EXPECT_NE(msg.find("loads"), std::string::npos) << msg;
}

TEST(MpsInput, UnknownEquationNamesTheChoices) {
  const auto msg = error_of(replaced("equation: navier", "equation: euler"));
  EXPECT_NE(msg.find("rotation_free"), std::string::npos) << msg;
}

namespace {

// breccia-mps on `case_file` with -o `out`: its exit code (-1: did not exit) and its stderr,
// kept in `dir`/stderr.txt.
struct MpsCliRun {
  int exit_code = -1;
  std::string err;
};
MpsCliRun run_mps_cli(const std::filesystem::path& case_file, const std::filesystem::path& out,
                      const std::filesystem::path& dir) {
  const std::string cmd = std::string(BRECCIA_MPS_EXE) + " " + case_file.string() + " -o " + out.string() + " 2> " +
                          (dir / "stderr.txt").string();
  const int status = std::system(cmd.c_str());
  std::ifstream err(dir / "stderr.txt");
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1,
          std::string((std::istreambuf_iterator<char>(err)), std::istreambuf_iterator<char>())};
}

}  // namespace

TEST(MpsCli, BadInputExitsWithCode2AndNamesTheField) {
  const auto dir = std::filesystem::temp_directory_path() / "breccia_mps_cli_test";
  std::filesystem::create_directories(dir);
  const auto case_file = dir / "bad.yaml";
  std::ofstream(case_file) << replaced("kinetic_friction: 0.5", "kinetic_friction: 0.9");
  const MpsCliRun r = run_mps_cli(case_file, dir / "out", dir);
  EXPECT_EQ(r.exit_code, breccia::kExitBadInput);
  const std::string& text = r.err;
  EXPECT_EQ(text.rfind("error: ", 0), 0u) << text;
  EXPECT_NE(text.find("cracks[0].kinetic_friction"), std::string::npos) << text;
  EXPECT_FALSE(std::filesystem::exists(dir / "out" / "results.h5"));
}

// An output folder that cannot be made (a file stands where it should be) is a usage error
// naming -o, found before the run (it was a failure, exit 3).
TEST(MpsCli, OutputFolderThatCannotBeMadeIsBadInputNamingTheOption) {
  const auto dir = std::filesystem::temp_directory_path() / "breccia_mps_cli_out_test";
  std::filesystem::create_directories(dir);
  const auto case_file = dir / "good.yaml";
  std::ofstream(case_file) << kGood;
  const auto blocker = dir / "blocker";
  std::ofstream(blocker) << "a file, not a folder\n";
  const MpsCliRun r = run_mps_cli(case_file, blocker / "out", dir);
  EXPECT_EQ(r.exit_code, breccia::kExitBadInput);
  EXPECT_NE(r.err.find("error: command line: -o: '" + (blocker / "out").string() + "' not writable"), std::string::npos)
      << r.err;
}

// --help, --version, and usage errors (exit 2 naming the option): the tools' shared contract.
TEST(MpsCli, FollowsTheToolsCommandLineContract) {
  breccia::testing::expect_cli_contract(BRECCIA_MPS_EXE, "breccia-mps", "case.yaml -o out",
                                        {{"--threads", "4x"}, {"--threads", "-1"}, {"--threads", "0"}});
}

TEST(MpsCli, RunWritesHistorySummaryAndResults) {
  const auto dir = std::filesystem::temp_directory_path() / "breccia_mps_cli_run";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const auto case_file = dir / "case.yaml";
  std::ofstream(case_file) << kGood << "output: {every: 10, progress: false, probes: [{name: A, position: [5 mm, 2 mm], field: velocity_x}]}\n"
                           << "boundary: [{face: top, components: [x], displacement: {amplitude: 1.0e-8, period: 0.5 us, cycles: 1}}]\n";
  const std::string cmd = std::string(BRECCIA_MPS_EXE) + " " + case_file.string() + " -o " + (dir / "out").string() +
                          " --threads 1 2> " + (dir / "stderr.txt").string();
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  EXPECT_TRUE(std::filesystem::exists(dir / "out" / "results.h5"));
  std::ifstream hist(dir / "out" / "history.csv");
  std::string header;
  std::getline(hist, header);
  EXPECT_EQ(header.rfind("time_s,A_velocity_x", 0), 0u) << header;
  // A strict parse (escaped strings, no NaN tokens), then the keys.
  const breccia::Json summary = breccia::read_json_file(dir / "out" / "summary.json");
  EXPECT_TRUE(summary.contains("steps"));
  EXPECT_TRUE(summary.at("dt_s").is_number());
  EXPECT_TRUE(summary.at("wall_time_s").is_number());
  EXPECT_EQ(summary.at("particles"), 400) << summary;  // 20 x 20 lattice
  EXPECT_EQ(summary.at("case_file"), (dir / "case.yaml").string());
}

// breccia-mps takes a case's variants and --set as breccia-solve does (--set after the
// variant): the run's end time is what the two made of the file's 1 us.
TEST(MpsCli, VariantAndSetChangeTheCaseForThisRun) {
  const auto dir = std::filesystem::temp_directory_path() / "breccia_mps_cli_variant";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const auto case_file = dir / "case.yaml";
  std::ofstream(case_file) << kGood << "output: {every: 1000, progress: false}\n"
                           << "variants: {short: {time.end: 0.25 us}, shorter: {time.end: 0.1 us}}\n";
  // The run ends at the first whole step at or past the end time: within one step of it.
  const auto expect_end = [&](const std::string& options, double end) {
    const std::string cmd = std::string(BRECCIA_MPS_EXE) + " " + case_file.string() + " -o " + (dir / "out").string() +
                            " --threads 1 " + options + " 2> " + (dir / "stderr.txt").string();
    ASSERT_EQ(std::system(cmd.c_str()), 0) << options;
    const breccia::Json summary = breccia::read_json_file(dir / "out" / "summary.json");
    const double t = summary.at("end_time_s").get<double>(), dt = summary.at("dt_s").get<double>();
    EXPECT_GE(t, end * (1 - 1e-9)) << options;
    EXPECT_LT(t, end + dt) << options;
  };
  expect_end("", 1e-6);
  expect_end("--variant short", 0.25e-6);
  expect_end("--variant short --set 'time.end=0.1 us'", 0.1e-6);
  const std::string bad = std::string(BRECCIA_MPS_EXE) + " " + case_file.string() + " -o " + (dir / "bad").string() +
                          " --variant long 2> " + (dir / "stderr.txt").string();
  const int status = std::system(bad.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), breccia::kExitBadInput);
}

TEST(MpsParticleFile, SpecimenFromParticlesH5MatchesTheEquivalentLattice) {
  // The same square lattice given as particles.h5 (with a named set for the driven face)
  // and as a lattice block must give the same particles, bonds and probe history.
  const auto dir = std::filesystem::temp_directory_path() / "breccia_mps_particles";
  std::filesystem::create_directories(dir);
  breccia::ParticleModel m;
  m.dimension = 2;
  m.thickness_m = 1e-3;
  const int nx = 16, ny = 24;
  const double h = 0.5e-3;
  breccia::ParticleSet top{"top_face", {}};
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      m.position_m.insert(m.position_m.end(), {(i + 0.5) * h, (j + 0.5) * h, 0.0});
      m.volume_m3.push_back(h * h * m.thickness_m);
      m.spacing_m.push_back(h);
      m.material_id.push_back(0);
      if (j == ny - 1) top.indices.push_back(static_cast<int64_t>(j) * nx + i);
    }
  m.material_names = {"steel"};
  m.sets = {top};
  m.source = "test lattice";
  breccia::write_particle_file((dir / "particles.h5").string(), m);

  const std::string tail = R"(
model: {type: mps}
materials:
  - {name: steel, density: 7850, C13: 121.1 GPa, C55: 80.8 GPa}
time: {end: 2 us}
)";
  std::ofstream(dir / "from_file.yaml") << "specimen: {particles: particles.h5}\n" << tail
                                        << "boundary: [{set: top_face, components: [x], displacement: {amplitude: 1.0e-8, period: 1 us, cycles: 1}}]\n";
  const CaseSpec from_file = load_case((dir / "from_file.yaml").string());
  const CaseSpec from_lattice = parse_case_text(
      "specimen: {lattice: {dimension: 2, box: [0, 0, 8 mm, 12 mm], spacing: 0.5 mm, thickness: 1 mm}}\n" + tail +
      "boundary: [{face: top, components: [x], displacement: {amplitude: 1.0e-8, period: 1 us, cycles: 1}}]\n");
  Simulation a(from_file), b(from_lattice);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(a.bonds().size(), b.bonds().size());
  const auto ta = test::run_and_record(a, {4e-3, 8e-3, 0}, "velocity_x");
  const auto tb = test::run_and_record(b, {4e-3, 8e-3, 0}, "velocity_x");
  ASSERT_EQ(ta.value.size(), tb.value.size());
  double peak = 0.0;
  for (double v : tb.value) peak = std::max(peak, std::abs(v));
  EXPECT_GT(peak, 0.0);
  for (size_t k = 0; k < ta.value.size(); ++k) EXPECT_NEAR(ta.value[k], tb.value[k], 1e-12 * peak);  // same arithmetic
}

// A case refused once built (here an end time of 10^13 steps, a unit slip that overflowed the
// step count to a run of no step, exit 0) leaves the folder's earlier case_as_run.yaml: it
// was written before the case was built, so the folder named a case that never ran.
TEST(MpsCli, ACaseRefusedOnceBuiltLeavesTheEarlierRunsFilesInPlace) {
  const auto dir = std::filesystem::temp_directory_path() / "breccia_mps_cli_keep";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const auto good = dir / "good.yaml", slip = dir / "slip.yaml";
  std::ofstream(good) << kGood << "output: {progress: false}\n";
  std::ofstream(slip) << replaced("time: {end: 1 us}", "time: {end: 1e7 s}") << "output: {progress: false}\n";
  ASSERT_EQ(run_mps_cli(good, dir / "out", dir).exit_code, 0);
  const auto read = [](const std::filesystem::path& p) {
    std::ifstream in(p);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  };
  const std::string before = read(dir / "out" / "case_as_run.yaml");
  ASSERT_NE(before.find("end: 1 us"), std::string::npos) << before;
  const MpsCliRun r = run_mps_cli(slip, dir / "out", dir);
  EXPECT_EQ(r.exit_code, breccia::kExitBadInput) << r.err;
  EXPECT_NE(r.err.find("time.end"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("10^12 steps"), std::string::npos) << r.err;
  EXPECT_EQ(read(dir / "out" / "case_as_run.yaml"), before);
}
