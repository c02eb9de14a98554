// breccia-post end to end on synthetic run directories, and its answers to bad input.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <numbers>
#include <sstream>

#include "../common/cli_contract.hpp"
#include "breccia/common/error.hpp"
#include "breccia/common/h5.hpp"
#include "breccia/postproc/run_data.hpp"
#include "real_run.hpp"
#include "synthetic_run.hpp"

using namespace breccia;
namespace bt = breccia::postproc::testing;
namespace fs = std::filesystem;
using breccia::postproc::testing::json_number;

namespace {

constexpr double kH = 1e-3;
constexpr double kG0 = 100.0;

struct Result {
  int code = -1;
  std::string output;
};

Result run_post(const std::string& args, const std::string& env = "") {
  const std::string cmd = env + " '" + std::string(BRECCIA_POST_EXE) + "' " + args + " 2>&1";
  Result r;
  FILE* p = popen(cmd.c_str(), "r");
  std::array<char, 4096> buf{};
  while (fgets(buf.data(), buf.size(), p)) r.output += buf.data();
  const int status = pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

// Cubes of 2, 3 and 4 mm, 3 mm apart; the 4 mm cube cut on z = 1 mm (16 mm^2).
bt::SyntheticRun cracked_cubes(const fs::path& dir) {
  bt::SyntheticRun run;
  run.dir = dir;
  fs::remove_all(dir);
  run.model = bt::merge({bt::structured_mesh(3, {2, 2, 2}, kH), bt::structured_mesh(3, {3, 3, 3}, kH, {5 * kH, 0, 0}),
                         bt::structured_mesh(3, {4, 4, 4}, kH, {11 * kH, 0, 0})});
  run.horizon_m = 1.6 * kH;
  run.fracture_energy_J_m2 = {kG0};
  const auto cut = bt::bonds_where(run.model, run.horizon_m, [](const double* a, const double* b) {
    return a[0] > 10 * kH && (a[2] - kH) * (b[2] - kH) < 0;
  });
  run.outputs.push_back({0, 0.0, {}, {}, {}, {}});
  bt::SyntheticOutput last{100, 1e-5, {}, {}, {}, cut};
  last.damage.assign(run.model.size(), 0.0);
  run.outputs.push_back(last);
  return run;
}

void write_history(const fs::path& dir, double dissipated_J) {
  // 512 samples, dt = 10 ns; probe A: 2 MHz on bin 10... (f0 = 10 / (512 dt)) plus 10 % third harmonic.
  const size_t n = 512;
  const double dt = 1e-8, f0 = 10.0 / (n * dt);
  std::ostringstream s;
  s << "step,time_s,kinetic_J,strain_J,external_work_J,dissipated_J,total_J,max_damage,broken_bonds,probe_A_ux,probe_A_uy\n";
  for (size_t k = 0; k < n; ++k) {
    const double t = k * dt, frac = static_cast<double>(k) / (n - 1);
    const double d = dissipated_J * frac, kin = 0.3 * frac, strain = 0.1 * frac;
    const double ux = 1e-8 * (std::sin(2 * std::numbers::pi * f0 * t) + 0.1 * std::sin(2 * std::numbers::pi * 3 * f0 * t));
    s << k * 100 / (n - 1) << ',' << t << ',' << kin << ',' << strain << ',' << kin + strain + d << ',' << d << ','
      << kin + strain + d << ",0,0," << ux << ',' << 0.5 * ux << '\n';
  }
  std::ofstream(dir / "history.csv") << s.str();
}

}  // namespace

TEST(BrecciaPostCli, FullRunWritesEveryOutputWithTheKnownAnswers) {
  const fs::path dir = fs::path(::testing::TempDir()) / "post_full";
  const auto run = cracked_cubes(dir);
  bt::write_run(run);
  write_history(dir, kG0 * 16e-6);
  const Result r = run_post("'" + dir.string() + "' --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  for (const char* f : {"cracks.vtp", "damage_iso.vtp", "crack_history.csv", "fragments.csv", "fragments.vtu",
                        "deformed.vtu", "size_distribution.csv", "post.json", "probe_A.csv", "spectrum_A.csv",
                        "fragment_sizes.png", "energy.png", "probe_A.png", "spectrum_A.png"})
    EXPECT_TRUE(fs::exists(dir / "post" / f)) << f << "\n" << r.output;
  const std::string json = bt::read_text(dir / "post" / "post.json");
  EXPECT_EQ(json_number(json, "fragment_count", "\"fragments\""), 4);
  EXPECT_NEAR(json_number(json, "crack_area_m2"), 16e-6, 1e-15);
  EXPECT_EQ(json_number(json, "crack_count"), 1);
  // History dissipated energy was written as G0 x 16 mm^2: the check reads 1.
  EXPECT_NEAR(json_number(json, "ratio", "\"energy\""), 1.0, 1e-6);
  EXPECT_NEAR(bt::first_spectrum_harmonic_ratio(json, 3), 0.1, 0.001);  // on-bin tones: 1 %
  // Crack area history: nothing at output 0, 16 mm^2 at output 1.
  const std::string hist = bt::read_text(dir / "post" / "crack_history.csv");
  EXPECT_NE(hist.find("\n0,0,0,0,"), std::string::npos) << hist;
  EXPECT_NE(hist.find("\n1,100,1e-05,1.6e-05,"), std::string::npos) << hist;
}

