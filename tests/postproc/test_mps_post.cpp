// breccia-post on MPS runs (results.h5 format 2 written by solver/mps/src/results_output.cpp):
// a straight spall-like crack across a strip (fragments equal to the solver's own `fragment`
// field, crack area = width x thickness), the same strip without fracture (one fragment, no
// crack), a frictional crack as a pre-crack of its length, the spectrum of a probe that follows a known sine, and the refusal of an old
// (format 1) MPS results file with the message a PD one gets.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <numbers>
#include <sstream>

#include "breccia/common/csv.hpp"
#include "breccia/common/h5.hpp"
#include "breccia/postproc/bond_graph.hpp"
#include "breccia/postproc/history.hpp"
#include "breccia/postproc/mps_history.hpp"
#include "breccia/postproc/run_data.hpp"
#include "breccia/postproc/spectrum.hpp"
#include "real_run.hpp"

using namespace breccia;
using namespace breccia::postproc;
namespace fs = std::filesystem;
using breccia::postproc::testing::json_number;
using breccia::postproc::testing::read_text;

namespace {

struct Result {
  int code = -1;
  std::string output;
};

Result shell(const std::string& cmd) {
  Result r;
  FILE* p = popen((cmd + " 2>&1").c_str(), "r");
  std::array<char, 4096> buf{};
  while (fgets(buf.data(), buf.size(), p)) r.output += buf.data();
  const int status = pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

std::string q(const fs::path& p) { return "'" + p.string() + "'"; }

fs::path scratch(const std::string& tag) {
  const fs::path dir = fs::temp_directory_path() / (tag + "_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// Solve `yaml` with breccia-solve (model: mps) into dir/run, then breccia-post with `post_args`.
// Returns post.json ("" and a test failure when a tool fails).
std::string solve_and_post(const fs::path& dir, const std::string& yaml, const std::string& post_args) {
  std::ofstream(dir / "case.yaml") << yaml;
  const Result solve = shell(q(BRECCIA_SOLVE_EXE) + " " + q(dir / "case.yaml") + " -o " + q(dir / "run"));
  EXPECT_EQ(solve.code, 0) << solve.output;
  if (solve.code != 0) return "";
  const Result post = shell(q(BRECCIA_POST_EXE) + " " + q(dir / "run") + " --no-plots --quiet " + post_args);
  EXPECT_EQ(post.code, 0) << post.output;
  return post.code == 0 ? read_text(dir / "run" / "post" / "post.json") : "";
}

// A 60 x 6 mm strip (1 mm lattice, 1 mm thick, E = 1 GPa, nu = 0, rho = 1000: c = 1000 m/s)
// moving at 1.1 m/s along x with its left column held in x: a tensile step of
// rho c v = 1.1 MPa starts at the held end. With fracture (strength 1 MPa) the strip breaks
// there across its width: measured, the crack runs between the 3rd and 4th columns in every
// row (18 particles stay at the clamp).
std::string strip_case(bool fracture) {
  std::string yaml = R"(specimen:
  lattice: {dimension: 2, box: [0, 0, 60 mm, 6 mm], spacing: 1 mm, thickness: 1 mm}
model: {type: mps, formulation: stress}
materials:
  - name: brittle
    density: 1000
    youngs_modulus: 1 GPa
    poisson_ratio: 0
)";
  if (fracture) yaml += "    fracture: {tensile_strength: 1 MPa}\n";
  yaml += R"(initial: {velocity: [1.1, 0]}
boundary:
  - {name: clamp, face: left, components: [x]}
time: {end: 20 us, safety: 0.3}
output: {every: 20, history_every: 10, energy: true, progress: false}
)";
  return yaml;
}

constexpr double kH = 1e-3, kWidth = 6e-3, kThickness = 1e-3;

// The solver's `fragment` labels and post's union-find components are the same partition
// of the particles when a bijection maps one set of labels onto the other.
bool same_partition(const std::vector<int32_t>& a, const std::vector<int32_t>& b) {
  if (a.size() != b.size()) return false;
  std::map<int32_t, int32_t> ab, ba;
  for (size_t i = 0; i < a.size(); ++i) {
    const auto [it, fresh] = ab.try_emplace(a[i], b[i]);
    const auto [jt, fresh2] = ba.try_emplace(b[i], a[i]);
    if (it->second != b[i] || jt->second != a[i]) return false;
  }
  return true;
}

// fragments.csv: the volume_m3 column, sorted.
std::vector<double> fragment_volumes(const fs::path& csv) {
  const breccia::CsvColumns t = breccia::read_csv_columns(csv, {});
  const auto at = std::find(t.names.begin(), t.names.end(), "volume_m3");
  if (at == t.names.end()) return {};
  std::vector<double> v = t.columns[static_cast<size_t>(at - t.names.begin())];
  std::sort(v.begin(), v.end());
  return v;
}

}  // namespace

TEST(MpsPost, StraightCrackAcrossAStripGivesTheSolversFragmentsAndWidthTimesThickness) {
  const fs::path dir = scratch("mps_post_crack");
  const std::string json = solve_and_post(dir, strip_case(true), "");
  ASSERT_FALSE(json.empty());
  const fs::path run_dir = dir / "run";
  const RunData run = open_run(run_dir);
  EXPECT_EQ(run.model, "mps");
  ASSERT_GE(run.outputs.size(), 2u);
  const OutputFrame last = read_output(run, run.outputs.size() - 1);
  // The broken bits are the solver's cut bonds: summary.json counts cut pairs.
  const double cut = json_number(read_text(run_dir / "summary.json"), "cut_bonds");
  EXPECT_EQ(static_cast<double>(last.broken_count), cut);
  EXPECT_GT(last.broken_count, 0u);
  // Post's union-find over the intact bonds and the solver's own labels: the same pieces.
  int32_t count = 0;
  const std::vector<int32_t> comp =
      intact_components(run.bonds, run.within_horizon, last.broken, RemovedBonds(run.precrack_bonds, run.size()), &count);
  h5::File f((run_dir / "results.h5").string(), h5::File::Mode::Read);
  const std::vector<int32_t> solver_labels = f.read_int32(last.info.group + "/fragment");
  EXPECT_TRUE(same_partition(comp, solver_labels));
  EXPECT_EQ(count, 2);
  EXPECT_EQ(json_number(json, "fragment_count"), 2.0);
  EXPECT_EQ(json_number(json, "solver_fragment_mismatches"), 0.0);  // post's own check of the same
  // Volumes per piece: post's fragments.csv against the solver's labels summed here (the two
  // sums add the same particle volumes in another order: 1e-12 relative).
  std::map<int32_t, double> volume;
  for (size_t i = 0; i < run.size(); ++i) volume[solver_labels[i]] += run.volume_m3[i];
  std::vector<double> expected;
  for (const auto& [label, v] : volume) expected.push_back(v);
  std::sort(expected.begin(), expected.end());
  const std::vector<double> got = fragment_volumes(run_dir / "post" / "fragments.csv");
  ASSERT_EQ(got.size(), expected.size());
  for (size_t k = 0; k < got.size(); ++k) EXPECT_NEAR(got[k], expected[k], 1e-12 * expected[k]);
  EXPECT_NEAR(expected.front(), 18 * kH * kH * kThickness, 1e-12 * expected.front());  // 3 columns of 6
  // The crack: the faces between the two pieces are one lattice bisector (h x thickness) per
  // row, so the separating area is the width times the thickness, exactly up to rounding.
  const double wt = kWidth * kThickness;
  EXPECT_NEAR(json_number(json, "separating_fracture_area_m2"), wt, 1e-9 * wt);
  // All cut face bonds: the separating ones plus the few that the stencil cut beside the crack
  // line at the two free edges (measured: 3 faces); at most a face per row more.
  const double all = json_number(json, "fracture_area_m2");
  EXPECT_GE(all, wt * (1 - 1e-9));
  EXPECT_LE(all, 2 * wt);
  // MPS has no fracture energy: no G0 x area is invented.
  EXPECT_EQ(json.find("G0_times_fracture_area_J"), std::string::npos);
  EXPECT_NE(json.find("\"mps_terms\""), std::string::npos);
  fs::remove_all(dir);
}

TEST(MpsPost, StripWithoutFractureIsOneFragmentWithoutCrackAndBalancesItsEnergy) {
  const fs::path dir = scratch("mps_post_intact");
  const std::string json = solve_and_post(dir, strip_case(false), "");
  ASSERT_FALSE(json.empty());
  EXPECT_EQ(json_number(json, "fragment_count"), 1.0);
  EXPECT_EQ(json_number(json, "crack_area_m2"), 0.0);
  EXPECT_EQ(json_number(json, "crack_faces"), 0.0);
  // Loaded by its initial velocity against a held (motionless) column, the strip's kinetic +
  // stress work stays at the initial kinetic energy up to the time-stepping error (measured
  // 0.23%); 1% as for the other elastic MPS energy checks.
  EXPECT_LT(std::abs(json_number(json, "relative_imbalance")), 0.01);
  fs::remove_all(dir);
}

// A frictional crack of the displacement formulation ([MPS harmonics]) removes the stencil bonds
// across its segment: they are the run's pre-cracks, so post's crack surface is the segment,
// 4 mm long (8 lattice bisectors of 0.5 mm) times the 1 mm thickness, exactly; the crack is
// inside the plate, which stays one piece.
TEST(MpsPost, FrictionalCrackIsAPrecrackOfItsLengthTimesThickness) {
  const fs::path dir = scratch("mps_post_friction");
  const std::string yaml = R"(specimen:
  lattice: {dimension: 2, box: [0, 0, 10 mm, 10 mm], spacing: 0.5 mm, thickness: 1 mm}
model: {type: mps, re_over_spacing: 2.1, equation: navier}
materials:
  - {name: steel, density: 7850, C13: 121.1 GPa, C55: 80.8 GPa}
cracks:
  - {name: c, segment: [[3 mm, 5 mm], [7 mm, 5 mm]], static_friction: 0.6, kinetic_friction: 0.5,
     normal_stress: 3.2 MPa, mode: sliding}
time: {end: 0.5 us, safety: 0.5}
output: {every: 0, progress: false}
)";
  const std::string json = solve_and_post(dir, yaml, "--cracks --fragments");
  ASSERT_FALSE(json.empty());
  const double area = 4e-3 * 1e-3;
  EXPECT_NEAR(json_number(json, "precrack_area_m2"), area, 1e-9 * area);
  EXPECT_EQ(json_number(json, "fracture_area_m2"), 0.0);
  EXPECT_EQ(json_number(json, "fragment_count"), 1.0);
  const RunData run = open_run(dir / "run");
  EXPECT_GT(run.precrack_bonds.size(), 0u);
  fs::remove_all(dir);
}

