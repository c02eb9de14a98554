// breccia-solve turns bad input into one clear message and exit code 2.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <csignal>
#include <filesystem>
#include <iterator>
#include <sys/wait.h>
#include <unistd.h>
#include <cstdio>
#include <fstream>
#include <string>
#include "helpers.hpp"
#include "../common/cli_contract.hpp"
#include "breccia/common/h5.hpp"
#include "breccia/common/particle_file.hpp"
#include "breccia/solver/results_layout.hpp"
#include "atlas.hpp"

#include <sstream>

#include <nlohmann/json.hpp>

namespace {

struct Outcome {
  int exit_code;
  std::string output;
};

// `quiet`: --quiet (no notes); the run writes into process_temp_dir()/cli_NAME/out.
Outcome run_solver(const std::string& case_yaml, const std::string& name, const std::string& extra = "",
                   bool quiet = true) {
  const std::string dir = breccia::solver::testing::process_temp_dir() + "/cli_" + name;
  std::string mk = "mkdir -p " + dir;
  if (std::system(mk.c_str()) != 0) return {-1, ""};
  const std::string file = dir + "/case.yaml";
  std::ofstream(file) << case_yaml;
  const std::string cmd =
      std::string(BRECCIA_SOLVE_EXE) + " " + file + " -o " + dir + "/out" + (quiet ? " --quiet " : " ") + extra + " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  std::string out;
  std::array<char, 512> buf{};
  while (fgets(buf.data(), buf.size(), p)) out += buf.data();
  const int status = pclose(p);
  return {WEXITSTATUS(status), out};
}

const std::string kBase =
    "specimen: {lattice: {dimension: 2, box: [0, 0, 0.01, 0.01], spacing: 1 mm, thickness: 1 mm}}\n"
    "model: {type: pmb, planar: plane_strain}\n";
const std::string kMaterial = "materials: [{name: m, density: 2000, youngs_modulus: 10 GPa, poisson_ratio: 0.25}]\n";
const std::string kTime = "time: {steps: 5}\n";

void expect_bad_input(const Outcome& o, const std::vector<std::string>& fragments) {
  EXPECT_EQ(o.exit_code, 2) << o.output;
  for (const auto& f : fragments) EXPECT_NE(o.output.find(f), std::string::npos) << "missing '" << f << "' in: " << o.output;
}

}  // namespace

TEST(SolverCli, UnknownSetIsNamedWithTheAvailableOnes) {
  expect_bad_input(run_solver(kBase + kMaterial + kTime + "boundary: [{type: fixed, set: bottom}]\n", "unknown_set"),
                   {"case.yaml", "boundary[0].set", "bottom", "xmin"});
}

// A bad expression, a name the expression may not use, and a repeated key: each one message
// naming the file and the key (and the position in the expression), exit 2.
TEST(SolverCli, BadExpressionUnknownVariableAndDuplicateKeyExitWith2) {
  expect_bad_input(run_solver(kBase + kMaterial + kTime +
                                  "initial: [{type: velocity, expression: [\"10 * (x +\", \"0\"]}]\n",
                              "bad_expression"),
                   {"case.yaml", "initial[0].expression[0]", "position"});
  expect_bad_input(run_solver(kBase + kMaterial + kTime +
                                  "boundary: [{type: velocity, set: xmin, expression: [\"0\", \"r * t\"]}]\n",
                              "unknown_variable"),
                   {"case.yaml", "boundary[0].expression[1]", "position 1"});
  expect_bad_input(run_solver(kBase + kMaterial + kTime + "time: {steps: 6}\n", "duplicate_key"),
                   {"case.yaml", "time", "line"});
}

TEST(SolverCli, NegativeModulusIsRejected) {
  expect_bad_input(
      run_solver(kBase + "materials: [{name: m, density: 2000, youngs_modulus: -1 GPa, poisson_ratio: 0.25}]\n" + kTime,
                 "negative_modulus"),
      {"materials[0].youngs_modulus", "positive"});
}

TEST(SolverCli, TimeStepAboveStableIsRejected) {
  expect_bad_input(run_solver(kBase + kMaterial + "time: {steps: 5, dt: 1 ms}\n", "big_dt"), {"time.dt", "stable"});
  // Both steps in significant digits (std::to_string printed the 0.84 us stable step as
  // 0.000001 s, and smaller ones as 0.000000 s).
  const Outcome o = run_solver(kBase + kMaterial + "time: {steps: 5, dt: 1 us}\n", "small_big_dt");
  expect_bad_input(o, {"dt = 1e-06 s exceeds the stable step 8.4"});
  EXPECT_EQ(o.output.find("0.000000"), std::string::npos) << o.output;
}