TEST(BrecciaPostCli, AllStepsWritesOneFileSetPerOutputAndCollections) {
  const fs::path dir = fs::path(::testing::TempDir()) / "post_all";
  bt::write_run(cracked_cubes(dir));
  const Result r = run_post("'" + dir.string() + "' --all --cracks --fragments --no-plots --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  for (const char* f : {"cracks_000000.vtp", "cracks_000100.vtp", "fragments_000100.vtu", "deformed_000000.vtu",
                        "cracks.pvd", "fragments.pvd"})
    EXPECT_TRUE(fs::exists(dir / "post" / f)) << f;
  EXPECT_FALSE(fs::exists(dir / "post" / "energy.png"));  // not selected
}

TEST(BrecciaPostCli, FailingChartScriptIsReportedAndResultsAreKept) {
  const fs::path dir = fs::path(::testing::TempDir()) / "post_noscript";
  bt::write_run(cracked_cubes(dir));
  const Result r = run_post("'" + dir.string() + "' --fragments --quiet", "BRECCIA_POSTPROC_SCRIPTS=/nonexistent");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("chart not drawn"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::exists(dir / "post" / "fragments.csv"));
  EXPECT_NE(bt::read_text(dir / "post" / "post.json").find("fragment_sizes.png: plot_fragment_sizes.py failed"), std::string::npos);
}

// The crack history runs beside the last output's analysis and the charts beside both when
// post has two or more threads: every file but the charts must be the same bytes as on one.
TEST(BrecciaPostCli, ThreadCountDoesNotChangeTheFilesWritten) {
  const fs::path dir = fs::path(::testing::TempDir()) / "post_threads";
  auto run = cracked_cubes(dir);
  // More outputs than threads, so that the history's outputs are shared out.
  for (long long step : {200, 300, 400, 500}) {
    auto more = run.outputs.back();
    more.step = step;
    more.time_s = 1e-7 * static_cast<double>(step);
    run.outputs.push_back(more);
  }
  bt::write_run(run);
  write_history(dir, kG0 * 16e-6);
  std::map<std::string, std::string> first;
  for (const char* threads : {"1", "3"}) {
    const Result r = run_post("'" + dir.string() + "' --quiet --threads " + threads);
    ASSERT_EQ(r.code, 0) << r.output;
    for (const char* f : {"crack_history.csv", "cracks.vtp", "damage_iso.vtp", "fragments.csv", "fragments.vtu",
                          "deformed.vtu", "size_distribution.csv", "post.json", "probe_A.csv", "spectrum_A.csv"}) {
      const std::string text = bt::read_text(dir / "post" / f);
      if (first.count(f) == 0) first[f] = text;
      else EXPECT_EQ(text, first[f]) << f << " differs on " << threads << " threads";
    }
    for (const char* png : {"fragment_sizes.png", "energy.png", "probe_A.png", "spectrum_A.png"})
      EXPECT_TRUE(fs::exists(dir / "post" / png)) << png << " on " << threads << " threads\n" << r.output;
  }
  // Every output in order, the last at 16 mm^2.
  const std::string hist = first["crack_history.csv"];
  EXPECT_NE(hist.find("\n0,0,0,0,"), std::string::npos) << hist;
  EXPECT_NE(hist.find("\n5,500,5e-05,1.6e-05,"), std::string::npos) << hist;
}

