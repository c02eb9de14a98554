#pragma once
// Small helpers for solver tests: write a case file, build a system from it.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>

#include <unistd.h>

#include "breccia/common/particle_file.hpp"
#include "breccia/solver/case_config.hpp"
#include "breccia/solver/outputs.hpp"
#include "breccia/solver/pd_system.hpp"
#include "breccia/solver/run.hpp"

namespace breccia::solver::testing {

// A scratch folder of this test process. CTest runs every test case as its own process, in
// parallel (-j), and the cases of one parametrized suite write files of the same name:
// sharing ::testing::TempDir() made them overwrite each other's inputs.
// The folder is removed when the process exits (tens of MB per process: a whole test run
// left gigabytes behind in the temporary folder); set BRECCIA_KEEP_TEST_FILES to keep it
// for a look at a failing test's files.
class ProcessTempDir {
 public:
  ProcessTempDir() : owner_(::getpid()), path_(::testing::TempDir() + "/breccia_test_" + std::to_string(owner_)) {
    std::filesystem::create_directories(path_);
  }
  ~ProcessTempDir() {
    // A death test's forked child that exits runs this destructor too: only the process that
    // made the folder removes it.
    if (::getpid() != owner_ || std::getenv("BRECCIA_KEEP_TEST_FILES") != nullptr) return;
    std::error_code ignored;  // a destructor at exit must not throw
    std::filesystem::remove_all(path_, ignored);
  }
  ProcessTempDir(const ProcessTempDir&) = delete;
  ProcessTempDir& operator=(const ProcessTempDir&) = delete;
  const std::string& path() const { return path_; }

 private:
  pid_t owner_;
  std::string path_;
};

inline const std::string& process_temp_dir() {
  static const ProcessTempDir dir;
  return dir.path();
}

inline std::string write_case(const std::string& name, const std::string& yaml) {
  const std::string path = process_temp_dir() + "/" + name + ".yaml";
  std::ofstream(path) << yaml;
  return path;
}

#if defined(BRECCIA_MESH_EXE) && defined(BRECCIA_PLACE_EXE)
// A specimen meshed by breccia-mesh and placed by breccia-place in this process's scratch
// folder `name`: the path of its particles.h5, or empty if a stage failed.
inline std::string mesh_and_place(const std::string& name, const std::string& specimen_yaml,
                                  const std::string& place_options = "") {
  const std::string dir = process_temp_dir() + "/" + name;
  std::filesystem::create_directories(dir);
  std::ofstream(dir + "/specimen.yaml") << specimen_yaml;
  const std::string cmd = std::string(BRECCIA_MESH_EXE) + " " + dir + "/specimen.yaml -o " + dir +
                          "/specimen.msh --quiet > /dev/null 2>&1 && " + BRECCIA_PLACE_EXE + " " + dir +
                          "/specimen.msh -o " + dir + "/particles.h5 " + place_options + " > /dev/null 2>&1";
  if (std::system(cmd.c_str()) != 0) return std::string();
  return dir + "/particles.h5";
}

// The gas tests' specimen (test_gas.cpp, test_distributed.cpp): a disc of radius 40 mm with a
// 5 mm charge hole, 10 mm thick (plane strain), meshed at 2 mm refined to 0.6 mm near the
// hole: 4,327 particles. Meshed once per test process; empty if a stage failed.
inline std::string charge_hole_disc() {
  static const std::string path = mesh_and_place(
      "charge_hole_disc",
      "dimension: 2\nthickness: 10 mm\n"
      "body: {shape: disc, name: rock, radius: 40 mm}\n"
      "holes: [{name: charge_hole, centre: [0, 0], radius: 5 mm}]\n"
      "mesh: {size: 2 mm, refine: [{near: charge_hole, size: 0.6 mm, distance_min: 1 mm, distance_max: 15 mm}]}\n",
      "--thickness 10mm");
  return path;
}
#endif

// A 2D square lattice of nx x ny particles of spacing h (origin at `x0`, `y0`), thickness t,
// material 0 ("m"): the particle model tests write as particles.h5 when a lattice spec
// cannot say what they need (several materials, sets).
inline breccia::ParticleModel square_lattice_model(int nx, int ny, double h, double thickness, double x0 = 0.0,
                                                   double y0 = 0.0) {
  breccia::ParticleModel m;
  m.dimension = 2;
  m.thickness_m = thickness;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      m.position_m.insert(m.position_m.end(), {x0 + (i + 0.5) * h, y0 + (j + 0.5) * h, 0.0});
      m.volume_m3.push_back(h * h * thickness);
      m.spacing_m.push_back(h);
      m.material_id.push_back(0);
    }
  m.material_names = {"m"};
  return m;
}