// An output folder that cannot be made is bad input named by its option, found before the
// set-up (it ended in an uncaught filesystem error and an abort after it): here a file sits
// where the folder should be (a path root cannot write either, unlike a read-only mode).
TEST(SolverCli, OutputFolderThatCannotBeMadeIsBadInputNamingTheOption) {
  const std::string dir = breccia::solver::testing::process_temp_dir() + "/cli_unwritable_out";
  std::filesystem::create_directories(dir);
  std::filesystem::remove_all(dir + "/out");
  std::ofstream(dir + "/out") << "a file, not a folder\n";
  const Outcome o = run_solver(kBase + kMaterial + kTime, "unwritable_out");
  expect_bad_input(o, {"error: command line: -o: '" + dir + "/out' not writable", "a folder this user can write"});
  EXPECT_EQ(o.output.find("terminate called"), std::string::npos) << o.output;
}

TEST(SolverCli, MalformedNumbersOnTheCommandLineAreRejected) {
  const std::string dir = breccia::solver::testing::process_temp_dir() + "/cli_threads";
  std::filesystem::create_directories(dir);
  std::ofstream(dir + "/case.yaml") << kBase + kMaterial + kTime;
  for (const char* bad : {"--threads 4x", "--steps 10s", "--threads two"}) {
    const std::string cmd = std::string(BRECCIA_SOLVE_EXE) + " " + dir + "/case.yaml -o " + dir + "/out --quiet " + bad + " 2>&1";
    FILE* p = popen(cmd.c_str(), "r");
    std::string out;
    std::array<char, 512> buf{};
    while (fgets(buf.data(), buf.size(), p)) out += buf.data();
    const int status = pclose(p);
    EXPECT_EQ(WEXITSTATUS(status), 2) << bad << ": " << out;
    EXPECT_NE(out.find("is not a number"), std::string::npos) << bad << ": " << out;
  }
}

// --help, --version, and usage errors (exit 2 naming the option): the tools' shared contract.
TEST(SolverCli, FollowsTheToolsCommandLineContract) {
  breccia::testing::expect_cli_contract(
      BRECCIA_SOLVE_EXE, "breccia-solve", "case.yaml -o out --quiet",
      {{"--threads", "4x"}, {"--threads", "-1"}, {"--steps", "10s"}, {"--steps", "-3"}, {"--kernel-times", "-3"},
       {"--kernel-times", "ten"}});
}

// --kernel-times on a run whose loop is on the CPU: a note says nothing is timed, the run
// completes as without it, and summary.json carries no kernel_times (a GPU run's table:
// test_solver_cuda, CudaBackend.RunLoopReportsKernelTimesWhenAsked).
TEST(SolverCli, KernelTimesOnTheCpuSayNothingIsTimed) {
  const Outcome o = run_solver(kBase + kMaterial + kTime, "kernel_times", "--backend cpu --kernel-times 2", false);
  ASSERT_EQ(o.exit_code, 0) << o.output;
  EXPECT_NE(o.output.find("--kernel-times: the time loop runs on the CPU"), std::string::npos) << o.output;
  std::ifstream summary(breccia::solver::testing::process_temp_dir() + "/cli_kernel_times/out/summary.json");
  const nlohmann::json j = nlohmann::json::parse(summary);
  EXPECT_EQ(j.at("steps_this_run"), 5);
  EXPECT_FALSE(j.contains("kernel_times"));
}

#ifdef BRECCIA_ATLAS_EXE
// breccia-atlas: the same contract; a list of numbers is checked item by item. Usage errors
// stop it before any sweep starts.
TEST(AtlasCli, FollowsTheToolsCommandLineContract) {
  const std::string dir = breccia::solver::testing::process_temp_dir() + "/cli_atlas";
  breccia::testing::expect_cli_contract(
      BRECCIA_ATLAS_EXE, "breccia-atlas", "--quick --no-stability --work " + dir + " --csv " + dir + "/atlas.csv",
      // --m at or below 0 skipped every point and left an atlas.csv of its header alone, exit 0;
      // --gradings at or below 0 never ended the graded strip's particle loop.
      {{"--threads", "4x"}, {"--threads", "-1"}, {"--m", "3,x"}, {"--gradings", "2,4y"}, {"--m", "-1"}, {"--m", "3,0"},
       {"--gradings", "0"}, {"--gradings", "-1"}});
  EXPECT_FALSE(std::filesystem::exists(dir + "/atlas.csv"));
}
#endif

// The atlas's tables record each run's message; the sweeps name their work folder by its
// absolute path, and a committed table must not carry the path of the machine that made it.
// So every occurrence of the working folder's prefix is cut, a path elsewhere is kept, and
// the message stays one CSV field (its commas and line breaks replaced).
TEST(AtlasTables, RunMessageLosesTheWorkingFolderPrefixAndStaysOneCsvField) {
  const std::string here = std::filesystem::current_path().string() + "/";
  const std::string message = "breccia-mesh failed on " + here + "atlas_work/a.msh, see\n" +
                              here + "atlas_work/a.log; /elsewhere/b.log kept";
  EXPECT_EQ(breccia::atlas::message_field(message),
            "breccia-mesh failed on atlas_work/a.msh; see atlas_work/a.log; /elsewhere/b.log kept");
  EXPECT_EQ(breccia::atlas::message_field("line one\nline two, \"quoted\""),
            "line one line two;  quoted ");
  EXPECT_EQ(breccia::atlas::message_field(""), "");
}

