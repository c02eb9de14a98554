// Verification of breccia-plan (tools/plan, docs/plan.md): its cost estimate against what
// the solver actually sets up and spends, its proposals against the error they actually
// reach when run, and its handling of bad input.
//
// The atlas rows used by the proposal tests are measured here, by the same error measures
// the tests then apply to the proposed setups; the CLI tests use a small hand-written CSV
// fixture whose numbers are not results.
#include <gtest/gtest.h>
#include <omp.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>

#include "../common/cli_contract.hpp"
#include "breccia/common/error.hpp"
#include "breccia/common/particle_file.hpp"
#include "breccia/plan/plan.hpp"
#include "breccia/solver/run.hpp"
#include "helpers.hpp"
#include "measures.hpp"

using namespace breccia;
using namespace breccia::plan;
using solver::CaseConfig;
using solver::PdSystem;

namespace {

std::string temp_path(const std::string& name) { return breccia::solver::testing::process_temp_dir() + "/plan_" + name; }

CaseConfig case_from_yaml(const std::string& name, const std::string& yaml) {
  const std::string path = temp_path(name + ".yaml");
  std::ofstream(path) << yaml;
  return solver::parse_case_file(path);
}

double cpu_seconds() { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

int64_t nearest(const PdSystem& s, double x, double y) {
  int64_t best = 0;
  double bd = 1e300;
  for (size_t i = 0; i < s.n; ++i) {
    const double d = std::pow(s.x0[3 * i] - x, 2) + std::pow(s.x0[3 * i + 1] - y, 2);
    if (d < bd) {
      bd = d;
      best = static_cast<int64_t>(i);
    }
  }
  return best;
}

// Steps breccia-solve takes for time.end (run.cpp, total_steps_of).
long long solver_steps(const PdSystem& s) {
  return s.config.steps ? *s.config.steps : static_cast<long long>(std::ceil(*s.config.end_time / s.dt - 1e-9));
}

// Small dynamic cases of different dimension and model, each a second or two of CPU; the
// fourth is correspondence PD (docs/plan.md: its rate is its own, about 2x LPS's cost per bond).
const char* kCase2dPmb = R"(
specimen: {lattice: {dimension: 2, box: [0, 0, 0.1, 0.03], spacing: 0.4 mm, thickness: 1 mm}}
model: {type: pmb, planar: plane_strain, horizon_factor: 3.015}
materials: [{name: rock, density: 2600, youngs_modulus: 50 GPa, poisson_ratio: 0.25}]
initial: [{type: velocity, set: xmin, value: [1, 0, 0]}]
time: {end: 20 us}
output: {results: false}
)";
const char* kCase3dPmb = R"(
specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.016, 0.016, 0.016], spacing: 1 mm}}
model: {type: pmb, horizon_factor: 3.015}
materials: [{name: rock, density: 2600, youngs_modulus: 50 GPa, poisson_ratio: 0.25}]
initial: [{type: velocity, set: xmin, value: [1, 0, 0]}]
time: {end: 40 us}
output: {results: false}
)";
const char* kCase3dLps = R"(
specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.014, 0.014, 0.014], spacing: 1 mm}}
model: {type: lps, horizon_factor: 3.015}
materials: [{name: glass, density: 2440, youngs_modulus: 72 GPa, poisson_ratio: 0.22}]
initial: [{type: velocity, set: xmin, value: [1, 0, 0]}]
time: {end: 30 us}
output: {results: false}
)";
const char* kCase2dCorrespondence = R"(
specimen: {lattice: {dimension: 2, box: [0, 0, 0.04, 0.02], spacing: 0.4 mm, thickness: 1 mm}}
model: {type: correspondence, planar: plane_strain, horizon_factor: 3.015, stabilisation: {type: penalty, coefficient: 1}}
materials: [{name: rock, density: 2600, youngs_modulus: 50 GPa, poisson_ratio: 0.25}]
initial: [{type: velocity, set: xmin, value: [1, 0, 0]}]
time: {end: 10 us}
output: {results: false}
)";

}  // namespace

// ---- (1) the cost estimate ----------------------------------------------------------------

// The lattice bond count by family offsets (used when a case is too big to set up here)
// is exact, not an approximation: compared with the solver's families on boxes whose
// every side is shorter than, about, and longer than two horizons.
TEST(PlanCost, LatticeBondCountByOffsetsEqualsTheSolversFamilies) {
  const Throughputs rates = load_throughputs(default_throughputs_path());
  omp_set_num_threads(1);  // the machine running the tests is shared: no spinning thread teams
  CostOptions counted;
  counted.exact_step_limit = 0;  // take the path used for big cases
  int k = 0;
  for (const char* yaml : {R"(
specimen: {lattice: {dimension: 2, box: [0, 0, 0.02, 0.007], spacing: 0.5 mm, thickness: 1 mm}}
model: {type: pmb, planar: plane_stress, horizon_factor: 3.015}
materials: [{name: steel, density: 7850, youngs_modulus: 200 GPa, poisson_ratio: 0.3333333333333333}]
time: {steps: 1}
)",
                           R"(
specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.012, 0.005, 0.003], spacing: 0.5 mm}}
model: {type: pmb, horizon_factor: 4.015}
materials: [{name: steel, density: 7850, youngs_modulus: 200 GPa, poisson_ratio: 0.25}]
time: {steps: 1}
)"}) {
    const CaseConfig c = case_from_yaml("offsets" + std::to_string(k++), yaml);
    const CostEstimate e = estimate_cost(c, rates, counted);
    EXPECT_EQ(e.bonds, static_cast<long long>(solver::setup_system(c).bond_count())) << e.bonds_method;
  }
}

// The estimate's bytes per bond entry are what set-up allocates (PdSystem::bytes_per_bond_entry):
// a lattice with one horizon shares the dual halves (26 B with the sampled partial volume's
// own counts), 2D LPS with fracture stores them (38 B), softening adds its two floats.
TEST(PlanCost, BytesPerBondEntryAreWhatSetUpHolds) {
  const Throughputs rates = load_throughputs(default_throughputs_path());
  omp_set_num_threads(1);
  int k = 0;
  for (const char* yaml : {R"(
specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.004, 0.003, 0.003], spacing: 0.5 mm}}
model: {type: pmb, horizon_factor: 3.015}
materials: [{name: glass, density: 2440, youngs_modulus: 72 GPa, poisson_ratio: 0.25, fracture_energy: 3.8}]
time: {steps: 1}
)",
                           R"(
