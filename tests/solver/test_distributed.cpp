// Distributed runs (solver/mpi/, docs/parallel.md): `mpirun -np P breccia-solve` gives the
// answer of one process, byte for byte, at any rank and thread count.
//
// Specimen: a 40 x 20 x 8 mm block with an embedded notch (x = 20 mm, 6 mm deep from ymin,
// through the thickness), meshed by gmsh with 0.6 mm tets near the notch grading to 1.5 mm:
// about 19,000 particles, so every model runs on a graded tet arrangement with the dual
// horizon (variable_horizon) and families of very unequal size. Its ends are pulled apart at
// 2 m/s: by step 40 about 5% of the bond pairs are broken (the notch's and new ones).
//
// What must hold (the requirement, no tolerance): displacements, velocities,
// accelerations, forces, damage and bond states byte-identical to the one-process run;
// energies, whose sums over ranks run in another order, to 1e-12 relative.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <bitset>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "breccia/common/h5.hpp"
#include "breccia/solver/distributed_setup.hpp"
#include "distributed_compare.hpp"
#include "helpers.hpp"

using namespace breccia::solver;
using namespace breccia::solver::testing;

namespace {

// The notched block's particles (meshed once per test process).
std::string notched_block() {
  static const std::string path = mesh_and_place(
      "notched_block",
      "dimension: 3\n"
      "body: {shape: box, name: block, size: [40 mm, 20 mm, 8 mm]}\n"
      "notches: [{name: notch, corner: [20 mm, 0, 0], edge_a: [0, 6 mm, 0], edge_b: [0, 0, 8 mm]}]\n"
      "mesh: {size: 1.5 mm, refine: [{near: notch, size: 0.6 mm, distance_min: 1 mm, distance_max: 10 mm}]}\n");
  return path;
}

std::string block_case(const std::string& name, const std::string& model, int steps = 40) {
  const std::string particles = notched_block();
  EXPECT_FALSE(particles.empty()) << "could not mesh the notched block";
  return write_case(name,
                    "name: " + name + "\nspecimen: {particles: " + particles + "}\n"
                    "model: {" + model + ", horizon_factor: 3.015, variable_horizon: true}\n"
                    "materials: [{name: block, density: 2400, youngs_modulus: 30 GPa, poisson_ratio: 0.25, "
                    "fracture_energy: 20}]\n"
                    "precracks: [{type: surface, surface: notch}]\n"
                    "boundary:\n"
                    "  - {type: velocity, set: xmin, value: [-2, 0, 0], components: [x]}\n"
                    "  - {type: velocity, set: xmax, value: [2, 0, 0], components: [x]}\n"
                    "time: {steps: " + std::to_string(steps) + "}\n"
                    "output: {every: 20, history_every: 10, fields: [damage, displacement, velocity]}\n");
}

class SameAnswer : public ::testing::TestWithParam<const char*> {};

}  // namespace

TEST_P(SameAnswer, AtOneToFourRanksAndOneOrTwoThreads) {
  const std::string name = std::string("block_") + GetParam();
  std::string model = std::string("type: ") + GetParam();
  if (model == "type: float32") model = "type: pmb, precision: float32";
  const std::string file = block_case(name, model);
  const std::string base = process_temp_dir() + "/" + name;
  const Outcome ref = solve(file, base + "_np1_t1", 1, 1);
  ASSERT_EQ(ref.exit_code, 0) << ref.err;
  const nlohmann::json s_ref = summary(base + "_np1_t1");
  // A few percent of the pairs broken, some of them during the run (not only the notch's).
  const double broken = 2.0 * s_ref["broken_bonds"].get<double>() / s_ref["bonds"].get<double>();
  EXPECT_GT(broken, 0.02) << "the check needs bonds that break";
  EXPECT_GT(s_ref["dissipated_J"].get<double>(), 0.0) << "no bond broke during the run";
  struct Variant {
    int ranks, threads;
  };
  for (const Variant v : {Variant{2, 1}, Variant{3, 1}, Variant{4, 1}, Variant{1, 2}}) {
    const std::string out = base + "_np" + std::to_string(v.ranks) + "_t" + std::to_string(v.threads);
    const Outcome o = solve(file, out, v.ranks, v.threads);
    ASSERT_EQ(o.exit_code, 0) << out << ": " << o.err;
    for (const char* f : {"/results.h5", "/checkpoint.h5"})
      EXPECT_EQ(differing(base + "_np1_t1" + f, out + f), std::vector<std::string>{}) << out << f;
    const nlohmann::json s = summary(out);
    EXPECT_EQ(s["ranks"], v.ranks);
    EXPECT_EQ(s["distributed_setup"], v.ranks > 1) << out;  // each rank built its own bonds
    expect_same_energies(s_ref, s, out);
  }
}

INSTANTIATE_TEST_SUITE_P(Models, SameAnswer, ::testing::Values("pmb", "lps", "correspondence", "float32"),
                         [](const auto& info) { return std::string(info.param); });

// The checkpoint holds the whole state in the particle file's order, whatever wrote it. A
// lattice block with a through-crack is enough here (the byte-identity above is the graded
// block's); its ends pulled apart break bonds on both sides of the stop.
TEST(Distributed, CheckpointOfThreeRanksRestartsOnTwoAndOneByteIdentical) {
  const std::string file = write_case("mpi_restart",
      "specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.02, 0.01, 0.004], spacing: 0.5 mm}}\n"
      "model: {type: lps, horizon_factor: 3.015}\n"
      "materials: [{name: m, density: 2000, youngs_modulus: 10 GPa, poisson_ratio: 0.25, fracture_energy: 5}]\n"
      "precracks: [{type: polygon, points: [[0.01, -0.001, -0.001], [0.01, 0.004, -0.001], [0.01, 0.004, 0.005], [0.01, -0.001, 0.005]]}]\n"
      "boundary:\n"
      "  - {type: velocity, set: xmin, value: [-5, 0, 0], components: [x]}\n"
      "  - {type: velocity, set: xmax, value: [5, 0, 0], components: [x]}\n"
      "time: {steps: 120}\n"
      "output: {every: 60, history_every: 10, fields: [damage, displacement, velocity]}\n");
  const std::string base = process_temp_dir() + "/restart";
  ASSERT_EQ(solve(file, base + "_whole", 1, 1).exit_code, 0);
  long long broken_half = 0;
  for (const int ranks : {2, 1}) {
    const std::string out = base + "_on" + std::to_string(ranks);
    const Outcome first = solve(file, out, 3, 1, "--steps 60");
    ASSERT_EQ(first.exit_code, 0) << first.err;
    broken_half = summary(out)["broken_bonds"].get<long long>();
    const Outcome second = solve(file, out, ranks, 1, "--steps 60 --restart " + out + "/checkpoint.h5");
    ASSERT_EQ(second.exit_code, 0) << second.err;
    EXPECT_EQ(differing(base + "_whole/checkpoint.h5", out + "/checkpoint.h5"), std::vector<std::string>{})
        << "stopped at step 60 on 3 ranks, finished on " << ranks;
    // The results too, their /particles written by the 3 ranks' rows; and the lattice's
    // particles.h5 beside them, of the whole lattice whatever rank 0 held of it.
    for (const char* f : {"/results.h5", "/particles.h5"})
      EXPECT_EQ(differing(base + "_whole" + f, out + f), std::vector<std::string>{}) << out << f;
  }
  EXPECT_GT(summary(base + "_whole")["broken_bonds"].get<long long>(), broken_half) << "no bond broke after the restart";
}

// Doubles of a dataset (its raw bytes as read above).
std::vector<double> doubles(const std::map<std::string, std::string>& sets, const std::string& name) {
  const auto it = sets.find(name);
  if (it == sets.end()) return {};
  std::vector<double> v(it->second.size() / sizeof(double));
  std::memcpy(v.data(), it->second.data(), v.size() * sizeof(double));
  return v;
}

// Dynamic relaxation's sums (damping, residual) steer its path: they are taken
// reproducibly (reproducible_sum.hpp), so 3 ranks follow one process's iterations and end in
// the same state; the issue asks 1e-12 of the displacement, this checks bytes too.
TEST(Distributed, DynamicRelaxationConvergesToTheSameStateOnThreeRanks) {
  const std::string file = write_case("mpi_adr",
      "specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.016, 0.008, 0.004], spacing: 1 mm}}\n"
      "model: {type: lps, horizon_factor: 3.015}\n"
      "materials: [{name: m, density: 2000, youngs_modulus: 10 GPa, poisson_ratio: 0.25}]\n"
      "precracks: [{type: polygon, points: [[0.008, -0.001, -0.001], [0.008, 0.004, -0.001], [0.008, 0.004, 0.005], [0.008, -0.001, 0.005]]}]\n"
      "loads: [{type: pressure, surface: xmax, history: {type: constant, value: -2 MPa}}]\n"
      "boundary: [{type: displacement, set: xmin, value: [0, 0, 0]}]\n"
      "time: {integrator: adr, adr_tolerance: 1e-10, adr_max_steps: 100000}\n"
      "output: {fields: [displacement]}\n");
  const std::string base = process_temp_dir() + "/adr";
  const Outcome one = solve(file, base + "_np1", 1, 1), three = solve(file, base + "_np3", 3, 1);
  ASSERT_EQ(one.exit_code, 0) << one.err;
  ASSERT_EQ(three.exit_code, 0) << three.err;
  EXPECT_EQ(summary(base + "_np1")["status"], "converged");
  EXPECT_EQ(summary(base + "_np1")["steps"], summary(base + "_np3")["steps"]) << "iterations";
  const auto a = datasets(base + "_np1/results.h5"), b = datasets(base + "_np3/results.h5");
  std::string last;  // the last frame's displacement
  for (const auto& [name, bytes] : a)
    if (name.size() > 13 && name.substr(name.size() - 13) == "/displacement") last = name;
  const std::vector<double> ua = doubles(a, last), ub = doubles(b, last);
  ASSERT_EQ(ua.size(), ub.size());
  ASSERT_FALSE(ua.empty());
  double umax = 0.0, diff = 0.0;
  for (size_t k = 0; k < ua.size(); ++k) {
    umax = std::max(umax, std::fabs(ua[k]));
    diff = std::max(diff, std::fabs(ua[k] - ub[k]));
  }
  EXPECT_GT(umax, 1e-5);  // 2 MPa over 16 mm of a 10 GPa bar with a half-depth crack: ~1.7e-5 m
  EXPECT_LE(diff, 1e-12 * umax) << "largest difference " << diff << " m against " << umax << " m";
  EXPECT_EQ(differing(base + "_np1/results.h5", base + "_np3/results.h5"), std::vector<std::string>{});
}

TEST(Distributed, BadInputIsReportedOnceWithExitCode2) {
  const std::string file = write_case("mpi_bad", "specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.004, 0.004, 0.004], spacing: 1 mm}}\n"
                                                 "model: {type: pmb, horizon_factor: 3.015}\n"
                                                 "materials: [{name: m, density: 2000, youngs_modulus: 10 GPA, poisson_ratio: 0.25}]\n"
                                                 "time: {steps: 5}\n");
  const Outcome o = solve(file, process_temp_dir() + "/mpi_bad", 3, 1);
  EXPECT_EQ(o.exit_code, 2) << o.err;
  const std::string key = "youngs_modulus";
  size_t count = 0;
  for (size_t at = o.err.find("error:"); at != std::string::npos; at = o.err.find("error:", at + 1)) ++count;
  EXPECT_EQ(count, 1u) << o.err;
  EXPECT_NE(o.err.find(key), std::string::npos) << o.err;
}