// --set KEY=VALUE overrides a value of the case file for this run (the variants of a case
// without editing it): the step count, a material's modulus, an initial velocity (its
// kinetic energy 0.5 m v^2 checks that the list value arrived), in the history's first row.
TEST(SolverCli, SetOverridesValuesOfTheCaseFile) {
  const std::string yaml = kBase + kMaterial + "initial: [{type: velocity, value: [1, 0, 0]}]\n" + kTime +
                           "output: {every: 1000, history_every: 1}\n";
  const Outcome o = run_solver(yaml, "set_ok",
                               "--set time.steps=3 --set 'materials[0].youngs_modulus=20 GPa' --set 'initial[0].value=[0, 2, 0]'");
  ASSERT_EQ(o.exit_code, 0) << o.output;
  const std::string dir = breccia::solver::testing::process_temp_dir() + "/cli_set_ok/out";
  std::ifstream js(dir + "/summary.json");
  const nlohmann::json summary = nlohmann::json::parse(js);
  EXPECT_EQ(summary["steps_this_run"].get<long long>(), 3);
  std::ifstream hist(dir + "/history.csv");
  std::string header, first;
  std::getline(hist, header);
  std::getline(hist, first);
  // 100 particles of 1 mm^2 x 1 mm at 2000 kg/m3 = 2e-4 kg, at 2 m/s: 4e-4 J.
  const double kinetic = std::stod(first.substr(first.find(',', first.find(',') + 1) + 1));
  EXPECT_NEAR(kinetic, 4e-4, 1e-9) << header << "\n" << first;
}

TEST(SolverCli, SetWithAMissingEntryOrNoValueIsBadInput) {
  const std::string yaml = kBase + kMaterial + kTime;
  expect_bad_input(run_solver(yaml, "set_index", "--set 'materials[3].density=1'"), {"materials[3]", "has no entry [3]", "(it has 1)"});
  expect_bad_input(run_solver(yaml, "set_novalue", "--set time.steps"), {"--set", "KEY=VALUE"});
  expect_bad_input(run_solver(yaml, "set_unknown", "--set time.stpes=3"), {"time.stpes", "unknown key"});
}

// --variant NAME applies the case file's variants.NAME entries as the same --set options
// would, before any --set (so --set wins); without --variant the block is ignored.
TEST(SolverCli, VariantAppliesItsOverridesBeforeSet) {
  const std::string yaml = kBase + kMaterial + kTime +
                           "variants:\n"
                           "  short:\n"
                           "    time.steps: 3\n"
                           "    materials[0].youngs_modulus: 20 GPa\n"
                           "  shorter: [{time.steps: 2}]\n";
  auto steps_run = [](const std::string& name) {
    std::ifstream js(breccia::solver::testing::process_temp_dir() + "/cli_" + name + "/out/summary.json");
    return nlohmann::json::parse(js)["steps_this_run"].get<long long>();
  };
  const Outcome plain = run_solver(yaml, "variant_none");
  ASSERT_EQ(plain.exit_code, 0) << plain.output;
  EXPECT_EQ(steps_run("variant_none"), 5);
  const Outcome shortv = run_solver(yaml, "variant_short", "--variant short");
  ASSERT_EQ(shortv.exit_code, 0) << shortv.output;
  EXPECT_EQ(steps_run("variant_short"), 3);
  const Outcome listv = run_solver(yaml, "variant_list", "--variant shorter");
  ASSERT_EQ(listv.exit_code, 0) << listv.output;
  EXPECT_EQ(steps_run("variant_list"), 2);
  const Outcome both = run_solver(yaml, "variant_set", "--set time.steps=4 --variant short");
  ASSERT_EQ(both.exit_code, 0) << both.output;
  EXPECT_EQ(steps_run("variant_set"), 4);
}

TEST(SolverCli, UnknownVariantOrBadVariantEntryIsBadInput) {
  const std::string yaml = kBase + kMaterial + kTime +
                           "variants:\n  short: {time.steps: 3}\n  typo: {time.stpes: 3}\n"
                           "  index:\n    materials[3].density: 1\n";
  expect_bad_input(run_solver(yaml, "variant_unknown", "--variant long"), {"case.yaml", "--variant long", "short, typo, index"});
  expect_bad_input(run_solver(yaml, "variant_typo", "--variant typo"), {"time.stpes", "unknown key"});
  expect_bad_input(run_solver(yaml, "variant_index", "--variant index"),
                   {"variants.index materials[3].density", "has no entry [3]", "(it has 1)"});
  expect_bad_input(run_solver(kBase + kMaterial + kTime, "variant_none_given", "--variant short"),
                   {"--variant short", "no 'variants' block"});
}