inline PdSystem system_from_yaml(const std::string& name, const std::string& yaml) {
  return setup_system(parse_case_file(write_case(name, yaml)));
}

// Time at which the x-displacement of particle p first reaches `level` (stepping s), or -1
// if it does not within max_steps.
inline double arrival_time(PdSystem& s, int64_t p, double level, long long max_steps) {
  for (long long k = 0; k < max_steps; ++k) {
    const double before = s.u[3 * p];
    cpu_step(s);
    if (s.u[3 * p] >= level) {  // linear interpolation inside the step
      const double f = (level - before) / (s.u[3 * p] - before);
      return s.time - s.dt + f * s.dt;
    }
  }
  return -1;
}

// A glass plate with a Weibull strength scatter and a pre-crack halfway in, pulled apart
// by tractions: bonds break within a few hundred steps. The restart and precision tests
// both run it; they append their own `time:` and `output:` lines.
inline const std::string kPrecrackedGlassPlateDeck = R"(
specimen: {lattice: {dimension: 2, box: [0, 0, 0.02, 0.01], spacing: 0.5 mm, thickness: 1 mm}}
model: {type: pmb, planar: plane_stress, horizon_factor: 3.015}
materials: [{name: glass, density: 2440, youngs_modulus: 72 GPa, poisson_ratio: 0.3333333333333333, fracture_energy: 3.8, weibull: {modulus: 5, seed: 3}}]
precracks: [{type: segment, from: [0, 0.005], to: [0.01, 0.005]}]
loads: [{type: traction, surface: ymax, value: [0, 20 MPa, 0]}, {type: traction, surface: ymin, value: [0, -20 MPa, 0]}]
)";

// A fixed pseudo-random field, the same on any platform: splitmix64, mapped to [-0.5, 0.5).
// The tests that compare two force paths bit for bit displace every particle by it.
struct SplitMixUniform {
  uint64_t z;
  double operator()() {
    z += 0x9E3779B97F4A7C15ull;
    uint64_t x = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return double((x ^ (x >> 31)) >> 11) / 9007199254740992.0 - 0.5;
  }
};

// Internal index of the particle nearest to a point.
inline int64_t nearest(const PdSystem& s, double x, double y, double z) {
  int64_t best = 0;
  double bd = 1e300;
  for (size_t i = 0; i < s.n; ++i) {
    const double d = std::pow(s.x0[3 * i] - x, 2) + std::pow(s.x0[3 * i + 1] - y, 2) + std::pow(s.x0[3 * i + 2] - z, 2);
    if (d < bd) {
      bd = d;
      best = static_cast<int64_t>(i);
    }
  }
  return best;
}

// Impose u = eps . x on every particle (eps row-major 3x3).
inline void impose_affine(PdSystem& s, const double eps[9]) {
  for (size_t i = 0; i < s.n; ++i)
    for (int a = 0; a < 3; ++a) {
      double v = 0;
      for (int b = 0; b < 3; ++b) v += eps[3 * a + b] * s.x0[3 * i + b];
      s.u[3 * i + a] = v;
    }
}

// Runs `config` straight through, and again stopped after `first_steps` and continued from
// its checkpoint; returns both final systems (the callers compare them bit for bit).
struct SplitRuns {
  PdSystem straight, restarted;
};
inline SplitRuns straight_and_restarted(const CaseConfig& config, const std::string& name, long long first_steps) {
  RunOptions o;
  o.progress = false;
  SplitRuns r{setup_system(config), setup_system(config)};
  o.out_dir = process_temp_dir() + "/" + name + "_straight";
  run_system(r.straight, o);
  PdSystem first = setup_system(config);
  o.out_dir = process_temp_dir() + "/" + name + "_split";
  o.steps = first_steps;
  run_system(first, o);
  read_checkpoint(r.restarted, o.out_dir + "/checkpoint.h5");
  o.restart_file = o.out_dir + "/checkpoint.h5";
  o.steps = r.straight.step - first_steps;
  run_system(r.restarted, o);
  return r;
}

// What the callers of straight_and_restarted compare first: the same step, displacements and
// velocities bit for bit, and the same bond states (each adds its model's own state).
inline void expect_same_motion(const PdSystem& second, const PdSystem& straight) {
  ASSERT_EQ(second.step, straight.step);
  EXPECT_EQ(0, std::memcmp(second.u.data(), straight.u.data(), straight.u.size() * sizeof(double)));
  EXPECT_EQ(0, std::memcmp(second.v.data(), straight.v.data(), straight.v.size() * sizeof(double)));
  EXPECT_EQ(second.state, straight.state);
}

}  // namespace breccia::solver::testing