specimen: {lattice: {dimension: 2, box: [0, 0, 0.006, 0.004], spacing: 0.5 mm}}
model: {type: lps, planar: plane_strain, horizon_factor: 3.015}
materials: [{name: glass, density: 2440, youngs_modulus: 72 GPa, poisson_ratio: 0.25, fracture_energy: 3.8}]
time: {steps: 1}
)",
                           R"(
specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.004, 0.003, 0.003], spacing: 0.5 mm}}
model: {type: pmb, horizon_factor: 3.015}
materials: [{name: rock, density: 2660, youngs_modulus: 50 GPa, poisson_ratio: 0.25, fracture_energy: 200, tensile_strength: 12 MPa}]
time: {steps: 1}
)"}) {
    const CaseConfig c = case_from_yaml("entry_bytes" + std::to_string(k++), yaml);
    const CostEstimate e = estimate_cost(c, rates);
    const solver::PdSystem sys = solver::setup_system(c);
    // bytes_per_bond_entry leaves out softening's s_onset and bond_damage (a float each).
    const size_t softening = sys.s_onset.empty() ? 0 : sizeof(float) * (sys.s_onset.size() + sys.bond_damage.size()) / sys.state.size();
    EXPECT_EQ(e.bond_entry_bytes, static_cast<double>(sys.bytes_per_bond_entry() + softening)) << "case " << k;
  }
}

// The estimate on three cases of different dimension and model. Particles, bonds and steps
// of a case small enough to set up are the solver's own numbers and must equal them
// exactly. Seconds must be within a factor 1.5 of the measured cost, with the throughput
// calibrated on this machine in this test: not a test of the solver's speed (the rate is
// measured, whatever it is) but of the cost model, that bond entries x steps plus set-up
// (power iteration and per-bond work) predicts cases of another size, shape and model than
// the calibration block. Timed in process CPU seconds on one thread.
//
// Best of three, interleaved: calibration and measurement alternate three times and each
// side keeps its fastest sample (highest rate, shortest time). CPU seconds are not immune
// to a neighbour on the other core (shared cache and memory bandwidth, clock changes): in
// one CI run a single calibration landed in a busy second and came out 1.5x slow against
// the run it predicted. The fastest of three is the usual estimator of a code's own cost
// on a shared machine; both sides get the same treatment, so the ratio still tests the model.
TEST(PlanCost, CountsAreExactAndSecondsWithinAFactorOnePointFiveOnThreeCases) {
  const Throughputs documented = load_throughputs(default_throughputs_path());
  constexpr int kSamples = 3;
  int k = 0;
  for (const char* yaml : {kCase2dPmb, kCase3dPmb, kCase3dLps, kCase2dCorrespondence}) {
    const CaseConfig c = case_from_yaml("timed" + std::to_string(k++), yaml);
    Throughputs rates;
    double setup_s = 1e300, loop_s = 1e300;
    for (int sample = 0; sample < kSamples; ++sample) {
      const Throughputs r_cal = calibrate(c, 1, documented, 0.5e6, 0.4);
      if (sample == 0) {
        rates = r_cal;
      } else {
        if (r_cal.rate(c.model, 1).bond_updates_per_core_s > rates.rate(c.model, 1).bond_updates_per_core_s)
          rates.loop = r_cal.loop;
        rates.setup_bonds_per_core_s = std::max(rates.setup_bonds_per_core_s, r_cal.setup_bonds_per_core_s);
      }

      omp_set_num_threads(1);
      const double t0 = cpu_seconds();
      PdSystem s = solver::setup_system(c);
      setup_s = std::min(setup_s, cpu_seconds() - t0);
      if (sample == 0) {
        const CostEstimate e = estimate_cost(c, documented);
        EXPECT_EQ(e.particles, static_cast<long long>(s.n));
        EXPECT_EQ(e.bonds, static_cast<long long>(s.bond_count()));
        EXPECT_EQ(e.steps, solver_steps(s));
      }
      solver::RunOptions o;
      o.progress = false;
      o.out_dir = temp_path("timed_run" + std::to_string(k) + "_" + std::to_string(sample));
      const solver::RunResult r = solver::run_system(s, o);
      ASSERT_EQ(r.status, "completed");
      loop_s = std::min(loop_s, r.cpu_s);
    }
    omp_set_num_threads(1);
    const CostEstimate e = estimate_cost(c, rates);
    const double measured = setup_s + loop_s;
    std::printf("case %d: estimated %.3g s (set-up %.3g + loop %.3g), measured %.3g s (set-up %.3g + loop %.3g), best of %d\n",
                k, e.total_s(), e.setup_s, e.loop_s, measured, setup_s, loop_s, kSamples);
    // 1.5: the issue's acceptance band for the planner's cost estimate (set-up + time loop,
    // what the user waits for). The loop alone is printed, not checked: loops this short
    // (a few tenths of a second) vary by more than 1.5x on a loaded machine.
    EXPECT_NEAR(std::log(e.total_s() / measured), 0.0, std::log(1.5))
        << "case " << k << ": estimated " << e.total_s() << " s (set-up " << e.setup_s << " + loop " << e.loop_s
        << "), measured " << measured << " s (set-up " << setup_s << " + loop " << loop_s << ")";
  }
}

// ---- (2) proposals meet the tolerance when run ------------------------------------------