// A relative specimen.particles is looked for in the output folder first, then next to the
// case file; absent from both, the error names the key and both places. The two files differ
// in particle count, which summary.json reports.
TEST(SolverCli, RelativeParticleFileIsLookedForInTheOutputFolderFirst) {
  const std::string dir = breccia::solver::testing::process_temp_dir() + "/cli_particles_lookup";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir + "/out");
  auto square = [](int n) {
    breccia::ParticleModel m;
    m.dimension = 2;
    m.thickness_m = 1e-3;
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        m.position_m.insert(m.position_m.end(), {(i + 0.5) * 1e-3, (j + 0.5) * 1e-3, 0.0});
        m.volume_m3.push_back(1e-9);
        m.spacing_m.push_back(1e-3);
        m.material_id.push_back(0);
      }
    m.source = "test_cli particle lookup";
    return m;
  };
  breccia::write_particle_file(dir + "/particles.h5", square(6));      // next to the case: 36
  breccia::write_particle_file(dir + "/out/particles.h5", square(7));  // in the output folder: 49
  std::ofstream(dir + "/case.yaml") << "specimen: {particles: particles.h5}\nmodel: {type: pmb, planar: plane_strain}\n" +
                                           kMaterial + kTime;
  auto solve = [&]() {
    const std::string cmd = std::string(BRECCIA_SOLVE_EXE) + " " + dir + "/case.yaml -o " + dir + "/out --quiet 2>&1";
    FILE* p = popen(cmd.c_str(), "r");
    std::string out;
    std::array<char, 512> buf{};
    while (fgets(buf.data(), buf.size(), p)) out += buf.data();
    return Outcome{WEXITSTATUS(pclose(p)), out};
  };
  auto particles_run = [&]() {
    std::ifstream js(dir + "/out/summary.json");
    return nlohmann::json::parse(js)["particles"].get<long long>();
  };
  Outcome o = solve();
  ASSERT_EQ(o.exit_code, 0) << o.output;
  EXPECT_EQ(particles_run(), 49);
  std::filesystem::remove(dir + "/out/particles.h5");
  o = solve();
  ASSERT_EQ(o.exit_code, 0) << o.output;
  EXPECT_EQ(particles_run(), 36);
  std::filesystem::remove(dir + "/particles.h5");
  expect_bad_input(solve(), {"specimen.particles", "does not exist", dir + "/out/particles.h5", dir + "/particles.h5"});
}

TEST(SolverCli, HorizonSmallerThanSpacingIsRejected) {
  expect_bad_input(run_solver("specimen: {lattice: {dimension: 2, box: [0, 0, 0.01, 0.01], spacing: 1 mm, thickness: 1 mm}}\n"
                              "model: {type: pmb, planar: plane_strain, horizon: 0.5 mm}\n" + kMaterial + kTime,
                              "small_horizon"),
                   {"model.horizon", "spacing"});
}

TEST(SolverCli, UnknownKeyAndWrongUnitAreRejected) {
  expect_bad_input(run_solver(kBase + kMaterial + kTime + "outptu: {every: 1}\n", "unknown_key"), {"outptu", "output"});
  expect_bad_input(
      run_solver(kBase + "materials: [{name: m, density: 2000, youngs_modulus: 10 mm, poisson_ratio: 0.25}]\n" + kTime,
                 "wrong_unit"),
      {"youngs_modulus", "GPa"});
}

TEST(SolverCli, MissingParticleFileIsNamed) {
  expect_bad_input(run_solver("specimen: {particles: nowhere.h5}\nmodel: {type: lps}\n" + kMaterial + kTime, "missing_file"),
                   {"nowhere.h5", "does not exist"});
}

TEST(SolverCli, PmbWithAnotherPoissonRatioPointsToLps) {
  expect_bad_input(
      run_solver(kBase + "materials: [{name: m, density: 2000, youngs_modulus: 10 GPa, poisson_ratio: 0.3}]\n" + kTime,
                 "pmb_nu"),
      {"poisson_ratio", "lps"});
}

TEST(SolverCli, CtrlCWritesACheckpointAndExitsWith130) {
  const std::string dir = breccia::solver::testing::process_temp_dir() + "/cli_sigint";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  std::ofstream(dir + "/case.yaml")
      << "specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.02, 0.02, 0.02], spacing: 1 mm}}\n"
         "model: {type: lps}\n" + kMaterial + "time: {steps: 100000000}\n";
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    const std::string out = dir + "/out";
    execl(BRECCIA_SOLVE_EXE, BRECCIA_SOLVE_EXE, (dir + "/case.yaml").c_str(), "-o", out.c_str(), "--quiet",
          static_cast<char*>(nullptr));
    _exit(127);
  }
  // Wait until the time loop runs (history.csv has its first row), then interrupt.
  for (int k = 0; k < 600 && !std::filesystem::exists(dir + "/out/history.csv"); ++k) usleep(100000);
  usleep(500000);
  kill(pid, SIGINT);
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 130);
  EXPECT_TRUE(std::filesystem::exists(dir + "/out/checkpoint.h5"));
  std::ifstream summary(dir + "/out/summary.json");
  const std::string text((std::istreambuf_iterator<char>(summary)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("\"status\": \"interrupted\""), std::string::npos) << text;
}