// An input error found on the whole body (a horizon below the largest spacing, which every
// rank judges from the ranks' blocks of the Morton sort; one rank 0 meets alone reaches the
// others as a refusal, distributed_setup.hpp BodyPlan): every rank stops with exit code 2,
// the error said once.
TEST(Distributed, AWholeBodyInputErrorOnRankZeroStopsEveryRankWithExitCode2) {
  const std::string file = write_case("mpi_bad_horizon",
                                      "specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.004, 0.004, 0.004], spacing: 1 mm}}\n"
                                      "model: {type: pmb, horizon: 0.5 mm}\n"
                                      "materials: [{name: m, density: 2000, youngs_modulus: 10 GPa, poisson_ratio: 0.25}]\n"
                                      "time: {steps: 5}\n");
  const Outcome o = solve(file, process_temp_dir() + "/mpi_bad_horizon", 3, 1);
  EXPECT_EQ(o.exit_code, 2) << o.err;
  size_t count = 0;
  for (size_t at = o.err.find("error:"); at != std::string::npos; at = o.err.find("error:", at + 1)) ++count;
  EXPECT_EQ(count, 1u) << o.err;
  EXPECT_NE(o.err.find("model.horizon"), std::string::npos) << o.err;
}

// A usage error under mpirun: every rank parses the command line, rank 0 alone speaks, and all
// leave with exit code 2 (mpirun reports the first non-zero code).
TEST(Distributed, UsageErrorIsReportedOnceWithExitCode2) {
  const std::string file =
      write_case("mpi_usage",
                 "specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.004, 0.004, 0.004], spacing: 1 mm}}\n"
                 "model: {type: pmb, horizon_factor: 3.015}\n"
                 "materials: [{name: m, density: 2000, youngs_modulus: 10 GPa, poisson_ratio: 0.25}]\n"
                 "time: {steps: 5}\n");
  for (const std::string bad : {"--steps 10s", "--no-such-option"}) {
    const Outcome o = solve(file, process_temp_dir() + "/mpi_usage", 2, 1, bad);
    EXPECT_EQ(o.exit_code, 2) << bad << ": " << o.err;
    size_t count = 0;
    for (size_t at = o.err.find("error:"); at != std::string::npos; at = o.err.find("error:", at + 1)) ++count;
    EXPECT_EQ(count, 1u) << o.err;
    EXPECT_NE(o.err.find("error: command line: " + bad.substr(0, bad.find(' '))), std::string::npos) << o.err;
  }
}

// A case refused under `ranks` processes: exit code 2 and a message holding `expected`.
void expect_refused(const std::string& name, const std::string& body, int ranks, const std::string& expected) {
  const std::string file = write_case(name, "specimen: {lattice: {dimension: 3, box: " + body);
  const Outcome o = solve(file, process_temp_dir() + "/" + name, ranks, 1);
  EXPECT_EQ(o.exit_code, 2) << o.err;
  EXPECT_NE(o.err.find(expected), std::string::npos) << o.err;
}

TEST(Distributed, MoreRanksThanParticlesIsAnInputError) {
  expect_refused("mpi_tiny", "[0, 0, 0, 0.003, 0.001, 0.001], spacing: 1 mm}}\n"
                 "model: {type: pmb, horizon_factor: 3.015}\n"
                 "materials: [{name: m, density: 2000, youngs_modulus: 10 GPa, poisson_ratio: 0.25}]\n"
                 "time: {steps: 5, check_stability: false}\n",
                 4, "at most one rank per particle");
}

// What is not distributed is refused by the key that asks for it: MPS, whose particles move
// between ranks (breccia_solve.cpp), before anything is read.
TEST(Distributed, WhatIsNotDistributedIsRefusedByItsKey) {
  const std::string file = write_case("mpi_mps", "model: {type: mps}\n");
  const Outcome o = solve(file, process_temp_dir() + "/mpi_mps", 2, 1);
  EXPECT_EQ(o.exit_code, 2) << o.err;
  EXPECT_NE(o.err.find("model.type"), std::string::npos) << o.err;
  EXPECT_NE(o.err.find("mps under mpirun -np 2"), std::string::npos) << o.err;
}

// The charge hole of the gas tests' disc (charge_hole_disc, helpers.hpp) pressurised by a gas
// (loads[].type: gas) behind a pre-crack `to` the given point; `extra`: more of the gas's
// keys, `material`: more of the rock's.
static std::string gas_case(const std::string& material, const std::string& to, const std::string& extra,
                            const std::string& time, const std::string& model = "type: lps") {
  return "specimen: {particles: " + charge_hole_disc() + "}\n"
         "model: {" + model + ", planar: plane_strain, horizon_factor: 3.015, variable_horizon: true}\n"
         "materials: [{name: rock, density: 2000, youngs_modulus: 1 GPa, poisson_ratio: 0.25" + material + "}]\n"
         "precracks: [{type: segment, from: [4 mm, 0.01 mm], to: " + to + "}]\n"
         "loads:\n  - {type: gas, surface: charge_hole, history: {type: constant, value: 20 MPa}, gamma_high: 3, "
         "gamma_low: 1.4, switch_pressure: 18 MPa, ambient_pressure: 0, front_speed: 500 m/s, gas_density: 1000 kg/m3" +
         extra + "}\n" + time;
}

// Dynamic relaxation with a gas load: its external pass (the gas's volumes, pressure and crack
// forces) runs over ranks as the time loop's does (RelaxHooks::external, mpi_backend.cpp), so
// 2 and 3 ranks take one process's iterations and end in its state: results.h5 and
// history.csv (with the gas's columns) byte for byte. Without that hook each rank's gas would
// see its own share of the wall and the cracks, and a pressure of its own.
TEST(Distributed, GasWithDynamicRelaxationGivesTheOneProcessAnswer) {
  ASSERT_FALSE(charge_hole_disc().empty()) << "could not mesh the charge-hole disc";
  const std::string file = write_case(
      "mpi_gas_adr", gas_case("", "[15 mm, 0.01 mm]", "",
                              "time: {integrator: adr, adr_tolerance: 1e-3, adr_max_steps: 20000}\n"
                              "output: {fields: [damage, displacement]}\n"));
  const std::string base = process_temp_dir() + "/mpi_gas_adr";
  const Outcome one = solve(file, base + "_np1", 1, 1);
  ASSERT_EQ(one.exit_code, 0) << one.err;
  ASSERT_EQ(summary(base + "_np1")["status"], "converged");
  // What the comparison must see: the gas following the cavity's volume (the hole grows, the
  // pressure falls below the charge's 20 MPa at V0) and in the pre-crack's faces at the wall.
  EXPECT_LT(last_history_value(base + "_np1", "gas_pressure_Pa"), 19.9e6);
  EXPECT_GT(last_history_value(base + "_np1", "crack_gas_volume_m3"), 0.0) << "no gas in a crack";
  for (const int ranks : {2, 3}) {
    const std::string out = base + "_np" + std::to_string(ranks);
    const Outcome o = solve(file, out, ranks, 1);
    ASSERT_EQ(o.exit_code, 0) << out << ": " << o.err;
    EXPECT_TRUE(summary(out)["distributed_setup"].get<bool>()) << out << " built the whole system";
    EXPECT_EQ(summary(out)["steps"], summary(base + "_np1")["steps"]) << out << ": iterations";
    EXPECT_EQ(differing(base + "_np1/results.h5", out + "/results.h5"), std::vector<std::string>{}) << out;
    expect_same_history(base + "_np1", out);
  }
}

// A graded, notched tet block (meshed once per test process): 0.4 mm tets at the notch
// grading to 1 mm, horizons differing by 3x between bonded particles, 3,369 particles.
static std::string graded_notch() {
  static const std::string path = mesh_and_place(
      "graded_notch",
      "dimension: 3\n"
      "body: {shape: box, name: block, size: [12 mm, 6 mm, 3 mm]}\n"
      "notches: [{name: notch, corner: [6 mm, 0, 0], edge_a: [0, 2 mm, 0], edge_b: [0, 0, 3 mm]}]\n"
      "mesh: {size: 1 mm, refine: [{near: notch, size: 0.4 mm, distance_min: 0.5 mm, distance_max: 4 mm}]}\n");
  return path;
}

// The graded block pulled apart at its ends with the dual horizon, the notch pre-cracked.
// check_stability: the start-up checks, among them the energy-scatter check of mesh-derived
// particles (a force pass over every family, family_check.hpp).
static std::string graded_case(const std::string& particles, const std::string& model, int steps, bool check_stability) {
  return "specimen: {particles: " + particles + "}\n"
         "model: {type: " + model + ", horizon_factor: 3.015, variable_horizon: true}\n"
         "materials: [{name: block, density: 2400, youngs_modulus: 30 GPa, poisson_ratio: 0.25, fracture_energy: 20}]\n"
         "precracks: [{type: surface, surface: notch}]\n"
         "boundary:\n"
         "  - {type: velocity, set: xmin, value: [-2, 0, 0], components: [x]}\n"
         "  - {type: velocity, set: xmax, value: [2, 0, 0], components: [x]}\n"
         "time: {steps: " + std::to_string(steps) + ", check_stability: " + (check_stability ? "true" : "false") + "}\n"
         "output: {every: 20, history_every: 10, fields: [damage, displacement, velocity]}\n";
}

// A case refused at set-up: one process and 3 ranks both exit with code 2, the error line
// holds `expected` and is the one process's, and 3 ranks print it once.
static void expect_one_refusal_on_three_ranks_as_one_process(const std::string& name, const std::string& yaml,
                                                             const std::string& expected) {
  const std::string file = write_case(name, yaml);
  const Outcome one = solve(file, process_temp_dir() + "/" + name + "_np1", 1, 1);
  const Outcome three = solve(file, process_temp_dir() + "/" + name + "_np3", 3, 1);
  EXPECT_EQ(one.exit_code, 2) << one.err;
  EXPECT_EQ(three.exit_code, 2) << three.err;
  const auto error_line = [](const std::string& err) {
    const size_t at = err.find("error:");
    return at == std::string::npos ? std::string() : err.substr(at, err.find('\n', at) - at);
  };
  EXPECT_NE(error_line(one.err).find(expected), std::string::npos) << one.err;
  EXPECT_EQ(error_line(one.err), error_line(three.err));
  EXPECT_EQ(three.err.find("error:", three.err.find("error:") + 1), std::string::npos) << "more than one error: " << three.err;
}