// The left column of a displacement-formulation block follows u_y = A sin(2 pi t / T) for 8
// whole periods, and the run ends at 8 T; a probe on that column records the sine exactly
// (to the 10 digits of history.csv). Post's spectrum of it equals the transform of the
// analytic samples, and peaks at 1/T with amplitude A (a whole number of periods in the
// record, rectangular window).
TEST(MpsPost, SpectrumOfAProbeOnAKnownSineIsTheSinesSpectrum) {
  const fs::path dir = scratch("mps_post_sine");
  const double amplitude = 1e-8, period = 2e-6;
  const std::string yaml = R"(specimen:
  lattice: {dimension: 2, box: [0, 0, 10 mm, 4 mm], spacing: 0.5 mm, thickness: 1 mm}
model: {type: mps, re_over_spacing: 2.1, equation: navier}
materials:
  - {name: steel, density: 7850, C13: 121.1 GPa, C55: 80.8 GPa}
boundary:
  - name: shaker
    face: left
    components: [y]
    displacement: {type: sine_burst, amplitude: 1.0e-8, period: 2 us, cycles: 8}
time: {end: 16 us, dt: 0.025 us}
output:
  every: 0
  progress: false
  probes:
    - {name: S, position: [0.25 mm, 2.25 mm], field: displacement_y}
)";
  const std::string json = solve_and_post(dir, yaml, "--spectrum S");
  ASSERT_FALSE(json.empty());
  const History h = read_history(dir / "run" / "history.csv");
  const auto& t = h.column("time_s");
  ASSERT_GT(t.size(), 600u);
  std::vector<double> analytic;
  for (double ti : t) analytic.push_back(amplitude * std::sin(2 * std::numbers::pi * ti / period));
  const double dt = (t.back() - t.front()) / static_cast<double>(t.size() - 1);
  const Spectrum expected = amplitude_spectrum(analytic, dt, false, std::nullopt);
  // post/spectrum_S.csv: frequency_Hz, amplitude_uy, normalised_uy.
  std::ifstream in(dir / "run" / "post" / "spectrum_S.csv");
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "frequency_Hz,amplitude_uy,normalised_uy");
  size_t k = 0;
  while (std::getline(in, line) && k < expected.amplitude.size()) {
    double f = 0, a = 0, nrm = 0;
    ASSERT_EQ(std::sscanf(line.c_str(), "%lf,%lf,%lf", &f, &a, &nrm), 3) << line;
    EXPECT_NEAR(f, expected.frequency_Hz[k], 1e-9 * expected.frequency_Hz.back());
    // 10 significant digits in history.csv and post's CSV: 1e-8 of the peak.
    EXPECT_NEAR(a, expected.amplitude[k], 1e-8 * amplitude) << "bin " << k;
    ++k;
  }
  EXPECT_EQ(k, expected.amplitude.size());
  // The analytic answer itself: the peak at 1/T (one bin is 1/(16 us) = 62.5 kHz) with
  // amplitude A to within the leakage of the one extra sample (641 samples of 640 dt).
  EXPECT_NEAR(json_number(json, "reference_frequency_Hz"), 1.0 / period, 0.5 / (16e-6));
  EXPECT_NEAR(json_number(json, "reference_amplitude"), amplitude, 0.01 * amplitude);
  fs::remove_all(dir);
}