TEST(SolverCli, SummaryOfARunStoppedForNonFiniteValuesIsStrictJson) {
  // A step five times the stable one, checked only after 2,000 steps: by then the state has
  // overflowed. summary.json must still parse with a strict parser (NaN is not JSON): the
  // non-finite energies are null and named in non_finite.
  const Outcome o = run_solver(
      "specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.006, 0.006, 0.006], spacing: 1 mm}}\n"
      "model: {type: pmb, fracture: false}\n"
      "materials: [{name: m, density: 1000, youngs_modulus: 1 GPa, poisson_ratio: 0.25}]\n"
      "initial: [{type: radial_velocity, center: [0, 0, 0], strain_rate: 10}]\n"
      "time: {steps: 2000, dt: 1e-5, check_stability: false}\n"
      "output: {every: 100000, history_every: 2000, results: false}\n",
      "non_finite");
  EXPECT_EQ(o.exit_code, 3) << o.output;
  std::ifstream in(breccia::solver::testing::process_temp_dir() + "/cli_non_finite/out/summary.json");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  nlohmann::json j;
  ASSERT_NO_THROW(j = nlohmann::json::parse(text)) << text;  // rejects NaN and Infinity tokens
  EXPECT_EQ(j["status"], "unstable");
  EXPECT_TRUE(j["kinetic_J"].is_null());
  const auto& named = j["non_finite"];
  EXPECT_NE(std::find(named.begin(), named.end(), "kinetic_J"), named.end()) << text;
  EXPECT_TRUE(j["particles"].is_number());
  // The set-up's profile, phase by phase (their sum is the set-up's wall time, less the
  // checkpoint read of a restart).
  double phases = 0.0;
  for (const char* name : {"particles", "families", "bond coefficients", "stable step"}) {
    ASSERT_TRUE(j["setup_phases_s"].contains(name)) << name << ": " << text;
    phases += j["setup_phases_s"][name].get<double>();
  }
  EXPECT_LE(phases, j["setup_wall_s"].get<double>() * 1.01 + 1e-3);
}

// A boundary whose set lists a particle twice would race on the GPU (each listed particle is
// written by its own thread): refused at set-up, naming the boundary, the set and the particle.
TEST(SolverCli, BoundarySetListingAParticleTwiceIsRejected) {
  const std::string dir = breccia::solver::testing::process_temp_dir() + "/cli_dup_set";
  std::filesystem::create_directories(dir);
  breccia::ParticleModel m = breccia::solver::testing::square_lattice_model(6, 6, 1e-3, 1e-3);
  m.sets = {breccia::ParticleSet{"edge", {0, 1, 2, 1}}};
  m.source = "test_cli duplicate set";
  breccia::write_particle_file(dir + "/particles.h5", m);
  std::ofstream(dir + "/case.yaml") << "specimen: {particles: particles.h5}\nmodel: {type: pmb, planar: plane_strain}\n" +
                                           kMaterial + kTime + "boundary: [{type: fixed, set: edge}]\n";
  const std::string cmd = std::string(BRECCIA_SOLVE_EXE) + " " + dir + "/case.yaml -o " + dir + "/out --quiet 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  std::string out;
  std::array<char, 512> buf{};
  while (fgets(buf.data(), buf.size(), p)) out += buf.data();
  const int status = pclose(p);
  expect_bad_input({WEXITSTATUS(status), out}, {"boundary[0].set", "'edge'", "particle 1 more than once"});
}

// --decomposition on a box lattice takes the route without families (partition.hpp): one
// row per rank count, and the bond balance of an 8,000-particle cube cut in two is close to 1.
TEST(SolverCli, DecompositionOfALatticePrintsOneRowPerRankCount) {
  const Outcome o = run_solver("specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.02, 0.02, 0.02], spacing: 1 mm}}\n"
                               "model: {type: pmb, horizon_factor: 3.015}\n" + kMaterial + kTime,
                               "decomposition", "--decomposition 2,4");
  ASSERT_EQ(o.exit_code, 0) << o.output;
  EXPECT_NE(o.output.find("20 x 20 x 20 lattice = 8000 particles"), std::string::npos) << o.output;
  const size_t row = o.output.find("\n2,");
  ASSERT_NE(row, std::string::npos) << o.output;
  EXPECT_NE(o.output.find("\n4,"), std::string::npos) << o.output;
  // ranks,owned_min,owned_max,bonds_max_over_mean,...: the balance column of the 2-rank row
  std::istringstream fields(o.output.substr(row + 1));
  std::string cell;
  for (int c = 0; c < 4; ++c) std::getline(fields, cell, ',');
  EXPECT_LT(std::stod(cell), 1.01) << o.output;
  EXPECT_GE(std::stod(cell), 1.0) << o.output;
  expect_bad_input(run_solver(kBase + kMaterial + kTime, "decomposition_bad", "--decomposition 2,x"), {"--decomposition", "'x'"});
}