// A bad row of the particle file (read_particle_file's checks): under mpirun every rank checks
// its block of the file's rows (setup.cpp, refuse_together), and the first bad row in the
// file's order is every rank's refusal, printed once. Here a material id out of range in rank
// 1's block and a negative volume in rank 2's (3 ranks): one process meets the material id
// first, and so do the 3 ranks, exit code 2.
TEST(Distributed, BadRowOfTheParticleFileIsTheOneProcessMessageOnce) {
  const std::string good = notched_block();
  ASSERT_FALSE(good.empty());
  const std::string bad = process_temp_dir() + "/bad_rows.h5";
  std::filesystem::copy_file(good, bad, std::filesystem::copy_options::overwrite_existing);
  const hid_t f = H5Fopen(bad.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  auto put = [&](const char* dataset, hsize_t row, hid_t type, const void* value) {
    const hid_t d = H5Dopen(f, dataset, H5P_DEFAULT), space = H5Dget_space(d);
    hsize_t count = 1;
    H5Sselect_hyperslab(space, H5S_SELECT_SET, &row, nullptr, &count, nullptr);
    const hid_t one = H5Screate_simple(1, &count, nullptr);
    EXPECT_GE(H5Dwrite(d, type, one, space, H5P_DEFAULT, value), 0) << dataset;
    H5Sclose(one);
    H5Sclose(space);
    H5Dclose(d);
  };
  hsize_t n = 0;
  {
    const hid_t d = H5Dopen(f, "/particles/volume", H5P_DEFAULT), space = H5Dget_space(d);
    H5Sget_simple_extent_dims(space, &n, nullptr);
    H5Sclose(space);
    H5Dclose(d);
  }
  const int32_t material = 7;
  const double volume = -1.0;
  const hsize_t material_row = n / 2, volume_row = n - 10;  // (file_block: rank 1's and rank 2's of 3)
  put("/particles/material_id", material_row, H5T_NATIVE_INT32, &material);
  put("/particles/volume", volume_row, H5T_NATIVE_DOUBLE, &volume);
  H5Fclose(f);
  expect_one_refusal_on_three_ranks_as_one_process(
      "mpi_dist_bad_row",
      "specimen: {particles: " + bad + "}\n"
      "model: {type: pmb, horizon_factor: 3.015}\n"
      "materials: [{name: block, density: 2400, youngs_modulus: 30 GPa, poisson_ratio: 0.25, fracture_energy: 20}]\n"
      "time: {steps: 2}\n",
      "/particles/material_id[" + std::to_string(material_row) + "]: value 7");
}

// An initial condition whose expression is not finite at particles of the last rank only
// (x >= 19.25 mm of a 20 mm block): each rank evaluates its own particles, and the refusal is
// every rank's (setup.cpp, refuse_together), printed once, exit code 2. The ranks that did
// not meet it waited at the next collective, silent, until killed.
TEST(Distributed, AnInitialExpressionNotFiniteOnOneRankIsTheOneProcessMessageOnce) {
  expect_one_refusal_on_three_ranks_as_one_process(
      "mpi_dist_initial_expression",
      "specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.02, 0.004, 0.004], spacing: 0.5 mm}}\n"
      "model: {type: pmb, horizon_factor: 3.015}\n"
      "materials: [{name: m, density: 2000, youngs_modulus: 10 GPa, poisson_ratio: 0.25}]\n"
      "initial: [{type: velocity, expression: ['sqrt(0.019 - x)', '0', '0']}]\n"
      "time: {steps: 2}\n",
      "initial[0].expression[0]: 'sqrt(0.019 - x)' is not finite at (0.019250");
}

// A boundary expression in t that is not finite at one particle of the last rank only (the
// block's far corner, x + y + z = 0.02725 m > 0.0272): each rank samples its system's
// constraint particles over the run before the writers open (run.cpp), and the refusal is
// every rank's, printed once, exit code 2, as one process's. Before, the rank that met it
// refused at the step, after the outputs began, and the others waited at the next collective.
TEST(Distributed, ABoundaryExpressionNotFiniteOnOneRankIsTheOneProcessMessageOnce) {
  expect_one_refusal_on_three_ranks_as_one_process(
      "mpi_dist_boundary_expression",
      "specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.02, 0.004, 0.004], spacing: 0.5 mm}}\n"
      "model: {type: pmb, horizon_factor: 3.015}\n"
      "materials: [{name: m, density: 2000, youngs_modulus: 10 GPa, poisson_ratio: 0.25}]\n"
      "sets: [{name: block, box: [0, 0, 0, 0.02, 0.004, 0.004]}]\n"
      "boundary: [{type: velocity, set: block, components: [x], expression: ['sqrt(0.0272 - x - y - z) * (1 + t)', '0', '0']}]\n"
      "time: {steps: 2}\n",
      "boundary[0].expression[0]: 'sqrt(0.0272 - x - y - z) * (1 + t)' is not finite at (0.01975");
}

// The graded check refusing one horizon over the graded block (graded_check.hpp): under
// mpirun every rank judges it from its block of the Morton sort (setup.cpp); on 3 ranks the
// one process's message (the same spacing ratio, ratio, worst particle, its position and the
// count), once, exit code 2.
TEST(Distributed, GradedHorizonRefusalOnThreeRanksIsTheOneProcessMessage) {
  const std::string graded = graded_notch();
  ASSERT_FALSE(graded.empty()) << "could not mesh the graded block";
  std::string yaml = graded_case(graded, "pmb", 10, true);
  yaml.replace(yaml.find("variable_horizon: true"), 22, "variable_horizon: false");
  expect_one_refusal_on_three_ranks_as_one_process("mpi_dist_graded", yaml,
                                                   "model.variable_horizon: particle spacings vary by");
}

// An output group's broken bits (mpi_backend.cpp broken_bits_together), with parallel HDF5:
// each rank forms and writes its own block of the dataset's bytes, so the most bytes of them
// each rank held (summary.json's broken_bits_bytes_per_rank) sum to the dataset's bytes once
// (exact) and, at 2 ranks or more and a dataset of 2 bytes or more, each is fewer than the
// dataset's (a rank that gathered the whole bits held all of them). Returns the figure. With a
// serial HDF5 rank 0 forms the whole bits and the figure is absent.
static std::vector<long long> expect_broken_bits_by_blocks(const std::string& one_dir, const std::string& out, int ranks) {
  const auto one = summary(one_dir), dist = summary(out);
#ifdef BRECCIA_PARALLEL_HDF5
  const auto sets = datasets(one_dir + "/results.h5");
  const auto it = sets.find("output/000000/broken");
  EXPECT_NE(it, sets.end()) << one_dir << ": no output group";
  if (it == sets.end()) return {};
  const long long whole = static_cast<long long>(it->second.size());
  EXPECT_FALSE(one.contains("broken_bits_bytes_per_rank")) << "one process forms the whole bits";
  EXPECT_TRUE(dist.contains("broken_bits_bytes_per_rank")) << out;
  if (!dist.contains("broken_bits_bytes_per_rank")) return {};
  const auto held = dist["broken_bits_bytes_per_rank"].get<std::vector<long long>>();
  EXPECT_EQ(held.size(), static_cast<size_t>(ranks)) << out;
  long long sum = 0;
  for (size_t r = 0; r < held.size(); ++r) {
    sum += held[r];
    if (ranks >= 2 && whole >= 2) EXPECT_LT(held[r], whole) << out << ": rank " << r << " held the whole broken bits";
  }
  EXPECT_EQ(sum, whole) << out << ": the ranks' blocks are not the dataset's bytes once each";
  return held;
#else
  EXPECT_FALSE(dist.contains("broken_bits_bytes_per_rank")) << out;
  (void)one;
  (void)ranks;
  return {};
#endif
}

// Each rank's set-up built the bonds of its own rows alone (distributed_setup.hpp), read off
// summary.json's setup_entries_per_rank (rank 0 first): the candidate family entries (the
// family search's arrays, the set-up's largest) and the kept bond entries of the ranks sum to
// one process's exactly, and each rank's is a part of them. A rank that built the whole
// system's families or bond arrays, or any row another rank also built (a ghost's), breaks the
// sum; exact counts, no tolerance.
static void expect_each_rank_built_its_own_rows(const std::string& one_dir, const std::string& out, int ranks) {
  const auto one = summary(one_dir), dist = summary(out);
  ASSERT_TRUE(one.contains("setup_entries_per_rank") && dist.contains("setup_entries_per_rank")) << out;
  EXPECT_EQ(one["setup_entries_per_rank"]["kept"][0], one["bonds"]) << "one process keeps every entry";
  for (const char* kind : {"candidates", "kept"}) {
    const auto& whole = one["setup_entries_per_rank"][kind];
    const auto& each = dist["setup_entries_per_rank"][kind];
    ASSERT_EQ(whole.size(), 1u) << kind;
    ASSERT_EQ(each.size(), static_cast<size_t>(ranks)) << out << ": one value per rank, " << kind;
    long long sum = 0;
    for (const auto& e : each) {
      EXPECT_GT(e.get<long long>(), 0) << out << ", " << kind;
      EXPECT_LT(e.get<long long>(), whole[0].get<long long>()) << out << ": a rank built the whole system's " << kind;
      sum += e.get<long long>();
    }
    EXPECT_EQ(sum, whole[0].get<long long>()) << out << ": the ranks' " << kind << " are not one process's rows once each";
  }
  // The family search's particles: one process's every particle, each rank's its rows'
  // geometric window (build_own_families): its own particles and more, so the windows
  // together hold every particle at least once, each at most all of them.
  const auto& window = dist["setup_window_particles_per_rank"];
  ASSERT_EQ(one["setup_window_particles_per_rank"], nlohmann::json::array({one["particles"]}));
  ASSERT_EQ(window.size(), static_cast<size_t>(ranks)) << out;
  long long held = 0;
  for (const auto& w : window) {
    EXPECT_LE(w.get<long long>(), one["particles"].get<long long>()) << out;
    held += w.get<long long>();
  }
  EXPECT_GT(held, one["particles"].get<long long>()) << out << ": the windows hold the ranks' particles and their halos";
  // The set-up's system (distributed_setup.hpp plan_window_system): every rank its window
  // alone, the longest of its per-particle arrays (positions, volumes, state, the model's)
  // sized to it (exact counts); with a serial HDF5 rank 0 the whole body (its writers'
  // staging, root_stages_whole_body).
  const auto& system = dist["setup_system_particles_per_rank"];
  ASSERT_EQ(one["setup_system_particles_per_rank"], nlohmann::json::array({one["particles"]}));
  ASSERT_EQ(system.size(), static_cast<size_t>(ranks)) << out;
  const int first_window = breccia::solver::root_stages_whole_body() ? 1 : 0;
  if (first_window == 1) EXPECT_EQ(system[0], one["particles"]) << out << ": a staged rank 0 keeps the whole body";
  for (int r = first_window; r < ranks; ++r)
    EXPECT_EQ(system[r], window[r]) << out << ": rank " << r << "'s set-up arrays are not sized to its window";
  // The particle file's rows read (plan_window_system): every rank its block of the file
  // (the sort's), its slice's window's, then its rows' window's: the most held at once at
  // least its window, at most the body; a staged rank 0 every row.
  const auto& file_rows = dist["setup_file_rows_per_rank"];
  ASSERT_EQ(one["setup_file_rows_per_rank"], nlohmann::json::array({one["particles"]}));
  ASSERT_EQ(file_rows.size(), static_cast<size_t>(ranks)) << out;
  if (first_window == 1) EXPECT_EQ(file_rows[0], one["particles"]) << out << ": a staged rank 0 reads every row";
  for (int r = first_window; r < ranks; ++r) {
    EXPECT_GE(file_rows[r].get<long long>(), window[r].get<long long>()) << out << ": rank " << r;
    EXPECT_LE(file_rows[r].get<long long>(), one["particles"].get<long long>()) << out << ": rank " << r;
  }
  // The row offsets (distributed_setup.hpp cut_partition, finish_distributed_setup): every
  // rank at most its set-up system's (its window's rows, n + 1 of the window), never the
  // body's; a staged rank 0 the whole system's (n + 1: its writers' staging).
  const auto& offsets = dist["offsets_rows_per_rank"];
  ASSERT_EQ(offsets.size(), static_cast<size_t>(ranks)) << out;
  if (first_window == 1) EXPECT_EQ(offsets[0].get<long long>(), one["particles"].get<long long>() + 1) << out << ": rank 0";
  for (int r = first_window; r < ranks; ++r)
    EXPECT_LE(offsets[r].get<long long>(), system[r].get<long long>() + 1)
        << out << ": rank " << r << " held row offsets beyond its window's";
#ifdef BRECCIA_PARALLEL_HDF5
  // results.h5's bond-list offsets (mpi_backend.cpp file_bond_offsets): each rank holds its
  // block of the n + 1 rows and its own rows' first places, so the ranks hold 2 n + 1 in all
  // (exact counts) and, from 3 ranks on, each fewer than the body's n (2 ranks: about n each).
  // With a serial HDF5 rank 0 holds the whole list and the figure is absent.
  const long long n = one["particles"].get<long long>();
  ASSERT_FALSE(one.contains("file_offsets_rows_per_rank")) << "one process holds the whole list";
  ASSERT_TRUE(dist.contains("file_offsets_rows_per_rank")) << out;
  const auto& file_offsets = dist["file_offsets_rows_per_rank"];
  ASSERT_EQ(file_offsets.size(), static_cast<size_t>(ranks)) << out;
  long long file_offsets_held = 0;
  for (int r = 0; r < ranks; ++r) {
    file_offsets_held += file_offsets[r].get<long long>();
    if (ranks >= 3) EXPECT_LT(file_offsets[r].get<long long>(), n) << out << ": rank " << r << " held the whole offsets";
  }
  EXPECT_EQ(file_offsets_held, 2 * n + 1) << out;
#endif
  expect_broken_bits_by_blocks(one_dir, out, ranks);
}

// A case run by one process and, with the distributed set-up, on each of `ranks`: no fallback
// note, and results.h5, history.csv and (for a dynamic run) checkpoint.h5 byte for byte.
static void expect_distributed_setup_gives_one_process_answer(const std::string& name, const std::string& yaml,
                                                              std::vector<int> ranks = {2, 3}) {
  const std::string file = write_case("mpi_dist_" + name, yaml);
  const std::string base = process_temp_dir() + "/dist_setup_" + name;
  const Outcome one = solve(file, base + "_whole", 1, 1);
  ASSERT_EQ(one.exit_code, 0) << name << ": " << one.err;
  EXPECT_GT(summary(base + "_whole")["broken_bonds"].get<long long>(), 0) << name << ": no bond broke";
  const bool relaxed = summary(base + "_whole")["status"] == "converged";  // ADR writes no checkpoint
  for (const int r : ranks) {
    const std::string out = base + "_np" + std::to_string(r);
    const Outcome o = solve(file, out, r, 1);
    ASSERT_EQ(o.exit_code, 0) << name << ": " << o.err;
    EXPECT_TRUE(summary(out)["distributed_setup"].get<bool>()) << name << ", " << r << " ranks built the whole system";
    expect_each_rank_built_its_own_rows(base + "_whole", out, r);
    EXPECT_EQ(o.err.find("note: set-up"), std::string::npos) << name << ": " << o.err;
    EXPECT_EQ(summary(out)["steps"], summary(base + "_whole")["steps"]) << name << ", " << r << " ranks";
    for (const char* f : {"/results.h5", "/checkpoint.h5"}) {
      if (relaxed && std::string(f) == "/checkpoint.h5") continue;
      EXPECT_EQ(differing(base + "_whole" + f, out + f), std::vector<std::string>{}) << name << ", " << r << " ranks, " << f;
    }
    expect_same_history(base + "_whole", out);
  }
}

// The distributed set-up (distributed_setup.hpp): under mpirun a PMB case builds on each rank
// the bonds of the particles it owns only, and the answer is still one process's, byte for
// byte: a lattice with a pre-crack expanding until bonds break, on 2 and 3 ranks, and its
// checkpoint of 2 ranks finished on 3; softening bonds with Weibull draws on 2 ranks.
TEST(DistributedSetup, PmbBuildsEachRanksOwnBondsWithOneProcessAnswer) {
  const std::string body =
      "specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.008, 0.004, 0.003], spacing: 0.5 mm}}\n"
      "precracks: [{type: polygon, points: [[0.004, -0.001, -0.001], [0.004, 0.002, -0.001], [0.004, 0.002, 0.004], [0.004, -0.001, 0.004]]}]\n"
      "initial: [{type: radial_velocity, center: [0.004, 0.002, 0.0015], strain_rate: 300}]\n"
      "time: {steps: 60}\n"
      "output: {every: 30, history_every: 10, fields: [damage, displacement, velocity]}\n";
  const std::string brittle =
      "materials: [{name: m, density: 2000, youngs_modulus: 10 GPa, poisson_ratio: 0.25, fracture_energy: 2}]\n";
  const std::string pmb = write_case("mpi_dist_pmb", "model: {type: pmb, horizon_factor: 3.015}\n" + brittle + body);
  const std::string base = process_temp_dir() + "/dist_setup";
  ASSERT_EQ(solve(pmb, base + "_whole", 1, 1).exit_code, 0);
  EXPECT_FALSE(summary(base + "_whole")["distributed_setup"].get<bool>());
  EXPECT_GT(summary(base + "_whole")["broken_bonds"].get<long long>(), 0) << "no bond broke: the test would not see bond states";
  for (const int ranks : {2, 3}) {
    const std::string out = base + "_np" + std::to_string(ranks);
    const Outcome o = solve(pmb, out, ranks, 1);
    ASSERT_EQ(o.exit_code, 0) << o.err;
    EXPECT_TRUE(summary(out)["distributed_setup"].get<bool>()) << ranks << " ranks built the whole system";
    expect_each_rank_built_its_own_rows(base + "_whole", out, ranks);
    // On this lattice every window is a part of the body: the set-up arrays of the ranks (but
    // a staged rank 0's) hold fewer particles than the body (a window system).
    for (int r = breccia::solver::root_stages_whole_body() ? 1 : 0; r < ranks; ++r)
      EXPECT_LT(summary(out)["setup_system_particles_per_rank"][r].get<long long>(),
                summary(base + "_whole")["particles"].get<long long>())
          << ranks << " ranks: rank " << r << " holds whole-body arrays at set-up";
    // Each rank's resident set at the end of its loop (docs/parallel.md, Memory), rank 0 first.
    const auto loop_mb = summary(out)["loop_resident_mb"];
    ASSERT_EQ(loop_mb.size(), static_cast<size_t>(ranks)) << "one value per rank";
    for (const auto& mb : loop_mb) EXPECT_GT(mb.get<double>(), 1.0);
    EXPECT_EQ(o.err.find("note: set-up"), std::string::npos) << o.err;
    for (const char* file : {"/results.h5", "/checkpoint.h5"})
      EXPECT_EQ(differing(base + "_whole" + file, out + file), std::vector<std::string>{}) << ranks << " ranks, " << file;
    expect_same_history(base + "_whole", out);
  }
  for (const int ranks : {3}) {  // stopped at step 30 on 2 ranks, finished on 3
    const std::string out = base + "_restart_on" + std::to_string(ranks);
    ASSERT_EQ(solve(pmb, out, 2, 1, "--steps 30").exit_code, 0);
    const Outcome second = solve(pmb, out, ranks, 1, "--steps 30 --restart " + out + "/checkpoint.h5");
    ASSERT_EQ(second.exit_code, 0) << second.err;
    EXPECT_EQ(differing(base + "_whole/checkpoint.h5", out + "/checkpoint.h5"), std::vector<std::string>{})
        << "finished on " << ranks;
  }
  // Softening bonds (bond damage is state too, in the checkpoint) with Weibull draws.
  const std::string soft = write_case(
      "mpi_dist_soft", "model: {type: pmb, horizon_factor: 3.015}\n"
                       "materials: [{name: m, density: 2000, youngs_modulus: 10 GPa, poisson_ratio: 0.25, fracture_energy: 2, "
                       "tensile_strength: 2 MPa, weibull: {modulus: 6, seed: 3}}]\n" + body);
  ASSERT_EQ(solve(soft, base + "_soft_whole", 1, 1).exit_code, 0);
  {
    const Outcome o = solve(soft, base + "_soft_np2", 2, 1);
    ASSERT_EQ(o.exit_code, 0) << o.err;
    EXPECT_TRUE(summary(base + "_soft_np2")["distributed_setup"].get<bool>());
    for (const char* file : {"/results.h5", "/checkpoint.h5"})
      EXPECT_EQ(differing(base + "_soft_whole" + file, base + "_soft_np2" + file), std::vector<std::string>{}) << file;
  }
}

// A body load on a set acts on the set's particles alone, also on a rank that holds none of
// them: a 8 x 4 x 3 mm PMB lattice whose first millimetre along x is pushed (the set `end`,
// 2 of the 16 layers), one process against 2, 3 and 4 ranks (the Morton ranges leave some
// ranks without a particle of the set), results.h5, checkpoint.h5 and history.csv byte for
// byte. (An empty list once meant "every particle": such a rank pushed all its particles.)
TEST(DistributedSetup, ABodyLoadOnASetSomeRanksDoNotHoldGivesTheOneProcessAnswer) {
  const std::string file = write_case(
      "mpi_dist_body_set",
      "specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.008, 0.004, 0.003], spacing: 0.5 mm}}\n"
      "model: {type: pmb, horizon_factor: 3.015}\n"
      "materials: [{name: m, density: 2000, youngs_modulus: 10 GPa, poisson_ratio: 0.25, fracture_energy: 2}]\n"
      "sets: [{name: end, box: [0, 0, 0, 0.001, 0.004, 0.003]}]\n"
      "loads: [{type: body_force, set: end, value: [2e7, 0, 0]}]\n"
      "time: {steps: 40}\n"
      "output: {every: 20, history_every: 10, fields: [damage, displacement, velocity]}\n");
  const std::string base = process_temp_dir() + "/dist_body_set";
  const Outcome one = solve(file, base + "_whole", 1, 1);
  ASSERT_EQ(one.exit_code, 0) << one.err;
  for (const int r : {2, 3, 4}) {
    const std::string out = base + "_np" + std::to_string(r);
    const Outcome o = solve(file, out, r, 1);
    ASSERT_EQ(o.exit_code, 0) << o.err;
    for (const char* f : {"/results.h5", "/checkpoint.h5"})
      EXPECT_EQ(differing(base + "_whole" + f, out + f), std::vector<std::string>{}) << r << " ranks, " << f;
    expect_same_history(base + "_whole", out);
  }
}

// The particle file on the ranks (distributed_setup.hpp plan_window_system): each reads its
// block of the rows, then the rows of its slice's window and of its rows' window
// (hyperslabs), never the whole file (but a staged rank 0, serial HDF5), and what the set-up
// reads of every particle the ranks take together from their blocks: here a traction spread
// over the boundary layer of a graded mesh (depth: horizon; the layer's particles and volume:
// layer_of_surface), a case set near a surface (each rank's members among its rows, the set's
// whole count the blocks' sum), the pre-crack's facets (the notch). One process against 2, 3
// and 4 ranks: results.h5, checkpoint.h5 and history.csv byte for byte, and each rank held
// fewer of the file's rows at once than the body.
TEST(DistributedSetup, ATractionOverAGradedLayerGivesTheOneProcessAnswerFromEachRanksWindowRows) {
  const std::string particles = notched_block();
  ASSERT_FALSE(particles.empty());
  const std::string file = write_case(
      "mpi_dist_layer",
      "specimen: {particles: " + particles + "}\n"
      "model: {type: pmb, horizon_factor: 3.015, variable_horizon: true}\n"
      "materials: [{name: block, density: 2400, youngs_modulus: 30 GPa, poisson_ratio: 0.25, fracture_energy: 20}]\n"
      "precracks: [{type: surface, surface: notch}]\n"
      "sets: [{name: grip, near_surface: {surface: xmin, distance: 2 mm}}]\n"
      "boundary: [{type: velocity, set: grip, value: [0, 0, 0], components: [x]}]\n"
      "loads: [{type: traction, surface: xmax, value: [200 MPa, 0, 0], depth: horizon}]\n"
      "time: {steps: 30}\n"
      "output: {every: 15, history_every: 5, fields: [damage, displacement, velocity]}\n");
  const std::string base = process_temp_dir() + "/dist_layer";
  const Outcome one = solve(file, base + "_whole", 1, 1);
  ASSERT_EQ(one.exit_code, 0) << one.err;
  const long long body = summary(base + "_whole")["particles"].get<long long>();
  for (const int r : {2, 3, 4}) {
    const std::string out = base + "_np" + std::to_string(r);
    const Outcome o = solve(file, out, r, 1);
    ASSERT_EQ(o.exit_code, 0) << o.err;
    expect_each_rank_built_its_own_rows(base + "_whole", out, r);
    for (int q = breccia::solver::root_stages_whole_body() ? 1 : 0; q < r; ++q)
      EXPECT_LT(summary(out)["setup_file_rows_per_rank"][q].get<long long>(), body)
          << r << " ranks: rank " << q << " read every row of the particle file";
    for (const char* f : {"/results.h5", "/checkpoint.h5"})
      EXPECT_EQ(differing(base + "_whole" + f, out + f), std::vector<std::string>{}) << r << " ranks, " << f;
    expect_same_history(base + "_whole", out);
  }
}

// results.h5's bond list (/bonds/*) written by rows (docs/parallel.md, Files): with parallel
// HDF5 each rank forms its own rows of the list, in the particle file's order (not one range:
// the ranks own Morton ranges), and writes them together; the pad bonds' within_horizon bits
// are cleared from every rank's places. A pre-cracked PMB lattice (0.5 mm spacing, m = 3.015:
// about a quarter of its bonds are pads, checked below, so both bit values are compared)
// expanding until bonds break: at 2 and 3 ranks every dataset of results.h5, the bond list
// among them, is one process's byte for byte; a checkpoint of 3 ranks restarted on 2 into a
// fresh folder (a new results.h5, its bond list written by the ranks at the restart) gives
// one process's restart into a fresh folder; a restart whose results.h5 holds another bond
// list is an input error on 2 ranks (exit code 2, the dataset named), as on one process.
// Without parallel HDF5 rank 0 writes the list alone and the same comparisons hold.
TEST(Distributed, ResultsBondListWrittenByRowsEqualsOneProcessFile) {
  const std::string file = write_case(
      "mpi_bond_rows",
      "specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.008, 0.006, 0.004], spacing: 0.5 mm}}\n"
      "model: {type: pmb, horizon_factor: 3.015}\n"
      "materials: [{name: m, density: 2000, youngs_modulus: 10 GPa, poisson_ratio: 0.25, fracture_energy: 2}]\n"
      "precracks: [{type: polygon, points: [[0.004, -0.001, -0.001], [0.004, 0.003, -0.001], [0.004, 0.003, 0.005], [0.004, -0.001, 0.005]]}]\n"
      "initial: [{type: radial_velocity, center: [0.004, 0.003, 0.002], strain_rate: 300}]\n"
      "time: {steps: 40}\n"
      "output: {every: 20, history_every: 10, fields: [damage, displacement, velocity]}\n");
  const std::string base = process_temp_dir() + "/bond_rows";
  ASSERT_EQ(solve(file, base + "_whole", 1, 1).exit_code, 0);
  ASSERT_EQ(solve(file, base + "_half", 1, 1, "--steps 20").exit_code, 0);
  {  // what the comparison covers: the list, both values of its bits, broken bonds
    const auto sets = datasets(base + "_whole/results.h5");
    for (const char* name : {"bonds/offsets", "bonds/neighbors", "bonds/within_horizon"})
      ASSERT_TRUE(sets.count(name)) << name;
    const size_t bonds = sets.at("bonds/neighbors").size() / sizeof(int64_t);
    size_t within = 0;
    for (const char byte : sets.at("bonds/within_horizon")) within += std::bitset<8>(static_cast<unsigned char>(byte)).count();
    EXPECT_GT(within, bonds / 2) << "most bonds lie within a horizon";
    EXPECT_LT(within, bonds - bonds / 10) << "the pad bonds (beyond both horizons) are at least a tenth";
    EXPECT_GT(summary(base + "_whole")["broken_bonds"].get<long long>(), 0) << "no bond broke";
  }
  for (const int ranks : {2, 3}) {
    const std::string out = base + "_np" + std::to_string(ranks);
    const Outcome o = solve(file, out, ranks, 1);
    ASSERT_EQ(o.exit_code, 0) << o.err;
    EXPECT_EQ(differing(base + "_whole/results.h5", out + "/results.h5"), std::vector<std::string>{}) << ranks << " ranks";
  }
  // Restarts into a fresh folder: the checkpoint of step 20, one process's and 3 ranks'.
  ASSERT_EQ(solve(file, base + "_np3_half", 3, 1, "--steps 20").exit_code, 0);
  const Outcome one = solve(file, base + "_fresh_whole", 1, 1, "--restart " + base + "_half/checkpoint.h5");
  const Outcome two = solve(file, base + "_fresh_np2", 2, 1, "--restart " + base + "_np3_half/checkpoint.h5");
  ASSERT_EQ(one.exit_code, 0) << one.err;
  ASSERT_EQ(two.exit_code, 0) << two.err;
  EXPECT_EQ(differing(base + "_fresh_whole/results.h5", base + "_fresh_np2/results.h5"), std::vector<std::string>{});
  // Another bond list in the folder's results.h5: refused on a restart, exit code 2.
  for (const int ranks : {1, 2}) {
    const std::string out = base + "_other_list" + std::to_string(ranks);
    std::filesystem::remove_all(out);
    std::filesystem::copy(base + "_np3_half", out);
    breccia::h5::File(out + "/results.h5", breccia::h5::File::Mode::ReadWrite)
        .write("/bonds/neighbors", std::vector<int64_t>{1, 2, 3}, {3});
    const Outcome o = solve(file, out, ranks, 1, "--restart " + out + "/checkpoint.h5");
    EXPECT_EQ(o.exit_code, 2) << ranks << " ranks: " << o.err;
    EXPECT_NE(o.err.find("/bonds/neighbors: missing or a different bond count"), std::string::npos) << o.err;
  }
  // A results.h5 of another particle model in the folder: the root alone opens it and refuses
  // it (ResultsWriter); under mpirun that refusal is every rank's (run.cpp, refuse_together),
  // printed once, exit code 2. The other ranks waited in the loop's first collective before.
  for (const int ranks : {1, 2}) {
    const std::string out = base + "_other_model" + std::to_string(ranks);
    std::filesystem::remove_all(out);
    std::filesystem::copy(base + "_np3_half", out);
    breccia::h5::File(out + "/results.h5", breccia::h5::File::Mode::ReadWrite)
        .set_attr("/", "particles_content_id", std::string("another model"));
    const Outcome o = solve(file, out, ranks, 1, "--restart " + out + "/checkpoint.h5");
    EXPECT_EQ(o.exit_code, 2) << ranks << " ranks: " << o.err;
    EXPECT_NE(o.err.find("/@particles_content_id: belongs to a different particle model"), std::string::npos) << o.err;
    EXPECT_EQ(o.err.find("error:", o.err.find("error:") + 1), std::string::npos) << "more than one error: " << o.err;
  }
}

// An output group's broken bits written by blocks of bytes (expect_broken_bits_by_blocks), here
// fewer bytes than ranks: a 3 x 2 x 1 PMB lattice (1 mm spacing, m = 3.015: all 15 pairs
// bonded, 2 bytes) expanding until 3 bonds break, bits in both bytes. At 4 ranks ranks 0 and 2
// hold no byte (they write none and still take part); at 2, 3 and 4 ranks every dataset of
// results.h5 is one process's byte for byte.
TEST(Distributed, BrokenBitsWrittenByBlocksEvenWhereARankHoldsNoByte) {
  const std::string file = write_case(
      "mpi_bits_tiny",
      "specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.003, 0.002, 0.001], spacing: 1 mm}}\n"
      "model: {type: pmb, horizon_factor: 3.015}\n"
      "materials: [{name: m, density: 2000, youngs_modulus: 10 GPa, poisson_ratio: 0.25, fracture_energy: 2}]\n"
      "initial: [{type: radial_velocity, center: [0.0012, 0.001, 0.0005], strain_rate: 100}]\n"
      "time: {steps: 40, check_stability: false}\n"
      "output: {every: 20, history_every: 10, fields: [damage, displacement, velocity]}\n");
  const std::string base = process_temp_dir() + "/bits_tiny";
  const Outcome one = solve(file, base + "_whole", 1, 1);
  ASSERT_EQ(one.exit_code, 0) << one.err;
  {  // what the comparison covers: 2 bytes of bits, broken bonds in each
    const auto sets = datasets(base + "_whole/results.h5");
    ASSERT_TRUE(sets.count("output/000002/broken"));
    const std::string& bits = sets.at("output/000002/broken");
    ASSERT_EQ(bits.size(), 2u);
    EXPECT_NE(bits[0], 0) << "no broken bond in the first byte";
    EXPECT_NE(bits[1], 0) << "no broken bond in the second byte";
    EXPECT_GT(summary(base + "_whole")["broken_bonds"].get<long long>(), 0);
  }
  for (const int ranks : {2, 3, 4}) {
    const std::string out = base + "_np" + std::to_string(ranks);
    const Outcome o = solve(file, out, ranks, 1);
    ASSERT_EQ(o.exit_code, 0) << o.err;
    EXPECT_EQ(differing(base + "_whole/results.h5", out + "/results.h5"), std::vector<std::string>{}) << ranks << " ranks";
    [[maybe_unused]] const std::vector<long long> held = expect_broken_bits_by_blocks(base + "_whole", out, ranks);
#ifdef BRECCIA_PARALLEL_HDF5
    if (ranks == 4) EXPECT_EQ(held, (std::vector<long long>{0, 1, 0, 1})) << "bytes 2 q / 4 to 2 (q + 1) / 4 on rank q";
#endif
  }
}

// The distributed set-up beyond PMB: LPS (each rank sums the weighted volume of its own rows,
// the ghosts' come from their owners), float32 (each rank's system converts its own
// particles and bonds), the energy surface correction with PMB and LPS (the ghosts' axis
// factors gathered after each sweep, the complete families' means summed in one process's
// order), 2D PMB and LPS (the ghosts' family reweighting (a, b), completeness and critical
// stretch scales gathered), and dual horizon (variable_horizon: each own row tests both ends of
// a pair instead of the transposed search) with PMB and LPS on a graded tet arrangement
// (0.4 mm tets at a notch grading to 1 mm: horizons differ by 3x between bonded
// particles). Each on 2 and 3 ranks against one process: results.h5, checkpoint.h5 and
// history.csv byte for byte, no fallback note.
TEST(DistributedSetup, LpsFloat32SurfaceCorrection2dAndDualHorizonBuildEachRanksOwnBondsWithOneProcessAnswer) {
  const std::string lattice_body =
      "specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.008, 0.004, 0.003], spacing: 0.5 mm}}\n"
      "precracks: [{type: polygon, points: [[0.004, -0.001, -0.001], [0.004, 0.002, -0.001], [0.004, 0.002, 0.004], [0.004, -0.001, 0.004]]}]\n"
      "initial: [{type: radial_velocity, center: [0.004, 0.002, 0.0015], strain_rate: 300}]\n"
      "materials: [{name: m, density: 2000, youngs_modulus: 10 GPa, poisson_ratio: 0.25, fracture_energy: 2}]\n"
      "time: {steps: 60}\n"
      "output: {every: 30, history_every: 10, fields: [damage, displacement, velocity]}\n";
  const std::string graded = graded_notch();
  ASSERT_FALSE(graded.empty()) << "could not mesh the graded block";
  auto flat_case = [](const std::string& model, const std::string& poisson) {
    return "model: {type: " + model + ", horizon_factor: 3.015, planar: plane_stress}\n"
           "specimen: {lattice: {dimension: 2, box: [0, 0, 0.008, 0.004], spacing: 0.25 mm, thickness: 1 mm}}\n"
           "materials: [{name: m, density: 2000, youngs_modulus: 10 GPa, poisson_ratio: " + poisson + ", fracture_energy: 2}]\n"
           "precracks: [{type: segment, from: [0.004, -0.001], to: [0.004, 0.002]}]\n"
           "initial: [{type: radial_velocity, center: [0.004, 0.002, 0], strain_rate: 2000}]\n"
           "time: {steps: 60}\n"
           "output: {every: 30, history_every: 10, fields: [damage, displacement, velocity]}\n";
  };
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"flat_pmb", flat_case("pmb", "0.3333333333333333")},  // PMB's plane-stress Poisson ratio: 1/3
      {"flat_lps", flat_case("lps", "0.25")},
      {"lps", "model: {type: lps, horizon_factor: 3.015}\n" + lattice_body},
      {"float32", "model: {type: pmb, horizon_factor: 3.015, precision: float32}\n" + lattice_body},
      {"surface_pmb", "model: {type: pmb, horizon_factor: 3.015, surface_correction: energy}\n" + lattice_body},
      {"surface_lps", "model: {type: lps, horizon_factor: 3.015, surface_correction: energy}\n" + lattice_body},
      {"dual_pmb", graded_case(graded, "pmb", 40, false)},
      {"dual_lps", graded_case(graded, "lps", 40, false)},
  };
  for (const auto& [name, yaml] : cases) expect_distributed_setup_gives_one_process_answer(name, yaml);
}