// The mapping of an MPS stress-formulation history onto post's balance terms (docs/postproc.md,
// "MPS runs"): a body falling under gravity onto a frictional floor. Each term is the
// documented sum of MPS columns, exactly; probes get post's names.
TEST(MpsPost, HistoryColumnsMapOntoTheBalanceTermsAsDocumented) {
  History mps;
  mps.path = "history.csv";
  mps.names = {"time_s", "drop_velocity_y", "kinetic_energy_J", "stress_work_J", "hourglass_energy_J",
               "contact_energy_J", "gravity_energy_J", "friction_dissipation_J"};
  mps.columns = {{0.0, 1e-3, 2e-3}, {-1.0, -1.5, -0.2}, {5.0, 6.0, 1.0}, {0.0, 0.5, 2.0},
                 {0.0, 0.1, 0.2},   {0.0, 0.0, 2.5},    {0.0, -1.5, -2.0}, {0.0, 0.0, 0.25}};
  const MpsHistoryMapping m = map_mps_history(mps);
  ASSERT_TRUE(m.energy);
  const History& h = m.history;
  EXPECT_EQ(h.probe_names(), std::vector<std::string>{"drop"});
  EXPECT_EQ(h.column("probe_drop_vy"), mps.column("drop_velocity_y"));
  const std::vector<double> strain{0.0, 0.6, 4.7}, external{5.0, 6.5, 7.0};
  EXPECT_EQ(h.column("kinetic_J"), mps.column("kinetic_energy_J"));
  for (size_t r = 0; r < 3; ++r) {
    EXPECT_DOUBLE_EQ(h.column("strain_J")[r], strain[r]);                // stress work + hourglass + contact
    EXPECT_DOUBLE_EQ(h.column("external_work_J")[r], external[r]);       // initial 5 J - gravity energy
    EXPECT_DOUBLE_EQ(h.column("dissipated_J")[r], mps.column("friction_dissipation_J")[r]);
  }
  // Nothing without the energy columns, and a note that says why.
  History bare;
  bare.names = {"time_s", "A_displacement_x"};
  bare.columns = {{0.0, 1.0}, {0.0, 2.0}};
  const MpsHistoryMapping none = map_mps_history(bare);
  EXPECT_FALSE(none.energy);
  EXPECT_FALSE(none.history.find("kinetic_J"));
  ASSERT_EQ(none.notes.size(), 1u);
  EXPECT_NE(none.notes[0].find("output.energy: false"), std::string::npos);
}