TEST(SolverCli, UnknownStrengthRateLawIsNamedWithTheChoices) {
  const std::string material =
      "materials: [{name: m, density: 2000, youngs_modulus: 10 GPa, poisson_ratio: 0.25, fracture_energy: 10, "
      "tensile_strength: 1 MPa, strength_rate: ccb}]\n";
  expect_bad_input(run_solver(kBase + material + kTime, "bad_strength_rate"),
                   {"case.yaml", "materials[0].strength_rate", "fib_mc2010"});
}

// Inputs found by fuzzing the case format that crashed (abort or segfault), overflowed to a
// run of no step, or ran on silently: each is now exit 2 naming its field.
TEST(SolverCli, SlipsThatCrashedOrRanSilentlyAreBadInputNamingTheField) {
  const std::string material_time = kMaterial + kTime;
  // A lattice of 10^18 points (1 um for 1 mm: 32-bit particle indices) and inverted boxes.
  expect_bad_input(run_solver("specimen: {lattice: {dimension: 3, box: [0, 0, 0, 1, 1, 1], spacing: 1 um}}\n"
                              "model: {type: pmb}\n" + material_time, "lattice_huge"),
                   {"specimen.lattice.spacing", "2^31 - 1"});
  expect_bad_input(run_solver("specimen: {lattice: {dimension: 2, box: [0, 0, -0.01, 0.01], spacing: 1 mm, thickness: 1 mm}}\n"
                              "model: {type: pmb, planar: plane_strain}\n" + material_time, "lattice_inverted"),
                   {"specimen.lattice.box", "x1 > x0"});
  // A horizon of a kilometre on millimetre particles, or of 30,150 spacings.
  expect_bad_input(run_solver("specimen: {lattice: {dimension: 2, box: [0, 0, 0.01, 0.01], spacing: 1 mm, thickness: 1 mm}}\n"
                              "model: {type: pmb, planar: plane_strain, horizon: 1 km}\n" + material_time, "horizon_km"),
                   {"model.horizon", "at most 50"});
  expect_bad_input(run_solver(kBase.substr(0, kBase.find("model:")) +
                              "model: {type: pmb, planar: plane_strain, horizon_factor: 30150}\n" + material_time, "factor_huge"),
                   {"model.horizon_factor", "1 to 50"});
  // A modulus of 1e300 GPa is infinite in pascals; a step of 1e-300 s is 10^295 steps.
  expect_bad_input(run_solver(kBase + "materials: [{name: m, density: 2000, youngs_modulus: 1e300 GPa, poisson_ratio: 0.25}]\n" + kTime,
                              "modulus_inf"),
                   {"youngs_modulus", "infinite in SI units"});
  expect_bad_input(run_solver(kBase + kMaterial + "time: {end: 1 us, dt: 1e-300}\n", "dt_tiny"), {"time.end", "10^12 steps"});
  // An alias inside its own anchor (a node that contains itself) and a key that is a list.
  expect_bad_input(run_solver(kBase + kMaterial + kTime + "description: &d [*d]\n", "self_alias"), {"description", "levels deep"});
  expect_bad_input(run_solver(kBase + kMaterial + kTime + "{[1, 2]: 3}: x\n", "list_key"), {"a key that is a list or a map"});
  // --set with an index of 23 digits, and a map given whole with a key twice.
  expect_bad_input(run_solver(kBase + kMaterial + kTime, "set_index_huge", "--set 'materials[99999999999999999999999].density=1'"),
                   {"has no entry"});
  expect_bad_input(run_solver(kBase + kMaterial + kTime, "set_dup", "--set 'time={steps: 3, steps: 4}'"),
                   {"time.steps", "given twice"});
  // A z component in a 2D model (it has no z motion: the value was dropped).
  expect_bad_input(run_solver(kBase + kMaterial + kTime + "initial: [{type: velocity, value: [0, 0, 100]}]\n", "init_z_2d"),
                   {"initial[0].value", "a z component in a 2D model"});
  expect_bad_input(run_solver(kBase + kMaterial + kTime + "initial: [{type: velocity, expression: ['1', '0', '5']}]\n",
                              "init_z_expression_2d"),
                   {"initial[0].expression[2]", "a z component in a 2D model"});
  // A negative ramp and two probes of one name (two history.csv columns of one name).
  expect_bad_input(run_solver(kBase + kMaterial + kTime +
                                  "sets: [{name: left, box: [0, 0, 0.002, 0.01]}]\n"
                                  "boundary: [{type: velocity, set: left, value: [0, 0, 0], ramp_time: -1 us}]\n",
                              "ramp_negative"),
                   {"boundary[0].ramp_time", "a time >= 0"});
  expect_bad_input(run_solver(kBase + kMaterial + kTime +
                                  "output: {probes: [{name: a, position: [0.005, 0.005, 0]}, {name: a, position: [0.002, 0.002, 0]}]}\n",
                              "probe_twice"),
                   {"output.probes[1].name", "a name of its own"});
}