// Correspondence (its shape tensor and deformation gradient are computed per step from the
// own family; between its two passes each ghost receives its owner's force tensor, the one
// halo exchange of the step) and dynamic relaxation (its damping's Rayleigh quotient, the
// residual and the load norm are reproducible sums over ranks; its fictitious density comes
// from the stable step, which is one process's to the last bit) with the distributed
// set-up: each rank builds its own bonds, and results.h5, checkpoint.h5 and history.csv
// are one process's byte for byte (the bound for ADR is 1e-12; bytes hold).
// Correspondence on the graded, notched tet block with the dual horizon (2, 3 and 4
// ranks, with the start-up checks: the energy-scatter check's force pass runs on each
// rank's rows and its sums over every rank's sampled particles in one process's order), and
// on a pre-cracked lattice expanding (correspondence grows zero-energy modes
// there after about 40 steps: 20 are compared); ADR with LPS and with correspondence
// (penalty stabilisation) on a pre-cracked bar under end pressure (they converge in a few
// hundred to a few thousand iterations; the cap of 10,000 makes a broken exchange fail fast).
TEST(DistributedSetup, CorrespondenceAndDynamicRelaxationBuildEachRanksOwnBondsWithOneProcessAnswer) {
  const std::string graded = graded_notch();
  ASSERT_FALSE(graded.empty()) << "could not mesh the graded block";
  expect_distributed_setup_gives_one_process_answer("dual_corr", graded_case(graded, "correspondence", 40, true), {2, 3, 4});
  // The energy-scatter check refusing a horizon too small for the tets (m = 1.5: 32 % RMS
  // against the 20 % limit, family_check.hpp): on 3 ranks the one process's message (the
  // same scatter, count and worst particle), once, exit code 2.
  {
    std::string yaml = graded_case(graded, "lps", 40, true);
    yaml.replace(yaml.find("horizon_factor: 3.015"), 21, "horizon_factor: 1.5");
    expect_one_refusal_on_three_ranks_as_one_process("mpi_dist_scatter", yaml,
                                                     "model.horizon_factor: per-particle strain energy");
  }
  expect_distributed_setup_gives_one_process_answer(
      "corr",
      "specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.008, 0.004, 0.003], spacing: 0.5 mm}}\n"
      "model: {type: correspondence, horizon_factor: 3.015}\n"
      "materials: [{name: m, density: 2000, youngs_modulus: 10 GPa, poisson_ratio: 0.25, fracture_energy: 2}]\n"
      "precracks: [{type: polygon, points: [[0.004, -0.001, -0.001], [0.004, 0.002, -0.001], [0.004, 0.002, 0.004], [0.004, -0.001, 0.004]]}]\n"
      "initial: [{type: radial_velocity, center: [0.004, 0.002, 0.0015], strain_rate: 300}]\n"
      "time: {steps: 20}\n"
      "output: {every: 10, history_every: 5, fields: [damage, displacement, velocity]}\n");
  const auto bar = [](const std::string& model, const std::string& size, const std::string& tolerance) {
    return "specimen: {lattice: {dimension: 3, box: [0, 0, 0, " + size + "], spacing: 1 mm}}\n"
           "model: {" + model + ", horizon_factor: 3.015}\n"
           "materials: [{name: m, density: 2000, youngs_modulus: 10 GPa, poisson_ratio: 0.25}]\n"
           "precracks: [{type: polygon, points: [[0.006, -0.001, -0.001], [0.006, 0.003, -0.001], [0.006, 0.003, 0.005], [0.006, -0.001, 0.005]]}]\n"
           "loads: [{type: pressure, surface: xmax, history: {type: constant, value: -2 MPa}}]\n"
           "boundary: [{type: displacement, set: xmin, value: [0, 0, 0]}]\n"
           "time: {integrator: adr, adr_tolerance: " + tolerance + ", adr_max_steps: 10000}\n"
           "output: {fields: [displacement]}\n";
  };
  expect_distributed_setup_gives_one_process_answer("adr_lps", bar("type: lps", "0.012, 0.006, 0.004", "1e-10"));
  expect_distributed_setup_gives_one_process_answer(
      "adr_corr", bar("type: correspondence, stabilisation: {type: penalty, coefficient: 1}", "0.012, 0.006, 0.004", "1e-8"));
}