TEST(BrecciaPostCli, TwoDimensionalLatticeRunReportsCrackLengthAndTwoFragments) {
  // 10 x 6 square lattice, thickness 5 mm, cut between rows 2 and 3: a 10 mm crack.
  const fs::path dir = fs::path(::testing::TempDir()) / "post_lattice2d";
  fs::remove_all(dir);
  bt::SyntheticRun run;
  run.dir = dir;
  run.model = bt::lattice(2, {10, 6, 1}, kH, 5e-3);
  run.horizon_m = 3.015 * kH;
  const auto cut = bt::bonds_where(run.model, run.horizon_m, [](const double* a, const double* b) {
    return (a[1] - 3 * kH) * (b[1] - 3 * kH) < 0;
  });
  run.outputs.push_back({10, 1e-6, {}, {}, {}, cut});
  bt::write_run(run);
  const Result r = run_post("'" + dir.string() + "' --no-plots --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  const std::string json = bt::read_text(dir / "post" / "post.json");
  EXPECT_NEAR(json_number(json, "crack_length_m"), 10 * kH, 1e-15);
  EXPECT_NEAR(json_number(json, "crack_area_m2"), 10 * kH * 5e-3, 1e-18);
  EXPECT_EQ(json_number(json, "fragment_count", "\"fragments\""), 2);
  EXPECT_TRUE(fs::exists(dir / "post" / "deformed.vtu"));
  EXPECT_FALSE(fs::exists(dir / "post" / "damage_iso.vtp"));  // no mesh to contour on
  EXPECT_NE(json.find("damage_iso.vtp not written: lattice model"), std::string::npos);
}

TEST(BrecciaPostCli, MissingResultsFileIsBadInputNamingTheFile) {
  const fs::path dir = fs::path(::testing::TempDir()) / "post_empty";
  fs::create_directories(dir);
  const Result r = run_post("'" + dir.string() + "'");
  EXPECT_EQ(r.code, kExitBadInput);
  EXPECT_NE(r.output.find("error: " + (dir / "results.h5").string() + ": file does not exist"), std::string::npos) << r.output;
}

// A --particles path that does not exist is the option's fault, not the run's: the error names
// the option (it named results.h5's attribute, which the option had replaced).
TEST(BrecciaPostCli, MissingParticlesFileGivenByTheOptionIsBadInputNamingTheOption) {
  const fs::path dir = fs::path(::testing::TempDir()) / "post_particles_option";
  bt::write_run(cracked_cubes(dir));
  const fs::path missing = dir / "no_such_particles.h5";
  const Result r = run_post("'" + dir.string() + "' --particles '" + missing.string() + "' --no-plots");
  EXPECT_EQ(r.code, kExitBadInput);
  EXPECT_NE(r.output.find("error: command line: --particles: '" + missing.string() + "' does not exist"),
            std::string::npos)
      << r.output;
}

// A run folder whose post/ cannot be made (here a file stands there) is bad input naming the
// folder (it ended in an uncaught filesystem error, exit 3).
TEST(BrecciaPostCli, PostFolderThatCannotBeMadeIsBadInputNamingIt) {
  const fs::path dir = fs::path(::testing::TempDir()) / "post_unwritable";
  bt::write_run(cracked_cubes(dir));
  fs::remove_all(dir / "post");
  std::ofstream(dir / "post") << "a file, not a folder\n";
  const Result r = run_post("'" + dir.string() + "' --no-plots");
  EXPECT_EQ(r.code, kExitBadInput);
  EXPECT_NE(r.output.find("error: " + (dir / "post").string() + ": not writable"), std::string::npos) << r.output;
}

TEST(BrecciaPostCli, UnknownStepIsBadInputListingTheAvailableSteps) {
  const fs::path dir = fs::path(::testing::TempDir()) / "post_step";
  bt::write_run(cracked_cubes(dir));
  const Result r = run_post("'" + dir.string() + "' --step 50 --no-plots");
  EXPECT_EQ(r.code, kExitBadInput);
  EXPECT_NE(r.output.find("no output at step 50"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("2 outputs, steps 0 100"), std::string::npos) << r.output;
}

TEST(BrecciaPostCli, ProvenanceMismatchIsBadInputNamingBothFiles) {
  const fs::path dir = fs::path(::testing::TempDir()) / "post_provenance";
  auto run = cracked_cubes(dir);
  run.content_id_override = "0123456789abcdef";
  bt::write_run(run);
  const Result r = run_post("'" + dir.string() + "' --no-plots");
  EXPECT_EQ(r.code, kExitBadInput);
  EXPECT_NE(r.output.find((dir / "results.h5").string() + ": /@particles_content_id: '0123456789abcdef'"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find((dir / "particles.h5").string()), std::string::npos) << r.output;
  // The library says the same through InputError, naming the field.
  try {
    postproc::open_run(dir);
    FAIL() << "open_run accepted a mismatched particles file";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "/@particles_content_id");
  }
}

// Replace one dataset of a written results.h5 (malformed-input tests); dims: its shape (by
// default one row of every value).
template <class T>
void replace_dataset(const fs::path& results, const std::string& name, const std::vector<T>& data,
                     std::vector<hsize_t> dims = {}) {
  h5::File f(results.string(), h5::File::Mode::ReadWrite);
  H5Ldelete(f.id(), name.c_str(), H5P_DEFAULT);
  f.write(name, data, dims.empty() ? std::vector<hsize_t>{data.size()} : dims);
}

TEST(BrecciaPostCli, BondPartnerOutOfRangeIsBadInputNamingTheDataset) {
  const fs::path dir = fs::path(::testing::TempDir()) / "post_bad_partner";
  const auto run = cracked_cubes(dir);
  bt::write_run(run);
  std::vector<int32_t> partners;
  {
    h5::File f((dir / "results.h5").string(), h5::File::Mode::Read);
    partners = f.read_int32("/bonds/neighbors");
  }
  partners.at(3) = static_cast<int32_t>(run.model.size() + 5);
  replace_dataset(dir / "results.h5", "/bonds/neighbors", partners);
  const Result r = run_post("'" + dir.string() + "' --no-plots --quiet");
  EXPECT_EQ(r.code, kExitBadInput);
  EXPECT_NE(r.output.find((dir / "results.h5").string() + ": /bonds/neighbors[3]: " +
                          std::to_string(run.model.size() + 5)),
            std::string::npos) << r.output;
}

// Drops the last byte of an output's broken bits in dir/results.h5; returns the bytes left.
size_t shorten_broken_bits(const fs::path& dir, const std::string& dataset) {
  std::vector<uint8_t> bits;
  {
    h5::File f((dir / "results.h5").string(), h5::File::Mode::Read);
    bits = f.read_uint8(dataset);
  }
  bits.pop_back();
  replace_dataset(dir / "results.h5", dataset, bits);
  return bits.size();
}

TEST(BrecciaPostCli, BrokenBitsOfTheWrongLengthAreBadInputNamingTheDataset) {
  const fs::path dir = fs::path(::testing::TempDir()) / "post_bad_bits";
  bt::write_run(cracked_cubes(dir));
  const size_t bytes = shorten_broken_bits(dir, "/output/000001/broken");
  const Result r = run_post("'" + dir.string() + "' --no-plots --quiet");
  EXPECT_EQ(r.code, kExitBadInput);
  EXPECT_NE(r.output.find((dir / "results.h5").string() + ": /output/000001/broken: size " + std::to_string(bytes)),
            std::string::npos) << r.output;
}

// An output only the crack history reads (not the last) is bad: on two threads that error
// comes from the history's thread, once, with exit code 2 (post.json is not written).
TEST(BrecciaPostCli, BadOutputReadBesideTheAnalysisIsBadInputReportedOnce) {
  const fs::path dir = fs::path(::testing::TempDir()) / "post_bad_history_output";
  bt::write_run(cracked_cubes(dir));
  const size_t bytes = shorten_broken_bits(dir, "/output/000000/broken");
  const Result r = run_post("'" + dir.string() + "' --no-plots --quiet --threads 2");
  EXPECT_EQ(r.code, kExitBadInput);
  const std::string expected = (dir / "results.h5").string() + ": /output/000000/broken: size " + std::to_string(bytes);
  const size_t at = r.output.find(expected);
  ASSERT_NE(at, std::string::npos) << r.output;
  EXPECT_EQ(r.output.find(expected, at + 1), std::string::npos) << "reported twice:\n" << r.output;
  EXPECT_FALSE(fs::exists(dir / "post" / "post.json"));
}

TEST(BrecciaPostCli, BrokenCountThatDisagreesWithTheBitsIsBadInput) {
  const fs::path dir = fs::path(::testing::TempDir()) / "post_bad_count";
  bt::write_run(cracked_cubes(dir));
  {
    h5::File f((dir / "results.h5").string(), h5::File::Mode::ReadWrite);
    f.set_attr("/output/000001", "broken_count", 3LL);  // the cut breaks more than 3 bonds
  }
  const Result r = run_post("'" + dir.string() + "' --no-plots --quiet");
  EXPECT_EQ(r.code, kExitBadInput);
  EXPECT_NE(r.output.find("/output/000001/@broken_count: 3"), std::string::npos) << r.output;
}

TEST(BrecciaPostCli, FormatVersionOneIsBadInputAskingForANewRun) {
  const fs::path dir = fs::path(::testing::TempDir()) / "post_version1";
  bt::write_run(cracked_cubes(dir));
  {
    h5::File f((dir / "results.h5").string(), h5::File::Mode::ReadWrite);
    f.set_attr("/", "format_version", 1LL);
  }
  const Result r = run_post("'" + dir.string() + "' --no-plots --quiet");
  EXPECT_EQ(r.code, kExitBadInput);
  EXPECT_NE(r.output.find("/@format_version: 1 (expected 2"), std::string::npos) << r.output;
}

TEST(BrecciaPostCli, UnknownProbeIsBadInputListingTheProbes) {
  const fs::path dir = fs::path(::testing::TempDir()) / "post_probe";
  bt::write_run(cracked_cubes(dir));
  write_history(dir, 0.0);
  const Result r = run_post("'" + dir.string() + "' --spectrum B --no-plots");
  EXPECT_EQ(r.code, kExitBadInput);
  EXPECT_NE(r.output.find("one of the probes in the header: A"), std::string::npos) << r.output;
}

TEST(BrecciaPostCli, EnergyWithoutHistoryIsBadInput) {
  const fs::path dir = fs::path(::testing::TempDir()) / "post_nohistory";
  bt::write_run(cracked_cubes(dir));
  const Result r = run_post("'" + dir.string() + "' --energy --no-plots");
  EXPECT_EQ(r.code, kExitBadInput);
  EXPECT_NE(r.output.find("history.csv: file does not exist"), std::string::npos) << r.output;
}

// --help, --version, and usage errors (exit 2 naming the option): the tools' shared contract.
TEST(BrecciaPostCli, FollowsTheToolsCommandLineContract) {
  breccia::testing::expect_cli_contract(BRECCIA_POST_EXE, "breccia-post", "somewhere --quiet",
                                        {{"--step", "1.5"},
                                         {"--step", "-1"},
                                         {"--min-fragment-particles", "0"},
                                         {"--damage-threshold", "0.5x"},
                                         {"--frequency", "2 parsecs"},
                                         {"--threads", "0"}});
}

TEST(BrecciaPostCli, UnknownOptionIsBadInput) {
  const Result r = run_post("somewhere --frobnicate");
  EXPECT_EQ(r.code, kExitBadInput);
  EXPECT_NE(r.output.find("--frobnicate: unknown option"), std::string::npos) << r.output;
}

namespace {

// 0 ... 6 us at 10 ns: inside [1, 4] us a 2 MHz sine of 10 nm plus 1 nm at 6 MHz, outside it a
// 50 nm tone at 1.3 MHz that a gate on [1, 4] us must leave out.
void write_gated_history(const fs::path& dir) {
  std::ostringstream s;
  s << "step,time_s,probe_A_ux\n";
  for (int k = 0; k <= 600; ++k) {
    const double t = k * 1e-8;
    const bool inside = k >= 100 && k <= 400;
    const double u = inside ? 1e-8 * (std::sin(2 * std::numbers::pi * 2e6 * t) + 0.1 * std::sin(2 * std::numbers::pi * 6e6 * t))
                            : 5e-8 * std::sin(2 * std::numbers::pi * 1.3e6 * t);
    s << k << ',' << t << ',' << u << '\n';
  }
  std::ofstream(dir / "history.csv") << s.str();
}

}  // namespace

// Gate [0.995, 4.005] us (edges between samples: rows 100-400), symmetric Hann, bins <= 20 kHz,
// peaks within +-0.3 MHz: the 3rd-harmonic ratio is the 0.1 put in, to 1 % (scalloping at
// 20 kHz bins and the Hann sidelobes of the 2 MHz tone 4 MHz away are below 0.2 %); without
// the gate the 50 nm, 1.3 MHz tone outside it dominates the 2 MHz band's neighbourhood.
TEST(BrecciaPostCli, GatedSpectrumReadsTheHarmonicsInsideTheGate) {
  const fs::path dir = fs::path(::testing::TempDir()) / "post_gate";
  bt::write_run(cracked_cubes(dir));
  write_gated_history(dir);
  const Result r = run_post("'" + dir.string() + "' --spectrum A --frequency 2e6 --hann --gate 0.995e-6,4.005e-6 "
                            "--resolution 20e3 --band 0.3e6 --no-plots --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  const std::string json = bt::read_text(dir / "post" / "post.json");
  EXPECT_EQ(nlohmann::json::parse(json).at("spectra").at(0).at("window"), "hann_symmetric") << json;
  EXPECT_EQ(json_number(json, "samples", "\"spectra\""), 301);
  EXPECT_EQ(json_number(json, "transform_length", "\"spectra\""), 8192);  // >= 1 / (20 kHz x 10 ns) = 5000
  EXPECT_NEAR(json_number(json, "reference_amplitude", "\"spectra\""), 1e-8, 1e-10);
  EXPECT_NEAR(bt::first_spectrum_harmonic_ratio(json, 3), 0.1, 1e-3);
}

TEST(BrecciaPostCli, GateOutsideTheRecordOrReversedIsBadInputNamingTheOption) {
  const fs::path dir = fs::path(::testing::TempDir()) / "post_gate_bad";
  bt::write_run(cracked_cubes(dir));
  write_gated_history(dir);
  const Result outside = run_post("'" + dir.string() + "' --spectrum A --gate 1e-6,9e-6 --no-plots --quiet");
  EXPECT_EQ(outside.code, kExitBadInput);
  EXPECT_NE(outside.output.find("--gate"), std::string::npos) << outside.output;
  EXPECT_NE(outside.output.find("a gate inside the record"), std::string::npos) << outside.output;
  const Result reversed = run_post("'" + dir.string() + "' --spectrum A --gate 4e-6,1e-6 --no-plots --quiet");
  EXPECT_EQ(reversed.code, kExitBadInput);
  EXPECT_NE(reversed.output.find("--gate: '4e-6,1e-6'"), std::string::npos) << reversed.output;
  const Result one = run_post("'" + dir.string() + "' --spectrum A --gate 1e-6 --no-plots --quiet");
  EXPECT_EQ(one.code, kExitBadInput);
  EXPECT_NE(one.output.find("T0,T1"), std::string::npos) << one.output;
  const Result alone = run_post("'" + dir.string() + "' --gate 1e-6,2e-6 --no-plots --quiet");
  EXPECT_EQ(alone.code, kExitBadInput);
  EXPECT_NE(alone.output.find("--gate: without --spectrum"), std::string::npos) << alone.output;
}

// --frequency must name a frequency the record resolves: above 0 and at most its Nyquist
// frequency (samples every 10 ns: 50 MHz); a probe value that is not finite is bad input too.
TEST(BrecciaPostCli, FrequencyOutsideTheRecordOrANonFiniteProbeValueIsBadInput) {
  const fs::path dir = fs::path(::testing::TempDir()) / "post_frequency_bad";
  bt::write_run(cracked_cubes(dir));
  write_gated_history(dir);
  for (const char* f : {"-2e5", "0", "1e12"}) {
    const Result r = run_post("'" + dir.string() + "' --spectrum A --frequency " + f + " --no-plots --quiet");
    EXPECT_EQ(r.code, kExitBadInput) << f;
    EXPECT_NE(r.output.find("--frequency"), std::string::npos) << r.output;
  }
  const Result nyquist = run_post("'" + dir.string() + "' --spectrum A --frequency 60e6 --no-plots --quiet");
  EXPECT_NE(nyquist.output.find("Nyquist frequency"), std::string::npos) << nyquist.output;
  std::string h = bt::read_text(dir / "history.csv");
  const size_t row = h.find("\n200,");
  ASSERT_NE(row, std::string::npos);
  const size_t value = h.rfind(',', h.find('\n', row + 1)) + 1;
  h.replace(value, h.find('\n', row + 1) - value, "nan");
  std::ofstream(dir / "history.csv") << h;
  const Result nan = run_post("'" + dir.string() + "' --spectrum A --no-plots --quiet");
  EXPECT_EQ(nan.code, kExitBadInput);
  EXPECT_NE(nan.output.find("probe_A_ux: nan at t = 2e-06 s"), std::string::npos) << nan.output;
}

// Positions stored as 3 x N hold 3N numbers like N x 3 but would be read as garbage.
TEST(BrecciaPostCli, PositionsOfTheWrongShapeAreBadInputNamingTheDataset) {
  const fs::path dir = fs::path(::testing::TempDir()) / "post_bad_shape";
  const auto run = cracked_cubes(dir);
  bt::write_run(run);
  std::vector<double> x;
  {
    h5::File f((dir / "results.h5").string(), h5::File::Mode::Read);
    x = f.read_doubles("/particles/position");
  }
  replace_dataset(dir / "results.h5", "/particles/position", x, {3, run.model.size()});
  const Result r = run_post("'" + dir.string() + "' --no-plots --quiet");
  EXPECT_EQ(r.code, kExitBadInput);
  EXPECT_NE(r.output.find("/particles/position: shape 3 x " + std::to_string(run.model.size())), std::string::npos)
      << r.output;
}


// A uniform record as breccia-solve prints it (times to 10 significant digits) is uniform,
// however long: past about 2,000 rows the printed times' rounding exceeded 1e-6 of a step
// and every long record was reported resampled (and interpolated).
TEST(BrecciaPostCli, ALongUniformRecordPrintedToTenDigitsIsNotResampled) {
  const fs::path dir = fs::path(::testing::TempDir()) / "post_long_record";
  bt::write_run(cracked_cubes(dir));
  std::ostringstream s;
  s << "step,time_s,probe_A_ux\n";
  const double dt = 9.109082355e-9;
  for (int k = 0; k < 5000; ++k) {
    char row[96];
    std::snprintf(row, sizeof row, "%d,%.9e,%.9e\n", k, k * dt, std::sin(2 * std::numbers::pi * k / 250.0));
    s << row;
  }
  std::ofstream(dir / "history.csv") << s.str();
  const Result r = run_post("'" + dir.string() + "' --spectrum A --no-plots --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json post = nlohmann::json::parse(bt::read_text(dir / "post" / "post.json"));
  EXPECT_EQ(post.at("spectra").at(0).at("resampled"), false);
}