namespace {

// The two problems and their error measures as the atlas sweeps them
// (tools/atlas/problems.cpp, wave_speed_bar and quasi_static_bar), so that rows measured
// here mean what the atlas's rows mean: same strips, same settings (PMB and LPS with the
// energy surface correction), same measures.
constexpr double kSteelE = 200e9, kSteelRho = 7850;

// Wave-speed bar: plane-stress strip 100 x 10 mm; the fundamental free-free mode
// u = A cos(pi x / L) has period 2 L / c0 with c0 = sqrt(E / rho) (uniaxial stress);
// error = |c / c0 - 1| from the first zero crossing of the modal amplitude (a quarter period).
constexpr double kWaveL = 0.1, kWaveW = 0.01;
constexpr const char* kWaveMeasure = "|c/c0-1| of the fundamental mode period; 2D plane stress strip 100x10 mm";

std::string model_line(const std::string& model, double m) {
  std::ostringstream y;
  y << "model: {type: " << model << ", planar: plane_stress, horizon_factor: " << m
    << ", surface_correction: energy}\n";
  return y.str();
}

std::string wave_bar_yaml(const std::string& model, double spacing) {
  std::ostringstream y;
  y << "specimen: {lattice: {dimension: 2, box: [0, 0, " << kWaveL << ", " << kWaveW << "], spacing: " << spacing
    << ", thickness: 1 mm}}\n"
    << model_line(model, 3.015)
    << "materials: [{name: steel, density: 7850, youngs_modulus: 200 GPa, poisson_ratio: 0.3333333333333333}]\n"
    << "time: {steps: 1}\n";
  return y.str();
}

double wave_speed_error(PdSystem& s) {
  return atlas::fundamental_mode_speed_error(s, kWaveL, std::sqrt(kSteelE / kSteelRho));
}

// Quasi-static bar: plane-stress strip 100 x 20 mm, xmin held in x (the corner particle
// also in y), 100 MPa traction on xmax, relaxed by ADR; the free end moves sigma L_eff / E
// with L_eff the distance between the held and the loaded layers;
// error = |u_end / (sigma L_eff / E) - 1|. This is the atlas's set-up and measure before
// 2026-12-04 (single end layers; the atlas now loads and grips one horizon deep and reads the
// span between, docs/atlas.md): kept here, where the rows and the proposal are measured alike.
constexpr const char* kStaticMeasure = "|u_end / (sigma L / E) - 1| by ADR; 2D plane stress strip 100x20 mm";

std::string static_bar_yaml(const std::string& model, double spacing) {
  std::ostringstream y;
  y << "specimen: {lattice: {dimension: 2, box: [0, 0, 0.1, 0.02], spacing: " << spacing << ", thickness: 1 mm}}\n"
    << model_line(model, 3.015)
    << "materials: [{name: steel, density: 7850, youngs_modulus: 200 GPa, poisson_ratio: 0.3333333333333333}]\n"
    << "boundary: [{type: fixed, set: xmin, components: [x]}]\n"
    << "loads: [{type: traction, surface: xmax, value: [100 MPa, 0, 0]}]\n"
    << "time: {integrator: adr, adr_tolerance: 1e-7, adr_max_steps: 400000}\noutput: {results: false}\n";
  return y.str();
}

double static_strain_error(PdSystem& s) {
  const double error = atlas::bar_end_displacement_error(s, 100e6, kSteelE);
  return error < 0 ? 1.0 : error;  // ADR not converged counts as a miss
}

// Measure one problem at several spacings and models; write the rows as atlas.csv does.
template <class YamlOf, class ErrorOf>
std::vector<AtlasRow> measure_rows(const std::string& problem, const std::string& measure, YamlOf yaml_of,
                                   ErrorOf error_of, const std::vector<std::string>& models,
                                   const std::vector<double>& spacings) {
  std::vector<AtlasRow> rows;
  for (const auto& model : models)
    for (double h : spacings) {
      const double t0 = cpu_seconds();
      PdSystem s = solver::setup_system(case_from_yaml(problem + model + std::to_string(h), yaml_of(model, h)));
      AtlasRow r;
      r.problem = problem;
      r.model = model;
      r.dimension = 2;
      r.particles_kind = "lattice";
      r.m = 3.015;
      r.spacing_m = h;
      r.precision = "float64";
      r.backend = "cpu";
      r.threads = 1;
      r.particles = static_cast<long long>(s.n);
      r.bonds = static_cast<long long>(s.bond_count());
      r.error = error_of(s);
      r.steps = s.step;
      r.wall_s = cpu_seconds() - t0;
      r.error_measure = measure;
      rows.push_back(r);
    }
  return rows;
}

std::string write_atlas(const std::string& name, const std::vector<AtlasRow>& rows) {
  const std::string path = temp_path(name + ".csv");
  std::ofstream out(path);
  out << "problem,model,dimension,particles_kind,m,spacing_m,precision,backend,threads,particles,bonds,steps,wall_s,"
         "error,error_measure\n";
  for (const auto& r : rows)
    out << r.problem << ',' << r.model << ',' << r.dimension << ',' << r.particles_kind << ',' << r.m << ','
        << r.spacing_m << ',' << r.precision << ',' << r.backend << ',' << r.threads << ',' << r.particles << ','
        << r.bonds << ',' << r.steps << ',' << r.wall_s << ',' << r.error << ",\"" << r.error_measure << "\"\n";
  return path;
}

// The fine user cases are planned the way big cases are (stable step from a sample block,
// bonds counted by lattice offsets) rather than set up whole: the same code path a real
// large case takes, and a short test.
CostOptions large_case_path() {
  CostOptions o;
  o.exact_step_limit = 20'000;
  return o;
}
const CostOptions kLargeCasePath = large_case_path();

// A tolerance just above the largest measured PMB error below the coarsest setting: every
// setting from the second-coarsest down meets it, the coarsest may or may not (the errors
// are not monotone in spacing), so the planner must choose (not a number fixed in advance).
double tolerance_between(const std::vector<AtlasRow>& rows) {
  double coarsest_spacing = 0;
  for (const auto& r : rows)
    if (r.model == "pmb") coarsest_spacing = std::max(coarsest_spacing, r.spacing_m);
  double error = 0;
  for (const auto& r : rows)
    if (r.model == "pmb" && r.spacing_m < coarsest_spacing) error = std::max(error, r.error);
  return 1.05 * error;
}

}  // namespace