// Material damping (materials[].damping_ratio): its material_damping_J joins the friction in
// post's dissipated term, exactly.
TEST(MpsPost, MaterialDampingColumnJoinsTheDissipatedTerm) {
  History mps;
  mps.path = "history.csv";
  mps.names = {"time_s", "kinetic_energy_J", "stress_work_J", "hourglass_energy_J", "contact_energy_J",
               "gravity_energy_J", "friction_dissipation_J", "material_damping_J"};
  mps.columns = {{0.0, 1e-3}, {5.0, 3.0}, {0.0, 0.5}, {0.0, 0.1}, {0.0, 0.0}, {0.0, 0.0}, {0.0, 0.25}, {0.0, 1.15}};
  const MpsHistoryMapping m = map_mps_history(mps);
  ASSERT_TRUE(m.energy);
  EXPECT_DOUBLE_EQ(m.history.column("dissipated_J")[1], 1.4);
  bool documented = false;
  for (const auto& [term, expression] : m.terms)
    documented = documented || (term == "dissipated_J" && expression.find("material_damping_J") != std::string::npos);
  EXPECT_TRUE(documented);
}

// A results file of an old MPS run (format 1: groups named by step, no bond list) is refused
// with the message an old PD file gets.
TEST(MpsPost, OldFormatOneMpsResultsAreRefusedLikePdOnes) {
  const fs::path dir = scratch("mps_post_v1");
  std::ofstream(dir / "case.yaml") << strip_case(false);
  ASSERT_EQ(shell(q(BRECCIA_SOLVE_EXE) + " " + q(dir / "case.yaml") + " -o " + q(dir / "run")).code, 0);
  {
    // What the MPS writer of format 1 left: version 1, output groups named by step, no /bonds.
    h5::File f((dir / "run" / "results.h5").string(), h5::File::Mode::ReadWrite);
    f.set_attr("/", "format_version", 1LL);
    H5Ldelete(f.id(), "/bonds", H5P_DEFAULT);
    H5Lmove(f.id(), "/output/000001", f.id(), "/output/000067", H5P_DEFAULT, H5P_DEFAULT);
  }
  const Result mps = shell(q(BRECCIA_POST_EXE) + " " + q(dir / "run") + " --no-plots --quiet");
  EXPECT_EQ(mps.code, 2) << mps.output;
  {
    h5::File f((dir / "run" / "results.h5").string(), h5::File::Mode::ReadWrite);
    f.set_attr("/", "model", std::string("pmb"));
  }
  const Result pd = shell(q(BRECCIA_POST_EXE) + " " + q(dir / "run") + " --no-plots --quiet");
  EXPECT_EQ(pd.code, 2);
  EXPECT_EQ(mps.output, pd.output);
  EXPECT_NE(mps.output.find("/@format_version: 1 (expected 2 (version 1 files, PD ones with broken-bond pairs or MPS ones"), std::string::npos) << mps.output;
  fs::remove_all(dir);
}