// Short-range forces between particles that were never in one family, owned by different
// ranks (ContactExchange, mpi_backend.cpp). A lattice block cut through at x = 6 mm by a
// pre-crack; its right half is moved 2 mm along y (more than the 1.5 mm horizon), so the
// particles facing each other across the cut are not family members, and 0.2 mm along x, so
// they start 0.7 mm apart, just outside the 0.675 mm reach (1.35 x the spacing). The halves
// then close at 20 m/s and collide through those pairs only. Two ranks cut the block at the
// pre-crack, so every such pair has its ends on two ranks (a run whose ranks send none of
// them ends, measured, as one process without the pass over those pairs). What must hold: the one-process files, byte
// for byte, at 2 and 3 ranks, each rank building its own bonds (the distributed set-up); and
// the collision must be there (without short-range forces
// the halves pass through each other: a different answer).
TEST(Distributed, ShortRangeForcesBetweenRanksGiveTheOneProcessAnswer) {
  for (const std::string model : {"type: pmb", "type: lps", "type: pmb, precision: float32"}) {
    auto deck = [&](bool contact) {
      return std::string("specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.012, 0.006, 0.003], spacing: 0.5 mm}}\n") +
             "model: {" + model + ", horizon_factor: 3.015" + (contact ? ", short_range_forces: true" : "") + "}\n"
             "materials: [{name: m, density: 2000, youngs_modulus: 10 GPa, poisson_ratio: 0.25, fracture_energy: 50}]\n"
             "sets: [{name: left, box: [-0.001, -0.001, -0.001, 0.006, 0.007, 0.004]},\n"
             "       {name: right, box: [0.006, -0.001, -0.001, 0.013, 0.007, 0.004]}]\n"
             "precracks: [{type: polygon, points: [[0.006, -0.001, -0.001], [0.006, 0.007, -0.001], "
             "[0.006, 0.007, 0.004], [0.006, -0.001, 0.004]]}]\n"
             "initial:\n"
             "  - {type: velocity, set: left, value: [10, 0, 0]}\n"
             "  - {type: velocity, set: right, value: [-10, 0, 0]}\n"
             "  - {type: displacement, set: right, value: [0.2 mm, 2 mm, 0]}\n"
             "time: {steps: 80}\n"
             "output: {every: 40, history_every: 10, fields: [damage, displacement, velocity]}\n";
    };
    const std::string tag = model.find("lps") != std::string::npos ? "lps" : model.find("float32") != std::string::npos ? "f32" : "pmb";
    const std::string file = write_case("mpi_contact_" + tag, deck(true));
    const std::string base = process_temp_dir() + "/contact_" + tag;
    const Outcome ref = solve(file, base + "_np1", 1, 1);
    ASSERT_EQ(ref.exit_code, 0) << ref.err;
    const Outcome plain = solve(write_case("mpi_no_contact_" + tag, deck(false)), base + "_off", 1, 1);
    ASSERT_EQ(plain.exit_code, 0) << plain.err;
    EXPECT_NE(read_text(base + "_np1/history.csv"), read_text(base + "_off/history.csv"))
        << model << ": the short-range forces changed nothing: no collision to check";
    for (const int ranks : {2, 3}) {
      const std::string out = base + "_np" + std::to_string(ranks);
      const Outcome o = solve(file, out, ranks, 1);
      ASSERT_EQ(o.exit_code, 0) << out << ": " << o.err;
      expect_one_process_files(base + "_np1", out);
      EXPECT_TRUE(summary(out)["distributed_setup"].get<bool>()) << out << " built the whole system";
      EXPECT_EQ(o.err.find("note: set-up"), std::string::npos) << out << ": " << o.err;
    }
  }
  // Mesh-derived particles with the start-up checks (the energy-scatter check's force pass
  // runs the short-range forces too) and the dual horizon: the graded, notched block pulled
  // apart, at 2 and 3 ranks with the distributed set-up.
  std::string graded = graded_case(graded_notch(), "pmb", 40, true);
  const std::string key = "variable_horizon: true";
  graded.replace(graded.find(key), key.size(), key + ", short_range_forces: true");
  expect_distributed_setup_gives_one_process_answer("dual_pmb_short_range", graded);
}