// A load table or an initial field that holds nan, inf or hexadecimal is bad input naming the
// file and line; it ran as a blow-up (exit 3) before.
TEST(SolverCli, NonFiniteOrHexadecimalValuesInInputTablesAreBadInput) {
  const std::string dir = breccia::solver::testing::process_temp_dir() + "/cli_tables";
  std::filesystem::create_directories(dir);
  for (const auto& [name, cell] : std::vector<std::pair<std::string, std::string>>{{"nan", "nan"}, {"inf", "inf"}, {"hex", "0x1"}}) {
    std::ofstream(dir + "/" + name + ".csv") << "time_s,value\n0,0\n1e-6," << cell << "\n1e-5,1\n";
    expect_bad_input(run_solver(kBase + kMaterial + kTime +
                                    "loads: [{type: body_force, value: [1, 0, 0], history: {type: table, file: " + dir + "/" +
                                    name + ".csv}}]\n",
                                "table_" + name),
                     {name + ".csv", "line 3", "'" + cell + "'"});
  }
  std::ofstream(dir + "/field.csv") << "vx,vy\n" << [] {
    std::string rows;
    for (int k = 0; k < 100; ++k) rows += k == 42 ? "nan,0\n" : "0,0\n";
    return rows;
  }();
  expect_bad_input(run_solver(kBase + kMaterial + kTime + "initial: [{type: velocity, file: " + dir + "/field.csv}]\n", "field_nan"),
                   {"field.csv", "line 44", "a finite number"});
}

// A restart reads the checkpoint's state as this case's: a checkpoint of another model type,
// or one whose step is above this case's stable step (the material made 100x stiffer since),
// is refused naming the attribute; before, the first ran on and the second blew up (exit 3).
TEST(SolverCli, RestartFromAnotherModelOrAStepAboveTheStableOneIsBadInput) {
  const std::string time = "time: {steps: 4}\noutput: {every: 100, history_every: 2}\n";
  const Outcome first = run_solver(kBase + kMaterial + time, "restart_source");
  ASSERT_EQ(first.exit_code, 0) << first.output;
  const std::string checkpoint = breccia::solver::testing::process_temp_dir() + "/cli_restart_source/out/checkpoint.h5";
  std::string lps = kBase;
  lps.replace(lps.find("type: pmb"), 9, "type: lps");
  expect_bad_input(run_solver(lps + kMaterial + time, "restart_lps", "--restart " + checkpoint + " --steps 2"),
                   {"checkpoint.h5: /@model", "'pmb', this case's is 'lps'"});
  const std::string stiff = "materials: [{name: m, density: 2000, youngs_modulus: 1000 GPa, poisson_ratio: 0.25}]\n";
  expect_bad_input(run_solver(kBase + stiff + time, "restart_stiff", "--restart " + checkpoint + " --steps 2"),
                   {"checkpoint.h5: /@dt_s", "above this case's stable step"});
  const Outcome same = run_solver(kBase + kMaterial + time, "restart_same", "--restart " + checkpoint + " --steps 2");
  EXPECT_EQ(same.exit_code, 0) << same.output;
}

// A restart into the folder of a longer run (found in review, 2026-12-08): results.xdmf lists
// only the output groups the restart keeps (it listed the removed ones until the next output,
// for good when the restarted run stopped before one), and a field the continued run did not
// write is refused naming the group's dataset (results.xdmf pointed ParaView at it).
TEST(SolverCli, ARestartKeepsResultsXdmfToItsGroupsAndRefusesAFieldTheRunDidNotWrite) {
  const std::string dir = breccia::solver::testing::process_temp_dir() + "/cli_restart_xdmf";
  const std::string output = "output: {every: 2, history_every: 2}\n";
  ASSERT_EQ(run_solver(kBase + kMaterial + "time: {steps: 4}\n" + output, "restart_xdmf").exit_code, 0);
  std::filesystem::copy_file(dir + "/out/checkpoint.h5", dir + "/step4.h5", std::filesystem::copy_options::overwrite_existing);
  ASSERT_EQ(run_solver(kBase + kMaterial + "time: {steps: 8}\n" + output, "restart_xdmf").exit_code, 0);
  const auto grids = [&] {
    std::ifstream in(dir + "/out/results.xdmf");
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    size_t count = 0;
    for (size_t at = text.find("<Time "); at != std::string::npos; at = text.find("<Time ", at + 1)) ++count;
    return std::pair{count, text};
  };
  ASSERT_EQ(grids().first, 5u);  // steps 0, 2, 4, 6, 8
  const Outcome again = run_solver(kBase + kMaterial + "time: {steps: 4}\n" + output, "restart_xdmf",
                                   "--restart " + dir + "/step4.h5");
  ASSERT_EQ(again.exit_code, 0) << again.output;
  const auto [count, text] = grids();
  EXPECT_EQ(count, 3u) << text;  // steps 0, 2, 4
  EXPECT_EQ(text.find("/output/000003"), std::string::npos) << text;
  const Outcome more = run_solver(kBase + kMaterial + "time: {steps: 6}\noutput: {every: 2, history_every: 2, fields: [stretch]}\n",
                                  "restart_xdmf", "--restart " + dir + "/step4.h5");
  expect_bad_input(more, {"results.h5: /output/000000/stretch: missing"});
}