// A 3D LPS strip, thin in z with free z faces and nothing acting along z: the planner must
// see that plane stress is enough and pick the model and spacing the measured
// atlas says meet the tolerance most cheaply. Run as proposed, the proposal must meet it.
TEST(PlanProposal, WaveSpeedProposalMeetsTheToleranceWhenRun) {
  omp_set_num_threads(1);
  const auto rows = measure_rows("wave_speed_bar", kWaveMeasure, wave_bar_yaml,
                                 [](PdSystem& s) { return wave_speed_error(s); }, {"pmb", "lps"}, {2e-3, 1e-3, 5e-4});
  for (const auto& r : rows) std::printf("atlas row: %s h %.2g m: error %.4g\n", r.model.c_str(), r.spacing_m, r.error);
  const auto atlas = read_atlas(write_atlas("wave_atlas", rows));
  const double tol = tolerance_between(rows);
  const CaseConfig user = case_from_yaml("wave_user", R"(
specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.1, 0.01, 0.001], spacing: 0.25 mm}}
model: {type: lps, horizon_factor: 3.015}
materials: [{name: steel, density: 7850, youngs_modulus: 200 GPa, poisson_ratio: 0.3333333333333333}]
time: {end: 20 us}
output: {results: false}
)");
  const Throughputs rates = load_throughputs(default_throughputs_path());
  const Proposal p = propose(user, atlas, tol, rates, kLargeCasePath);
  for (const auto& line : p.reasoning) std::printf("  %s\n", line.c_str());
  ASSERT_TRUE(p.tolerance_met);
  EXPECT_EQ(p.dimension, 2);
  const std::string proposed = temp_path("wave_proposed.yaml");
  write_proposed_case(user, p, proposed);
  const CaseConfig back = solver::parse_case_file(proposed);
  EXPECT_TRUE(back.surface_correction) << "the rows ran with the correction, so must the proposal (" << p.model << ")";
  PdSystem s = solver::setup_system(back);
  const double error = wave_speed_error(s);
  std::printf("tolerance %.4g: proposed spacing %.4g m, measured error %.4g\n", tol, p.spacing_m, error);
  EXPECT_LE(error, tol);
}

// A fine 2D LPS bar relaxed by ADR: the planner coarsens to what the measured atlas needs
// (PMB is allowed too, nu = 1/3 in plane stress); run as proposed, the interior strain must
// be within the tolerance of sigma/E.
TEST(PlanProposal, QuasiStaticBarProposalMeetsTheToleranceWhenRun) {
  omp_set_num_threads(1);
  const auto rows = measure_rows("quasi_static_bar", kStaticMeasure, static_bar_yaml,
                                 [](PdSystem& s) { return static_strain_error(s); }, {"pmb", "lps"}, {4e-3, 2e-3, 1e-3});
  for (const auto& r : rows) std::printf("atlas row: %s h %.2g m: error %.4g\n", r.model.c_str(), r.spacing_m, r.error);
  const auto atlas = read_atlas(write_atlas("static_atlas", rows));
  const double tol = tolerance_between(rows);
  const CaseConfig user = case_from_yaml("static_user", static_bar_yaml("lps", 2.5e-4));
  const Throughputs rates = load_throughputs(default_throughputs_path());
  const Proposal p = propose(user, atlas, tol, rates, kLargeCasePath);
  for (const auto& line : p.reasoning) std::printf("  %s\n", line.c_str());
  ASSERT_TRUE(p.tolerance_met);
  const std::string proposed = temp_path("static_proposed.yaml");
  write_proposed_case(user, p, proposed);
  const CaseConfig back = solver::parse_case_file(proposed);
  EXPECT_TRUE(back.surface_correction) << "the rows ran with the correction, so must the proposal (" << p.model << ")";
  PdSystem s = solver::setup_system(back);
  const double error = static_strain_error(s);
  std::printf("tolerance %.4g: proposed spacing %.4g m, measured error %.4g\n", tol, p.spacing_m, error);
  EXPECT_LE(error, tol);
}

// ---- small rules: plane detection, problem class, atlas contract ------------------------

TEST(PlanRules, ThickBlockWithFreeFacesIsNotPlaneButHeldFacesMakePlaneStrain) {
  const std::string body = R"(
specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.02, 0.02, 0.02], spacing: 2 mm}}
model: {type: pmb}
materials: [{name: rock, density: 2600, youngs_modulus: 50 GPa, poisson_ratio: 0.25}]
time: {steps: 1}
)";
  const PlaneCheck free = plane_check(case_from_yaml("thick", body + "boundary: [{type: fixed, set: xmin}]\n"));
  EXPECT_FALSE(free.plane) << free.why;
  const PlaneCheck held = plane_check(case_from_yaml(
      "held", body + "boundary: [{type: fixed, set: zmin, components: [z]}, {type: fixed, set: zmax, components: [z]}]\n"));
  EXPECT_TRUE(held.plane) << held.why;
  EXPECT_EQ(held.planar, solver::Planar::PlaneStrain);
  // A thin plate: a load with a z component breaks extrusion invariance.
  const std::string plate = R"(
specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.04, 0.04, 0.002], spacing: 1 mm}}
model: {type: pmb}
materials: [{name: rock, density: 2600, youngs_modulus: 50 GPa, poisson_ratio: 0.25}]
time: {steps: 1}
)";
  const PlaneCheck tilted =
      plane_check(case_from_yaml("tilted", plate + "loads: [{type: traction, surface: xmax, value: [1 MPa, 0, 1 MPa]}]\n"));
  EXPECT_FALSE(tilted.plane) << tilted.why;
  // Initial conditions and boundaries by value or expression: a z part, or a value that varies
  // through the thickness, keeps the case 3D (the check read velocities' values alone: a 3D
  // plate with an initial z displacement was proposed in 2D and then refused by the solver,
  // and one with a velocity varying in z was run at its z = 0 value).
  EXPECT_TRUE(plane_check(case_from_yaml("plate_in_plane", plate + "initial: [{type: velocity, expression: ['1000 * x', '0', '0']}]\n")).plane);
  for (const auto& [name, extra, why] : std::vector<std::tuple<std::string, std::string, std::string>>{
           {"plate_uz", "initial: [{type: displacement, value: [0, 0, 1e-6]}]\n", "an initial displacement has a z part"},
           {"plate_vz_expr", "initial: [{type: velocity, expression: ['0', '0', '1000 * z']}]\n", "varies with z"},
           {"plate_vx_of_z", "initial: [{type: velocity, expression: ['1000 * (z - 0.001)', '0', '0']}]\n", "varies with z"},
           {"plate_vz_const", "initial: [{type: velocity, expression: ['0', '0', '2']}]\n", "has a z part"},
           {"plate_bc_of_z",
            "boundary: [{type: velocity, set: xmin, components: [x], expression: ['z * t', '0', '0']}]\n", "varies with z"}}) {
    const PlaneCheck p = plane_check(case_from_yaml(name, plate + extra));
    EXPECT_FALSE(p.plane) << name << ": " << p.why;
    EXPECT_NE(p.why.find(why), std::string::npos) << name << ": " << p.why;
  }
}