// Gas loads under mpirun (gas.hpp; GasExchange, mpi_backend.cpp): the charge hole's gas
// enters the cracks it opens (LPS, and PMB in float32), and in a third case vents through a
// pre-crack to the outer face. The cavity's and the cracks' volumes are sums over the wall
// and over every particle: the ranks add every rank's terms in one process's order, and the
// front's arrival times reach the ghosts' owners as minima, so the gas (pressure, volumes,
// front, outflow) and the motion it drives are one process's at 2 and 3 ranks: results.h5,
// checkpoint.h5 (with the gas's front and wall shares) and history.csv (with the gas's
// columns) byte for byte; and a run stopped on 3 ranks and finished on 2 ends
// byte-identical too.
static void expect_gas_gives_one_process_answer(const std::string& name, const std::string& yaml) {
  const std::string file = write_case("mpi_" + name, yaml);
  const std::string base = process_temp_dir() + "/" + name;
  const Outcome one = solve(file, base + "_np1", 1, 1);
  ASSERT_EQ(one.exit_code, 0) << name << ": " << one.err;
  // What the comparison must see: gas in the cracks, and (venting) a vent.
  EXPECT_GT(last_history_value(base + "_np1", "crack_gas_volume_m3"), 0.0) << name << ": no gas in a crack";
  EXPECT_GT(last_history_value(base + "_np1", "gas_wetted_particles"), 100.0) << name << ": the front did not move";
  if (name != "gas_venting") EXPECT_GT(summary(base + "_np1")["broken_bonds"].get<long long>(), 0) << name;
  if (name == "gas_venting") {
    EXPECT_TRUE(summary(base + "_np1")["gas_vented"].get<bool>()) << name;
    EXPECT_LT(last_history_value(base + "_np1", "gas_mass_fraction"), 1.0) << name << ": no gas left";
  }
  for (const int ranks : {2, 3}) {
    const std::string out = base + "_np" + std::to_string(ranks);
    const Outcome o = solve(file, out, ranks, 1);
    ASSERT_EQ(o.exit_code, 0) << out << ": " << o.err;
    // Each rank built its own bonds and the gas's per-entry arrays of its rows.
    EXPECT_TRUE(summary(out)["distributed_setup"].get<bool>()) << out << " built the whole system";
    EXPECT_EQ(o.err.find("note: set-up"), std::string::npos) << out << ": " << o.err;
    expect_one_process_files(base + "_np1", out);
  }
  // Stopped on 3 ranks half way (on a history row: a stop writes one), finished on 2.
  const std::string out = base + "_restart";
  const long long steps = summary(base + "_np1")["steps"].get<long long>();
  ASSERT_EQ(solve(file, out, 3, 1, "--steps " + std::to_string(steps / 20 * 10)).exit_code, 0);
  const Outcome second = solve(file, out, 2, 1, "--restart " + out + "/checkpoint.h5");
  ASSERT_EQ(second.exit_code, 0) << second.err;
  EXPECT_EQ(differing(base + "_np1/checkpoint.h5", out + "/checkpoint.h5"), std::vector<std::string>{}) << out;
  expect_same_history(base + "_np1", out);
}

static const std::string kGasOutput = "output: {every: 50, history_every: 10, fields: [damage, displacement, velocity]}\n";