// A boundary value in time that stops being finite mid-run (sqrt(2e-6 - t) past 2 us; the run
// is 40 steps of a few tenths of a microsecond) is refused before the writers open their
// files: the folder's earlier results stay as they were (they were truncated to the failed
// run's first steps before).
TEST(SolverCli, ABoundaryValueThatTurnsNonFiniteMidRunIsRefusedBeforeAnythingIsWritten) {
  const std::string sets = "sets: [{name: right, box: [0.009, 0, 0.01, 0.01]}]\n";
  const std::string time = "time: {steps: 40}\noutput: {every: 10, history_every: 5}\n";
  const Outcome good = run_solver(kBase + kMaterial + sets + time, "late_field");
  ASSERT_EQ(good.exit_code, 0) << good.output;
  const std::string out = breccia::solver::testing::process_temp_dir() + "/cli_late_field/out";
  const auto read = [](const std::string& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  };
  const std::string results = read(out + "/results.h5"), history = read(out + "/history.csv");
  const Outcome late = run_solver(kBase + kMaterial + sets + time +
                                      "boundary: [{type: velocity, set: right, components: [x], "
                                      "expression: ['sqrt(2e-6 - t)', '0']}]\n",
                                  "late_field");
  expect_bad_input(late, {"boundary[0].expression[0]", "is not finite at"});
  EXPECT_EQ(read(out + "/results.h5"), results);
  EXPECT_EQ(read(out + "/history.csv"), history);
}

// Relaxation finds one equilibrium: it read every load history at t = 0 (a ramp gave no load
// at all, "converged" with u = 0) and held a velocity boundary still. Both are refused.
TEST(SolverCli, AHistoryInTimeOrAVelocityBoundaryUnderRelaxationIsBadInput) {
  const std::string adr = "time: {integrator: adr}\n";
  const std::string sets = "sets: [{name: left, box: [0, 0, 0.002, 0.01]}]\n";
  expect_bad_input(run_solver(kBase + kMaterial + adr + sets + "boundary: [{type: fixed, set: left}]\n"
                                  "loads: [{type: body_force, value: [1, 0, 0], history: {type: ramp, value: 1, ramp_time: 5 us}}]\n",
                              "adr_ramp"),
                   {"loads[0].history", "type: constant"});
  expect_bad_input(run_solver(kBase + kMaterial + adr + sets + "boundary: [{type: velocity, set: left, value: [1, 0, 0]}]\n",
                              "adr_velocity"),
                   {"boundary[0].type", "fixed or displacement"});
}


// A finished run's results.h5 says so (root attribute complete = 1; 0 while it runs, and for
// a run stopped early); an MPS case takes --steps 0 (the set-up and initial outputs alone,
// it ran to time.end) and --quiet (it printed its summary lines) as a PD case does.
TEST(SolverCli, AFinishedRunIsMarkedCompleteAndAnMpsCaseTakesStepsZeroAndQuiet) {
  const Outcome pd = run_solver(kBase + kMaterial + kTime, "complete");
  ASSERT_EQ(pd.exit_code, 0) << pd.output;
  {
    const breccia::h5::File f(breccia::solver::testing::process_temp_dir() + "/cli_complete/out/results.h5",
                              breccia::h5::File::Mode::Read);
    EXPECT_EQ(f.attr_int("/", "complete"), 1);
    // results.xdmf's times are the groups' time_s to the last bit (17 digits).
    std::ifstream xdmf(breccia::solver::testing::process_temp_dir() + "/cli_complete/out/results.xdmf");
    const std::string text((std::istreambuf_iterator<char>(xdmf)), std::istreambuf_iterator<char>());
    size_t at = 0;
    int groups = 0;
    while ((at = text.find("<Time Value=\"", at)) != std::string::npos) {
      at += 13;
      const double t = std::stod(text.substr(at, text.find('"', at) - at));
      EXPECT_EQ(t, f.attr_double(breccia::solver::results_output_group(groups), "time_s")) << groups;
      ++groups;
    }
    EXPECT_EQ(groups, f.attr_int("/", "output_count"));
  }
  const std::string mps = "specimen:\n  lattice: {dimension: 2, box: [0, 0, 10 mm, 10 mm], spacing: 0.5 mm}\n"
                          "model: {type: mps, equation: navier}\n"
                          "materials: [{name: steel, density: 7850, C13: 121.1 GPa, C55: 80.8 GPa}]\n"
                          "time: {end: 1 us}\n";
  const Outcome zero = run_solver(mps, "mps_steps_zero", "--steps 0 --backend cpu");
  ASSERT_EQ(zero.exit_code, 0) << zero.output;
  EXPECT_EQ(zero.output, "");  // --quiet: nothing but errors
  std::ifstream js(breccia::solver::testing::process_temp_dir() + "/cli_mps_steps_zero/out/summary.json");
  const nlohmann::json summary = nlohmann::json::parse(js);
  EXPECT_EQ(summary.at("steps").get<long long>(), 0) << summary;
}