TEST(PlanRules, ProblemClassFollowsIntegratorAndFracture) {
  const std::string head = R"(
specimen: {lattice: {dimension: 2, box: [0, 0, 0.01, 0.01], spacing: 1 mm}}
model: {type: pmb, planar: plane_strain}
)";
  EXPECT_EQ(classify_problem(case_from_yaml("cls_adr", head + R"(
materials: [{name: r, density: 2600, youngs_modulus: 50 GPa, poisson_ratio: 0.25}]
time: {integrator: adr}
)")).problem, "quasi_static_bar");
  EXPECT_EQ(classify_problem(case_from_yaml("cls_frac", head + R"(
materials: [{name: r, density: 2600, youngs_modulus: 50 GPa, poisson_ratio: 0.25, fracture_energy: 50}]
time: {steps: 1}
)")).problem, "fracture_energy");
  EXPECT_EQ(classify_problem(case_from_yaml("cls_soft", head + R"(
materials: [{name: r, density: 2600, youngs_modulus: 50 GPa, poisson_ratio: 0.25, fracture_energy: 50, tensile_strength: 3 MPa}]
time: {steps: 1}
)")).problem, "softening_strength");
  EXPECT_EQ(classify_problem(case_from_yaml("cls_wave", head + R"(
materials: [{name: r, density: 2600, youngs_modulus: 50 GPa, poisson_ratio: 0.25}]
time: {steps: 1}
)")).problem, "wave_speed_bar");
}

namespace {

// A hand-written fixture in the atlas's CSV contract: the numbers are NOT results, they
// only exercise reading and the CLI.
const char* kFixtureAtlas =
    "problem,model,dimension,particles_kind,m,spacing_m,precision,backend,threads,particles,bonds,steps,wall_s,error,"
    "error_measure\n"
    "wave_speed_bar,pmb,2,lattice,3.015,0.002,float64,cpu,1,600,18000,100,0.1,0.08,\"fixture, not a result\"\n"
    "wave_speed_bar,pmb,2,lattice,3.015,0.001,float64,cpu,1,2400,80000,200,0.4,0.04,\"fixture, not a result\"\n";

struct CliResult {
  int code;
  std::string output;
};

CliResult run_plan(const std::string& args) {
  const std::string out = temp_path("cli_output.txt");
  const std::string cmd = std::string(BRECCIA_PLAN_EXE) + " " + args + " > " + out + " 2>&1";
  const int status = std::system(cmd.c_str());
  std::ifstream in(out);
  std::stringstream ss;
  ss << in.rdbuf();
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, ss.str()};
}

std::string small_case_file() {
  const std::string path = temp_path("cli_case.yaml");
  std::ofstream(path) << R"(
specimen: {lattice: {dimension: 2, box: [0, 0, 0.2, 0.012], spacing: 0.5 mm, thickness: 1 mm}}
model: {type: lps, planar: plane_stress, horizon_factor: 3.015}
materials: [{name: steel, density: 7850, youngs_modulus: 200 GPa, poisson_ratio: 0.3333333333333333}]
boundary: [{type: velocity, set: xmin, value: [1, 0, 0], components: [x]}]
time: {end: 40 us}
)";
  return path;
}

}  // namespace

TEST(PlanAtlas, WrongHeaderIsAnInputErrorNamingTheHeader) {
  const std::string path = temp_path("bad_atlas.csv");
  std::ofstream(path) << "problem,model,error\nwave_speed_bar,pmb,0.1\n";
  try {
    read_atlas(path);
    FAIL() << "no error for a wrong header";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("header"), std::string::npos) << e.what();
  }
}

// An atlas row's counts and sizes must be positive (and whole where they count): a negative m
// failed later as the case's horizon error, a dimension of 2.7 was read as 2.
TEST(PlanAtlas, ARowWithANonPositiveOrFractionalCountIsAnInputErrorNamingTheLine) {
  const std::string head =
      "problem,model,dimension,particles_kind,m,spacing_m,precision,backend,threads,particles,bonds,steps,wall_s,"
      "error,error_measure\n";
  for (const auto& [name, row, field] : std::vector<std::tuple<std::string, std::string, std::string>>{
           {"neg_m", "wave_speed_bar,pmb,2,lattice,-3,0.002,float64,cpu,1,600,18000,100,0.1,0.08,x\n", "line 2 m"},
           {"frac_dim", "wave_speed_bar,pmb,2.7,lattice,3,0.002,float64,cpu,1,600,18000,100,0.1,0.08,x\n", "line 2 dimension"},
           {"zero_spacing", "wave_speed_bar,pmb,2,lattice,3,0,float64,cpu,1,600,18000,100,0.1,0.08,x\n", "line 2 spacing_m"},
           {"neg_particles", "wave_speed_bar,pmb,2,lattice,3,0.002,float64,cpu,1,-600,18000,100,0.1,0.08,x\n",
            "line 2 particles"}}) {
    const std::string path = temp_path("atlas_" + name + ".csv");
    std::ofstream(path) << head << row;
    try {
      read_atlas(path);
      ADD_FAILURE() << name << ": no error";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << name << ": " << e.what();
    }
  }
}

// The planner's resolution is a measured row's particle count to the 1/d; powering it back
// rounded above the count (500.00000000000006) and proposed an unmeasured 510-particle spacing.
TEST(PlanProposal, AMeasuredLatticeIsProposedAtItsOwnSpacing) {
  const std::vector<double> box{0, 0, 0.1, 0.02};
  EXPECT_DOUBLE_EQ(spacing_for_resolution(box, 2, std::pow(500.0, 0.5)), 0.002);
  EXPECT_DOUBLE_EQ(spacing_for_resolution(box, 2, std::pow(2000.0, 0.5)), 0.001);
}

// An --atlas file that is not there is a typo the user hears about (exit 2 naming it); only
// the default atlas, when missing, is a note.
TEST(PlanCli, AnAtlasNamedButMissingExitsTwoNamingIt) {
  const CliResult r = run_plan(small_case_file() + " --tolerance 0.05 --atlas " + temp_path("no_such_atlas.csv"));
  EXPECT_EQ(r.code, kExitBadInput) << r.output;
  EXPECT_NE(r.output.find("no_such_atlas.csv: --atlas: no such file"), std::string::npos) << r.output;
}

TEST(PlanCli, NonPositiveOrMissingToleranceExitsTwoWithAMessage) {
  const std::string c = small_case_file();
  for (const std::string tol : {"0", "-0.1"}) {
    const CliResult r = run_plan(c + " --tolerance " + tol);
    EXPECT_EQ(r.code, kExitBadInput) << r.output;
    EXPECT_NE(r.output.find("error: --tolerance"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("> 0"), std::string::npos) << r.output;
  }
  const CliResult missing = run_plan(c);
  EXPECT_EQ(missing.code, kExitBadInput) << missing.output;
  EXPECT_NE(missing.output.find("--tolerance: missing"), std::string::npos) << missing.output;
  const CliResult word = run_plan(c + " --tolerance tight");
  EXPECT_EQ(word.code, kExitBadInput) << word.output;
  EXPECT_NE(word.output.find("not a number"), std::string::npos) << word.output;
}

// --help, --version, and usage errors (exit 2 naming the option): the tools' shared contract.
TEST(PlanCli, FollowsTheToolsCommandLineContract) {
  breccia::testing::expect_cli_contract(BRECCIA_PLAN_EXE, "breccia-plan", "case.yaml --tolerance 0.05",
                                        {{"--threads", "4x"}, {"--threads", "0"}, {"--tolerance", "5%"}});
}

TEST(PlanCli, MissingCaseFileExitsTwoNamingTheFile) {
  const CliResult r = run_plan(temp_path("no_such_case.yaml") + " --tolerance 0.05");
  EXPECT_EQ(r.code, kExitBadInput) << r.output;
  EXPECT_NE(r.output.find("no_such_case.yaml"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("no such case file"), std::string::npos) << r.output;
}

// A --write path whose folder cannot be made (a file stands there) is a usage error naming the
// option, said before the estimates (it was a failure, exit 3, after them).
TEST(PlanCli, WritePathThatCannotBeWrittenExitsTwoBeforeTheEstimates) {
  const std::string blocker = temp_path("plan_write_blocker");
  std::filesystem::remove_all(blocker);
  std::ofstream(blocker) << "a file, not a folder\n";
  const CliResult r = run_plan(small_case_file() + " --tolerance 0.05 --write " + blocker + "/proposed.yaml");
  EXPECT_EQ(r.code, kExitBadInput) << r.output;
  EXPECT_NE(r.output.find("--write: '" + blocker + "' not writable"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("Cost of the case"), std::string::npos) << r.output;
}

TEST(PlanCli, WritesAProposedCaseTheSolverLoaderAccepts) {
  const std::string atlas = temp_path("fixture_atlas.csv");
  std::ofstream(atlas) << kFixtureAtlas;
  const std::string proposed = temp_path("cli_proposed.yaml");
  std::filesystem::remove(proposed);
  const CliResult r = run_plan(small_case_file() + " --tolerance 0.05 --threads 1 --atlas " + atlas + " --write " + proposed);
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("no measured GPU throughput"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("Proposed setup"), std::string::npos) << r.output;
  const CaseConfig c = solver::parse_case_file(proposed);
  EXPECT_EQ(c.model_name, "pmb") << "nu = 1/3 in plane stress allows PMB, the only model the fixture has rows for";
}

// The atlas writer records a nominal m and runs the solver at m + 0.015, and writes its
// free-text last column unquoted: a comma there belongs to it, and a proposal from an m = 3
// row must run at 3.015. A row whose error is not a number is skipped, not fatal.
TEST(PlanAtlas, NominalMRunsAtTheAtlasHorizonFactorAndFreeTextMayHoldCommas) {
  const std::string path = temp_path("nominal_atlas.csv");
  std::ofstream(path)
      << "problem,model,dimension,particles_kind,m,spacing_m,precision,backend,threads,particles,bonds,steps,wall_s,"
         "error,error_measure\n"
         "wave_speed_bar,pmb,2,lattice,3,0.002,float64,cpu,1,600,18000,100,0.1,0.08,fixture, not a result\n"
         "wave_speed_bar,pmb,2,lattice,3,0.001,float64,cpu,1,2400,80000,200,0.4,0.04,fixture, not a result\n"
         "wave_speed_bar,pmb,2,lattice,3,0.0005,float64,cpu,1,9600,320000,400,1.6,nan,fixture: failed measurement\n";
  const auto atlas = read_atlas(path);
  ASSERT_EQ(atlas.size(), 2u);
  EXPECT_EQ(atlas[0].error_measure, "fixture, not a result");
  EXPECT_DOUBLE_EQ(horizon_factor_of_row_m(3.0), 3.015);
  EXPECT_DOUBLE_EQ(horizon_factor_of_row_m(3.015), 3.015);
  omp_set_num_threads(1);
  const CaseConfig c = case_from_yaml("nominal_case", R"(
specimen: {lattice: {dimension: 2, box: [0, 0, 0.1, 0.01], spacing: 0.5 mm, thickness: 1 mm}}
model: {type: pmb, planar: plane_stress, horizon_factor: 3.015}
materials: [{name: steel, density: 7850, youngs_modulus: 200 GPa, poisson_ratio: 0.3333333333333333}]
boundary: [{type: velocity, set: xmin, value: [1, 0, 0], components: [x]}]
time: {end: 10 us}
)");
  const Proposal p = propose(c, atlas, 0.05, load_throughputs(default_throughputs_path()), CostOptions{});
  ASSERT_TRUE(p.from_atlas);
  EXPECT_DOUBLE_EQ(p.horizon_factor, 3.015);
}

// Precision (docs/plan.md): float32 is proposed only where the atlas has float32 rows at the
// proposed model that meet the tolerance and stay within a tenth of it of float64, and the
// throughputs show a measured gain of 10% or more; each refusal says which part is missing.
TEST(PlanProposal, Float32IsProposedOnlyWhenTheAtlasShowsItSafeAndTheThroughputsFaster) {
  const std::string head =
      "problem,model,dimension,particles_kind,m,spacing_m,precision,backend,threads,particles,bonds,steps,wall_s,"
      "error,error_measure\n"
      "wave_speed_bar,pmb,2,lattice,3,0.002,float64,cpu,1,600,18000,100,0.1,0.08,fixture\n"
      "wave_speed_bar,pmb,2,lattice,3,0.001,float64,cpu,1,2400,80000,200,0.4,0.04,fixture\n";
  const std::string safe_path = temp_path("f32_safe_atlas.csv");
  std::ofstream(safe_path) << head << "wave_speed_bar,pmb,2,lattice,3,0.002,float32,cpu,1,600,18000,100,0.1,0.0801,fixture\n"
                                      "wave_speed_bar,pmb,2,lattice,3,0.001,float32,cpu,1,2400,80000,200,0.4,0.0401,fixture\n";
  const std::string unsafe_path = temp_path("f32_unsafe_atlas.csv");
  std::ofstream(unsafe_path) << head << "wave_speed_bar,pmb,2,lattice,3,0.002,float32,cpu,1,600,18000,100,0.1,0.09,fixture\n"
                                        "wave_speed_bar,pmb,2,lattice,3,0.001,float32,cpu,1,2400,80000,200,0.4,0.06,fixture\n";
  omp_set_num_threads(1);
  const CaseConfig c = case_from_yaml("f32_case", R"(
specimen: {lattice: {dimension: 2, box: [0, 0, 0.1, 0.01], spacing: 0.5 mm, thickness: 1 mm}}
model: {type: pmb, planar: plane_stress, horizon_factor: 3.015}
materials: [{name: steel, density: 7850, youngs_modulus: 200 GPa, poisson_ratio: 0.3333333333333333}]
boundary: [{type: velocity, set: xmin, value: [1, 0, 0], components: [x]}]
time: {end: 10 us}
)");
  const Throughputs measured = load_throughputs(default_throughputs_path());
  // The shipped file measures float32 slower on the CPU: it must keep the proposal float64.
  const Proposal shipped = propose(c, read_atlas(safe_path), 0.05, measured, CostOptions{});
  EXPECT_EQ(shipped.precision, "float64");
  Throughputs faster = measured;
  std::erase_if(faster.loop, [](const LoopRate& r) { return r.precision == "float32"; });
  const std::vector<LoopRate> float64_rates = faster.loop;
  for (const LoopRate& r : float64_rates) {
    LoopRate f = r;
    f.precision = "float32";
    f.bond_updates_per_core_s *= 1.3;
    faster.loop.push_back(f);
  }
  Throughputs slower = faster;
  for (LoopRate& r : slower.loop)
    if (r.precision == "float32") r.bond_updates_per_core_s /= 1.3 * 1.3;
  const auto precision_line = [](const Proposal& p) {
    for (const auto& l : p.reasoning)
      if (l.rfind("Precision:", 0) == 0) return l;
    return std::string();
  };
  const Proposal yes = propose(c, read_atlas(safe_path), 0.05, faster, CostOptions{});
  EXPECT_EQ(yes.precision, "float32") << precision_line(yes);
  EXPECT_NE(precision_line(yes).find("float32 / float64 throughput 1.3"), std::string::npos) << precision_line(yes);
  const std::string proposed = temp_path("f32_proposed.yaml");
  write_proposed_case(c, yes, proposed);
  EXPECT_EQ(solver::parse_case_file(proposed).precision, CaseConfig::Precision::Float32);

  const Proposal no_gain = propose(c, read_atlas(safe_path), 0.05, slower, CostOptions{});
  EXPECT_EQ(no_gain.precision, "float64");
  EXPECT_NE(precision_line(no_gain).find("no real gain"), std::string::npos) << precision_line(no_gain);
  // A case given in float32 whose proposal stays float64 is written (and costed) in float64, as
  // the reasoning says: it was written back as float32.
  CaseConfig given_f32 = c;
  given_f32.precision = CaseConfig::Precision::Float32;
  const Proposal stays = propose(given_f32, read_atlas(safe_path), 0.05, slower, CostOptions{});
  EXPECT_EQ(stays.precision, "float64");
  EXPECT_EQ(proposed_config(given_f32, stays).precision, CaseConfig::Precision::Float64);
  const std::string f32_given_dir = temp_path("f32_given");
  std::filesystem::create_directories(f32_given_dir);
  const std::string f32_given = f32_given_dir + "/case.yaml";
  std::ofstream(f32_given) << R"(
specimen: {lattice: {dimension: 2, box: [0, 0, 0.1, 0.01], spacing: 0.5 mm, thickness: 1 mm}}
model: {type: pmb, planar: plane_stress, horizon_factor: 3.015, precision: float32}
materials: [{name: steel, density: 7850, youngs_modulus: 200 GPa, poisson_ratio: 0.3333333333333333}]
boundary: [{type: velocity, set: xmin, value: [1, 0, 0], components: [x]}]
time: {end: 10 us}
)";
  const CaseConfig parsed_f32 = solver::parse_case_file(f32_given);
  const Proposal stays_file = propose(parsed_f32, read_atlas(safe_path), 0.05, slower, CostOptions{});
  const std::string stays_written = temp_path("f32_stays_proposed.yaml");
  write_proposed_case(parsed_f32, stays_file, stays_written);
  EXPECT_EQ(solver::parse_case_file(stays_written).precision, CaseConfig::Precision::Float64);
  const Proposal unsafe = propose(c, read_atlas(unsafe_path), 0.05, faster, CostOptions{});
  EXPECT_EQ(unsafe.precision, "float64");
  EXPECT_NE(precision_line(unsafe).find("0 of 2 float32"), std::string::npos) << precision_line(unsafe);
}

// Correspondence (docs/plan.md): the planner knows its measured cost relative to LPS and that
// it needs stabilisation. Where the atlas shows LPS meets the tolerance it proposes LPS and says
// why; the written case drops model.stabilisation (refused for LPS) and loads. Without atlas
// rows nothing shows LPS meets the tolerance, so correspondence is kept. The fixture's numbers
// are not results.
TEST(PlanProposal, CorrespondenceIsReplacedByLpsWhereTheAtlasShowsLpsMeetsTheToleranceAndSaysWhy) {
  const std::string path = temp_path("corr_atlas.csv");
  std::ofstream(path)
      << "problem,model,dimension,particles_kind,m,spacing_m,precision,backend,threads,particles,bonds,steps,wall_s,"
         "error,error_measure\n"
         "wave_speed_bar,lps,2,lattice,3,0.002,float64,cpu,1,600,18000,100,0.1,0.08,fixture\n"
         "wave_speed_bar,lps,2,lattice,3,0.001,float64,cpu,1,2400,80000,200,0.4,0.04,fixture\n";
  omp_set_num_threads(1);
  const CaseConfig c = case_from_yaml("corr_case", R"(
specimen: {lattice: {dimension: 2, box: [0, 0, 0.1, 0.01], spacing: 0.5 mm, thickness: 1 mm}}
model: {type: correspondence, planar: plane_strain, horizon_factor: 3.015, stabilisation: {type: penalty, coefficient: 1}}
materials: [{name: rock, density: 2600, youngs_modulus: 50 GPa, poisson_ratio: 0.3}]
boundary: [{type: velocity, set: xmin, value: [1, 0, 0], components: [x]}]
time: {end: 10 us}
)");
  const Throughputs rates = load_throughputs(default_throughputs_path());
  // The shipped throughputs measure correspondence (make bench): dearer per bond than LPS.
  const std::optional<double> relative = rates.relative_cost(solver::PdModel::Correspondence, solver::PdModel::LPS, 1);
  ASSERT_TRUE(relative.has_value());
  EXPECT_GT(*relative, 1.0);
  // Same bonds (correspondence keeps LPS's families); the steps are each model's own (its
  // stable step differs), so per bond-update the estimates differ by the measured rates alone.
  CaseConfig as_lps = c;
  as_lps.model = solver::PdModel::LPS;
  as_lps.model_name = "lps";
  as_lps.stabilisation = "none";
  const CostEstimate corr_cost = estimate_cost(c, rates), lps_cost = estimate_cost(as_lps, rates);
  EXPECT_EQ(corr_cost.bonds, lps_cost.bonds);
  const auto per_update = [](const CostEstimate& e) { return e.loop_s / (double(e.bonds) * double(e.steps)); };
  EXPECT_NEAR(per_update(corr_cost) / per_update(lps_cost), *relative, 1e-9 * *relative);
  EXPECT_GT(corr_cost.run_bytes, lps_cost.run_bytes);  // F, force tensor, moduli per particle

  const Proposal p = propose(c, read_atlas(path), 0.05, rates, CostOptions{});
  std::string all;
  for (const auto& l : p.reasoning) all += l + "\n";
  ASSERT_TRUE(p.tolerance_met) << all;
  EXPECT_EQ(p.model, "lps") << all;
  EXPECT_NE(all.find("asks for correspondence PD"), std::string::npos) << all;
  EXPECT_NE(all.find("x LPS's per bond entry"), std::string::npos) << all;
  EXPECT_NE(all.find("stabilisation"), std::string::npos) << all;
  EXPECT_NE(all.find("Correspondence is replaced by lps"), std::string::npos) << all;
  const std::string proposed = temp_path("corr_proposed.yaml");
  write_proposed_case(c, p, proposed);
  const CaseConfig back = solver::parse_case_file(proposed);
  EXPECT_EQ(back.model, solver::PdModel::LPS);
  // The atlas's LPS rows run with the energy surface correction (tools/atlas, model_yaml), so
  // the LPS proposal must too, or it would not have their error.
  EXPECT_TRUE(back.surface_correction);
  EXPECT_NE(all.find("measures lps with the energy surface correction"), std::string::npos) << all;

  const std::string empty = temp_path("corr_empty_atlas.csv");
  std::ofstream(empty) << "problem,model,dimension,particles_kind,m,spacing_m,precision,backend,threads,particles,bonds,"
                          "steps,wall_s,error,error_measure\n";
  const Proposal kept = propose(c, read_atlas(empty), 0.05, rates, CostOptions{});
  EXPECT_EQ(kept.model, "correspondence");
  EXPECT_EQ(kept.precision, "float64");
  std::string kept_text;
  for (const auto& l : kept.reasoning) kept_text += l + "\n";
  EXPECT_NE(kept_text.find("Correspondence is kept"), std::string::npos) << kept_text;
}

// A float32 case is costed at the measured float32 rate, not float64's (docs/plan.md).
TEST(PlanCost, Float32CaseIsCostedAtTheMeasuredFloat32Rate) {
  omp_set_num_threads(1);
  const CaseConfig c64 = case_from_yaml("f32_cost64", R"(
specimen: {lattice: {dimension: 2, box: [0, 0, 0.02, 0.01], spacing: 0.5 mm, thickness: 1 mm}}
model: {type: lps, planar: plane_strain, horizon_factor: 3.015}
materials: [{name: rock, density: 2600, youngs_modulus: 50 GPa, poisson_ratio: 0.25}]
time: {steps: 100}
)");
  CaseConfig c32 = c64;
  c32.precision = CaseConfig::Precision::Float32;
  const Throughputs rates = load_throughputs(default_throughputs_path());
  const std::optional<double> speedup = rates.float32_speedup(solver::PdModel::LPS, 1);
  ASSERT_TRUE(speedup.has_value());
  const CostEstimate e64 = estimate_cost(c64, rates), e32 = estimate_cost(c32, rates);
  EXPECT_EQ(e64.bonds, e32.bonds);
  EXPECT_NEAR(e64.loop_s / e32.loop_s, *speedup, 1e-9);
  EXPECT_NE(e32.rate_source.find("float32"), std::string::npos) << e32.rate_source;
}

// -o RUN: a relative particle file is looked for in the run folder first, as breccia-solve
// does (the case READMEs write particles.h5 there); --set overrides a value. Without -o the
// same case is refused naming the file it did not find next to the case.
TEST(PlanCli, ARunFolderAndSetAreReadAsTheSolverReadsThem) {
  const std::string dir = temp_path("plan_run_folder");
  std::filesystem::create_directories(dir + "/run");
  breccia::ParticleModel m = breccia::solver::testing::square_lattice_model(20, 6, 1e-3, 1e-3);
  m.material_names = {"steel"};
  breccia::write_particle_file(dir + "/run/particles.h5", m);
  const std::string c = dir + "/case.yaml";
  std::ofstream(c) << "specimen: {particles: particles.h5}\n"
                      "model: {type: pmb, planar: plane_stress}\n"
                      "materials: [{name: steel, density: 7850, youngs_modulus: 200 GPa, poisson_ratio: 0.3333333333333333}]\n"
                      "time: {steps: 10}\n";
  const CliResult without = run_plan(c + " --tolerance 0.05");
  EXPECT_EQ(without.code, kExitBadInput) << without.output;
  const CliResult with = run_plan(c + " -o " + dir + "/run --set time.steps=25 --tolerance 0.05");
  EXPECT_EQ(with.code, 0) << with.output;
  EXPECT_NE(with.output.find("particles      120"), std::string::npos) << with.output;
  EXPECT_NE(with.output.find("steps          25 of"), std::string::npos) << with.output;
}