TEST(Distributed, GasLoadsGiveTheOneProcessAnswer) {
  ASSERT_FALSE(charge_hole_disc().empty()) << "could not mesh the charge-hole disc";
  const std::vector<std::pair<std::string, std::string>> cases = {
      // Breaking rock: the gas follows the cracks that grow from the pre-crack's tip.
      {"gas_cracking", gas_case(", fracture_energy: 20", "[15 mm, 0.01 mm]", "", "time: {end: 60 us}\n" + kGasOutput)},
      // The same in float (the gas reads the double mirror of the displacement, ghosts included).
      {"gas_float32", gas_case(", fracture_energy: 20", "[15 mm, 0.01 mm]", "", "time: {end: 60 us}\n" + kGasOutput,
                               "type: pmb, precision: float32")},
      // A pre-crack to the outer face: the front reaches it and the gas vents through the crack's mouth.
      {"gas_venting",
       gas_case("", "[41 mm, 0.01 mm]", ", vent_surfaces: [outer], vent_area: crack_opening", "time: {end: 120 us}\n" + kGasOutput)},
  };
  for (const auto& [name, yaml] : cases) expect_gas_gives_one_process_answer(name, yaml);
}

// Sparse crack passes (crack_pass_every, gas.hpp GasCrackDrift): at a pass the front takes one
// hop per step since the last, each hop reading the snapshot of the hop before over the
// particles and the ghosts. Between hops the ranks exchange what they reached (the smallest
// arrival time to the owner and back: gas_update), so the front crosses rank boundaries as
// on one process: the breaking rock of GasLoadsGiveTheOneProcessAnswer with passes up to 8
// steps apart gives one process's files at 2 and 3 ranks, and a run stopped on 3 ranks
// between two passes (checkpoint.h5's /gas/push and /gas/crack_pass) finishes on 2 alike.
TEST(Distributed, GasSparseCrackPassesGiveTheOneProcessAnswer) {
  ASSERT_FALSE(charge_hole_disc().empty()) << "could not mesh the charge-hole disc";
  const auto deck = [](const std::string& passes) {
    return gas_case(", fracture_energy: 20", "[15 mm, 0.01 mm]", passes, "time: {end: 60 us}\n" + kGasOutput);
  };
  expect_gas_gives_one_process_answer("gas_sparse_passes", deck(", crack_pass_every: 8, crack_pass_tolerance: 0.01"));
  const std::string base = process_temp_dir() + "/gas_sparse_passes";
  EXPECT_EQ(datasets(base + "_np1/checkpoint.h5").count("gas/push"), 1u) << "no crack-pass state in the checkpoint";
  // The passes did spread out (else the hops, and the exchange between them, went untested):
  // the answer differs from the every-step passes'.
  ASSERT_EQ(solve(write_case("mpi_gas_every_step", deck("")), base + "_every_step", 1, 1).exit_code, 0);
  EXPECT_NE(read_text(base + "_np1/history.csv"), read_text(base + "_every_step/history.csv"))
      << "the sparse passes ran every step";
}
// The rate law (materials[].strength_rate: a softening bond's onset raised by its stretch
// rate when it begins to soften, and kept): the stretch rate reads the partner's velocity, so
// the ghosts receive their owners' velocities with their displacements, and the raised
// onsets are state (in checkpoint.h5's /bond_onset, gathered whole on each rank's global
// system like the bond damage). Softening bonds with Weibull draws on the pre-cracked
// lattice expanding at 300/s: with the distributed set-up, 2 and 3 ranks give one process's
// files byte for byte, and a run stopped on 3 ranks and finished on 2 ends byte-identical.
TEST(DistributedSetup, RateLawGivesTheOneProcessAnswer) {
  auto deck = [](bool rate) {
    return std::string("model: {type: pmb, horizon_factor: 3.015}\n") +
           "materials: [{name: m, density: 2000, youngs_modulus: 10 GPa, poisson_ratio: 0.25, fracture_energy: 2, "
           "tensile_strength: 2 MPa, weibull: {modulus: 6, seed: 3}" + (rate ? ", strength_rate: fib_mc2010" : "") + "}]\n"
           "specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.008, 0.004, 0.003], spacing: 0.5 mm}}\n"
           "precracks: [{type: polygon, points: [[0.004, -0.001, -0.001], [0.004, 0.002, -0.001], [0.004, 0.002, 0.004], "
           "[0.004, -0.001, 0.004]]}]\n"
           "initial: [{type: radial_velocity, center: [0.004, 0.002, 0.0015], strain_rate: 300}]\n"
           "time: {steps: 60}\n"
           "output: {every: 30, history_every: 10, fields: [damage, displacement, velocity]}\n";
  };
  expect_distributed_setup_gives_one_process_answer("rate_law", deck(true));
  const std::string base = process_temp_dir() + "/dist_setup_rate_law";
  // The law matters here (else the comparison would not see it).
  ASSERT_EQ(solve(write_case("mpi_no_rate", deck(false)), base + "_static", 1, 1).exit_code, 0);
  EXPECT_NE(read_text(base + "_whole/history.csv"), read_text(base + "_static/history.csv"))
      << "the rate law changed nothing: no raised onset to check";
  const std::string file = write_case("mpi_dist_rate_law", deck(true));
  const std::string out = base + "_restart";
  ASSERT_EQ(solve(file, out, 3, 1, "--steps 30").exit_code, 0);
  const Outcome second = solve(file, out, 2, 1, "--steps 30 --restart " + out + "/checkpoint.h5");
  ASSERT_EQ(second.exit_code, 0) << second.err;
  EXPECT_EQ(differing(base + "_whole/checkpoint.h5", out + "/checkpoint.h5"), std::vector<std::string>{});
  expect_same_history(base + "_whole", out);
}

// A distributed restart reads each rank's owned rows of checkpoint.h5's per-particle
// datasets alone (read_checkpoint: one hyperslab each, the file's rows being in internal
// order); the ghosts' values come from their owners (MpiBackend::restart_ghosts). The
// minimum stretches of compressive enhancement are among them, and the force pass reads the
// partners' (ghosts'); float32's state is converted from the rows after the exchange: the
// pre-cracked lattice expanding, in double and in float32, stopped on 3 ranks and finished on
// 3, ends byte-identical to one process's uninterrupted run, and no rank read every row
// (summary.json's restart_rows_per_rank: with parallel HDF5 the ranks' owned counts, which
// add up to the body's, exact; with a serial HDF5 rank 0, its writers' staging, reads them
// all).
TEST(Distributed, RestartReadsEachRanksOwnRowsWithMinimumStretches) {
  for (const std::string precision : {"float64", "float32"}) {
    const std::string file = write_case("mpi_restart_rows_" + precision,
        "model: {type: pmb, horizon_factor: 3.015, compressive_enhancement: 0.25, precision: " + precision + "}\n"
        "materials: [{name: m, density: 2000, youngs_modulus: 10 GPa, poisson_ratio: 0.25, fracture_energy: 2}]\n"
        "specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.008, 0.004, 0.003], spacing: 0.5 mm}}\n"
        "precracks: [{type: polygon, points: [[0.004, -0.001, -0.001], [0.004, 0.002, -0.001], [0.004, 0.002, 0.004], "
        "[0.004, -0.001, 0.004]]}]\n"
        "initial: [{type: radial_velocity, center: [0.004, 0.002, 0.0015], strain_rate: 300}]\n"
        "time: {steps: 60}\n"
        "output: {every: 30, history_every: 10, fields: [damage, displacement, velocity]}\n");
    const std::string base = process_temp_dir() + "/restart_rows_" + precision;
    ASSERT_EQ(solve(file, base + "_whole", 1, 1).exit_code, 0);
    EXPECT_EQ(datasets(base + "_whole/checkpoint.h5").count("min_stretch"), 1u) << "no minimum stretches checkpointed";
    const std::string out = base + "_np3";
    ASSERT_EQ(solve(file, out, 3, 1, "--steps 30").exit_code, 0);
    const long long broken_half = summary(out)["broken_bonds"].get<long long>();
    const Outcome second = solve(file, out, 3, 1, "--steps 30 --restart " + out + "/checkpoint.h5");
    ASSERT_EQ(second.exit_code, 0) << second.err;
    EXPECT_EQ(differing(base + "_whole/checkpoint.h5", out + "/checkpoint.h5"), std::vector<std::string>{}) << precision;
    expect_same_history(base + "_whole", out);
    EXPECT_GT(summary(base + "_whole")["broken_bonds"].get<long long>(), broken_half)
        << precision << ": no bond broke after the restart";
    const long long n = summary(base + "_whole")["particles"].get<long long>();
    const nlohmann::json rows = summary(out)["restart_rows_per_rank"];
    ASSERT_EQ(rows.size(), 3u) << out;
    long long read = 0;
    for (int r = 0; r < 3; ++r) {
      read += rows[r].get<long long>();
#ifndef BRECCIA_PARALLEL_HDF5
      if (r == 0) {
        EXPECT_EQ(rows[0].get<long long>(), n) << "rank 0 stages the whole state";
        continue;
      }
#endif
      EXPECT_LT(rows[r].get<long long>(), n) << "rank " << r << " read every row of the checkpoint";
    }
#ifdef BRECCIA_PARALLEL_HDF5
    EXPECT_EQ(read, n) << "the ranks' owned rows are the body's, each read once";
#endif
  }
}

// An initial field from a file (initial[].file): a distributed set-up's ranks other than 0
// read their window's rows of it alone (an HDF5 dataset by those rows; a CSV file whole, then
// its window's rows kept), in the particle file's order. The expanding pre-cracked lattice
// with its radial velocity from an HDF5 file and a displacement of one set from a CSV file
// (17 significant digits: the same doubles) gives one process's files on 3 ranks.
TEST(DistributedSetup, AnInitialFieldFromAFileGivesTheOneProcessAnswer) {
  const std::string head =
      "model: {type: pmb, horizon_factor: 3.015}\n"
      "materials: [{name: m, density: 2000, youngs_modulus: 10 GPa, poisson_ratio: 0.25, fracture_energy: 2}]\n"
      "specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.008, 0.004, 0.003], spacing: 0.5 mm}}\n"
      "precracks: [{type: polygon, points: [[0.004, -0.001, -0.001], [0.004, 0.002, -0.001], [0.004, 0.002, 0.004], "
      "[0.004, -0.001, 0.004]]}]\n"
      "sets: [{name: top, box: [-1, 0.003, -1, 1, 1, 1]}]\n"
      "time: {steps: 60}\n"
      "output: {every: 30, history_every: 10, fields: [damage, displacement, velocity]}\n";
  const PdSystem probe = system_from_yaml("initial_file_probe", head);
  std::vector<double> v(3 * probe.n), u(3 * probe.n);
  const double c[3] = {0.004, 0.002, 0.0015};
  for (size_t i = 0; i < probe.n; ++i)
    for (int d = 0; d < 3; ++d) {  // a radial expansion at 300/s, and a small shear of the top
      v[3 * probe.original_index[i] + d] = 300.0 * (probe.x0[3 * i + d] - c[d]);
      u[3 * probe.original_index[i] + d] = d == 0 ? 1e-3 * probe.x0[3 * i + 1] : 0.0;
    }
  const std::string dir = process_temp_dir();
  {
    breccia::h5::File f(dir + "/v_initial.h5", breccia::h5::File::Mode::Create);
    f.write("velocity", v, {probe.n, 3});
  }
  {
    std::ofstream csv(dir + "/u_initial.csv");
    csv << "ux,uy,uz\n";
    csv.precision(17);
    for (size_t r = 0; r < probe.n; ++r) csv << u[3 * r] << "," << u[3 * r + 1] << "," << u[3 * r + 2] << "\n";
  }
  expect_distributed_setup_gives_one_process_answer(
      "initial_file", head + "initial:\n  - {type: velocity, file: " + dir + "/v_initial.h5, dataset: velocity}\n"
                             "  - {type: displacement, set: top, file: " + dir + "/u_initial.csv}\n", {3});
}

// The probes and the indenter, read on their ranks (MpiBackend::history_particles): each
// probe's owner sends its particle's value, each rank its particles' indenter terms in
// contact, which rank 0 adds in index order as one process does (indenter_reaction), so
// history.csv's probe and indenter columns are one process's text at 1 and 2 threads and 2
// and 3 ranks (the indenter's x and y reactions, sums of terms that nearly cancel, show any
// other order). With parallel HDF5 rank 0 then holds no whole state array after its loop
// (summary.json's loop_whole_bytes_rank0: the bytes of the whole per-particle and per-entry
// arrays its global system holds: before 2026-12-06 it held u, v, a, force, body, the fields
// and the reference arrays, 497,664 B here, 216 B per particle, and this test failed there);
// with serial HDF5 it holds them, the staging its files are written from.
TEST(Distributed, ProbesAndTheIndenterGiveTheOneProcessHistoryFromTheirOwners) {
  const std::string file = write_case("mpi_probes_indenter",
      "specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.012, 0.006, 0.004], spacing: 0.5 mm}}\n"
      "model: {type: lps, horizon_factor: 3.015}\n"
      "materials: [{name: m, density: 2000, youngs_modulus: 10 GPa, poisson_ratio: 0.25, fracture_energy: 5}]\n"
      "indenter: {radius: 2 mm, center: [0.009, 0.003, 0.0056], velocity: [0, 0, -20], stiffness: 1e15}\n"
      "boundary: [{type: displacement, set: zmin, value: [0, 0, 0]}]\n"
      "time: {steps: 80}\n"
      "output: {every: 40, history_every: 10, fields: [damage, displacement, velocity],\n"
      "         probes: [{name: under, position: [9 mm, 3 mm, 3.75 mm], field: displacement},\n"
      "                  {name: far, position: [1 mm, 1 mm, 3.75 mm], field: velocity},\n"
      "                  {name: middle, position: [6 mm, 3 mm, 2 mm], field: velocity}]}\n");
  const std::string base = process_temp_dir() + "/probes_indenter";
  ASSERT_EQ(solve(file, base + "_np1_t1", 1, 1).exit_code, 0);
  // The columns hold something to compare: the indenter pushes, the probes move.
  EXPECT_GT(last_history_value(base + "_np1_t1", "indenter_force_z_N"), 0.1);
  EXPECT_NE(last_history_value(base + "_np1_t1", "indenter_force_x_N"), 0.0);
  EXPECT_LT(last_history_value(base + "_np1_t1", "probe_under_uz"), 0.0);
  EXPECT_NE(last_history_value(base + "_np1_t1", "probe_far_vx"), 0.0);
  for (const auto& [ranks, threads] : {std::pair{1, 2}, {3, 1}, {2, 2}}) {
    const std::string out = base + "_np" + std::to_string(ranks) + "_t" + std::to_string(threads);
    const Outcome o = solve(file, out, ranks, threads);
    ASSERT_EQ(o.exit_code, 0) << out << ": " << o.err;
    expect_one_process_files(base + "_np1_t1", out);
    if (ranks == 1) continue;
    const nlohmann::json s = summary(out);
    ASSERT_TRUE(s.contains("loop_whole_bytes_rank0")) << out;
    const double whole = s["loop_whole_bytes_rank0"].get<double>(), particles = s["particles"].get<double>();
#ifdef BRECCIA_PARALLEL_HDF5
    EXPECT_LT(whole, 8.0 * particles) << out << ": rank 0 still holds a whole array after its loop";
#else
    EXPECT_GE(whole, 24.0 * particles) << out << ": serial HDF5's staging (u at least) is gone";
#endif
  }
}

// A blow-up's message names its particle as one process's does (MpiBackend::instability): the
// fastest one (the first of the largest speeds over the ranks) when the energy grows beyond
// 10x what was supplied (checked every 5 steps), the non-finite one (measure's) when it is
// first checked after the overflow (step 1000). With the radial velocity about the far corner
// these are internal particles 703 and 1535 of 1536 (found by matching a one-step run's
// checkpoint rows, internal order, to its results rows, file order): ranks 1 and 2 of 3 own
// them, so their owners send rank 0 the file index and position.
TEST(Distributed, AnInstabilityIsNamedAsOneProcessNamesIt) {
  for (const auto& [every, expected] : {std::pair{5, "fastest particle"}, {1000, "non-finite"}}) {
    const std::string name = "mpi_unstable_" + std::to_string(every);
    const std::string file = write_case(name,
        "specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.008, 0.006, 0.004], spacing: 0.5 mm}}\n"
        "model: {type: pmb, fracture: false, horizon_factor: 3.015}\n"
        "materials: [{name: m, density: 1000, youngs_modulus: 1 GPa, poisson_ratio: 0.25}]\n"
        "initial: [{type: radial_velocity, center: [0.008, 0.006, 0.004], strain_rate: 10}]\n"
        "time: {steps: 1000, dt: 1.3e-6, check_stability: false}\n"  // 1.4x the stable step (9.15e-7 s)
        "output: {every: 100000, history_every: " + std::to_string(every) + "}\n");
    const std::string base = process_temp_dir() + "/" + name;
    const Outcome one = solve(file, base + "_np1", 1, 1), three = solve(file, base + "_np3", 3, 1);
    EXPECT_EQ(one.exit_code, 3) << one.err;
    EXPECT_EQ(three.exit_code, 3) << three.err;
    const nlohmann::json a = summary(base + "_np1"), b = summary(base + "_np3");
    EXPECT_EQ(a["status"], "unstable");
    EXPECT_EQ(b["status"], "unstable");
    EXPECT_NE(a["message"].get<std::string>().find(expected), std::string::npos) << a["message"];
    EXPECT_EQ(a["message"], b["message"]);
  }
}

// The processes whose command line runs breccia-solve with `-o out` (a run's ranks), by /proc.
std::vector<pid_t> solver_processes_writing(const std::string& out) {
  std::vector<pid_t> pids;
  for (const auto& entry : std::filesystem::directory_iterator("/proc")) {
    const std::string name = entry.path().filename();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream in(entry.path() / "cmdline");
    std::vector<std::string> args;
    for (std::string a; std::getline(in, a, '\0');) args.push_back(a);
    const bool solver = !args.empty() && args[0] == executable("BRECCIA_SOLVE_EXE", BRECCIA_SOLVE_EXE);
    for (size_t k = 1; solver && k + 1 < args.size(); ++k)
      if (args[k] == "-o" && args[k + 1] == out) pids.push_back(static_cast<pid_t>(std::stol(name)));
  }
  return pids;
}

// Ctrl-C on 3 ranks (every rank interrupted, as a terminal's SIGINT reaches the job): the
// interrupted path (the state to the host, a history line, an output group, the checkpoint
// every rank writes) stops at the step one process reaches with --steps, with its checkpoint,
// and the run continued from it on 3 ranks ends as one process's straight run, dataset by
// dataset (differing: the checkpoint's energy attributes are sums over ranks, to rounding).
TEST(Distributed, AnInterruptedRunStopsWithOneProcessCheckpointAndContinues) {
  const std::string file = write_case("mpi_interrupt",
      "specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.012, 0.006, 0.004], spacing: 0.5 mm}}\n"
      "model: {type: lps, horizon_factor: 3.015}\n"
      "materials: [{name: m, density: 2000, youngs_modulus: 10 GPa, poisson_ratio: 0.25, fracture_energy: 5}]\n"
      "precracks: [{type: polygon, points: [[0.006, -0.001, -0.001], [0.006, 0.004, -0.001], [0.006, 0.004, 0.005], "
      "[0.006, -0.001, 0.005]]}]\n"
      "boundary:\n"
      "  - {type: velocity, set: xmin, value: [-5, 0, 0], components: [x]}\n"
      "  - {type: velocity, set: xmax, value: [5, 0, 0], components: [x]}\n"
      "time: {steps: 20000}\n"  // ends on its own (some minutes) should the interrupt not arrive
      "output: {every: 50, history_every: 10, fields: [damage, displacement, velocity]}\n");
  const std::string base = process_temp_dir() + "/interrupt", out = base + "_np3";
  std::filesystem::remove_all(out);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) _exit(solve(file, out, 3, 1).exit_code);
  // The loop runs (its rows of steps 0 and 10), then every rank is interrupted.
  for (int k = 0; k < 600; ++k) {
    const std::string history = read_text(out + "/history.csv");
    if (std::count(history.begin(), history.end(), '\n') >= 3) break;
    usleep(100000);
  }
  const std::vector<pid_t> ranks = solver_processes_writing(out);
  EXPECT_EQ(ranks.size(), 3u);
  for (const pid_t p : ranks) kill(p, SIGINT);
  int status = 0;
  waitpid(child, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  ASSERT_EQ(WEXITSTATUS(status), 130) << read_text(out + ".stderr");
  const nlohmann::json s = summary(out);
  EXPECT_EQ(s["status"], "interrupted");
  const long long stopped = s["steps"].get<long long>();
  ASSERT_GE(stopped, 10);  // the loop had written its step-10 row
  ASSERT_LT(stopped, 20000);
  ASSERT_EQ(solve(file, base + "_np1_stop", 1, 1, "--steps " + std::to_string(stopped)).exit_code, 0);
  EXPECT_EQ(differing(base + "_np1_stop/checkpoint.h5", out + "/checkpoint.h5"), std::vector<std::string>{})
      << "interrupted at step " << stopped;
  const Outcome second = solve(file, out, 3, 1, "--steps 60 --restart " + out + "/checkpoint.h5");
  ASSERT_EQ(second.exit_code, 0) << second.err;
  ASSERT_EQ(solve(file, base + "_np1", 1, 1, "--steps " + std::to_string(stopped + 60)).exit_code, 0);
  EXPECT_EQ(differing(base + "_np1/checkpoint.h5", out + "/checkpoint.h5"), std::vector<std::string>{});
  EXPECT_GT(summary(base + "_np1")["broken_bonds"].get<long long>(), s["broken_bonds"].get<long long>())
      << "no bond broke after the restart";
}

// Dynamic relaxation's one history line (MpiBackend::relax) takes its probe from the probed
// particle's owner too: the far corner of the pressed bar of
// DynamicRelaxationConvergesToTheSameStateOnThreeRanks (the last rank's, the end of the Morton
// order), one process's text on 3 ranks.
TEST(Distributed, DynamicRelaxationReadsItsProbeOnItsRank) {
  const std::string file = write_case("mpi_adr_probe",
      "specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.016, 0.008, 0.004], spacing: 1 mm}}\n"
      "model: {type: lps, horizon_factor: 3.015}\n"
      "materials: [{name: m, density: 2000, youngs_modulus: 10 GPa, poisson_ratio: 0.25}]\n"
      "precracks: [{type: polygon, points: [[0.008, -0.001, -0.001], [0.008, 0.004, -0.001], [0.008, 0.004, 0.005], [0.008, -0.001, 0.005]]}]\n"
      "loads: [{type: pressure, surface: xmax, history: {type: constant, value: -2 MPa}}]\n"
      "boundary: [{type: displacement, set: xmin, value: [0, 0, 0]}]\n"
      "time: {integrator: adr, adr_tolerance: 1e-10, adr_max_steps: 100000}\n"
      "output: {fields: [displacement], probes: [{name: tip, position: [16 mm, 8 mm, 4 mm], field: displacement}]}\n");
  const std::string base = process_temp_dir() + "/adr_probe";
  ASSERT_EQ(solve(file, base + "_np1", 1, 1).exit_code, 0);
  const Outcome three = solve(file, base + "_np3", 3, 1);
  ASSERT_EQ(three.exit_code, 0) << three.err;
  EXPECT_GT(last_history_value(base + "_np1", "probe_tip_uy"), 1e-5);  // the bar bends open at the crack
  expect_one_process_files(base + "_np1", base + "_np3");
}
