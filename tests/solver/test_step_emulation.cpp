// The step of step.hpp driven by an execution space that launches every loop in reverse
// order and sums in blocks, as a GPU's threads may run and its reductions do: the state it
// produces must equal the OpenMP backend's bit for bit (each index of a phase is
// independent of the others' order: no phase reads what another index of the same phase
// writes), and the energy sums must agree to round-off. This is what the CUDA backend's
// agreement rests on, checked here without a GPU.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstring>
#include <memory>
#include <omp.h>

#include "breccia/solver/exec_openmp.hpp"
#include "breccia/solver/step.hpp"
#include "helpers.hpp"
#include "reverse_block_exec.hpp"

using namespace breccia::solver;
using namespace breccia::solver::testing;

namespace {

void expect_same_state(const PdSystem& a, const PdSystem& b, bool energies_exact) {
  ASSERT_EQ(a.step, b.step);
  EXPECT_EQ(0, std::memcmp(a.u.data(), b.u.data(), a.u.size() * sizeof(double)));
  EXPECT_EQ(0, std::memcmp(a.v.data(), b.v.data(), a.v.size() * sizeof(double)));
  EXPECT_EQ(a.state, b.state);
  EXPECT_EQ(a.bond_damage, b.bond_damage);
  const double scale = std::max(std::fabs(a.external_work), 1e-30);
  EXPECT_NEAR(a.external_work, b.external_work, energies_exact ? 0.0 : 1e-12 * scale);
  EXPECT_NEAR(a.dissipated_energy, b.dissipated_energy, 1e-12 * std::max(a.dissipated_energy, 1e-30));
}

void run_both(const std::string& name, const std::string& deck, int steps) {
  PdSystem cpu = system_from_yaml(name + "_cpu", deck);
  PdSystem emulated = system_from_yaml(name + "_emulated", deck);
  for (int k = 0; k < steps; ++k) cpu_step(cpu);
  for (int k = 0; k < steps; ++k) {
    ReverseBlockExec exec(emulated);
    if (emulated.f32.active) {
      float32_upload(emulated);
      StepArrays<float> a = float32_step_arrays(emulated);
      pd_step(exec, a, emulated);
      float32_download(emulated);
    } else {
      StepArrays<double> a = cpu_step_arrays(emulated);
      pd_step(exec, a, emulated);
    }
  }
  ASSERT_GT(measure(cpu).broken_half_bonds, 0) << name << ": the case should break bonds";
  expect_same_state(cpu, emulated, false);
}

// A notched plate pulled by tractions, constrained on three sides by every boundary kind,
// with a body force: loads, constraints, breaking, in both models and precisions.
std::string plate(const char* model, const char* extra_model, const char* extra_material) {
  return std::string("specimen: {lattice: {dimension: 2, box: [0, 0, 0.02, 0.01], spacing: 0.5 mm, thickness: 1 mm}}\n") +
         "model: {type: " + model + ", planar: plane_strain, horizon_factor: 3.015" + extra_model + "}\n"
         "materials: [{name: glass, density: 2440, youngs_modulus: 72 GPa, poisson_ratio: 0.25, fracture_energy: 3.8" +
         extra_material + ", weibull: {modulus: 5, seed: 3}}]\n"
         "precracks: [{type: segment, from: [0, 0.005], to: [0.008, 0.005]}]\n"
         "loads:\n"
         "  - {type: traction, surface: ymax, value: [0, 12 MPa, 0], history: {type: ramp, value: 1, ramp_time: 20 us}}\n"
         "  - {type: body_force, value: [0, -1e5, 0]}\n"
         "boundary:\n"
         "  - {type: fixed, set: ymin}\n"
         "  - {type: velocity, set: xmin, value: [-0.2, 0, 0], components: [x], ramp_time: 1 us}\n"
         "  - {type: displacement, set: xmax, value: [1e-6, 0, 0], components: [x], ramp_time: 3 us}\n"
         "time: {steps: 1}\n";
}

// A load that counts how often each index is loaded. StepLoad kicks particle k / 3 at k % 3
// == 0 and the measure's loads write too (step.hpp: "load(i) runs exactly once per i"): a
// reduce that loaded an index twice (a second pass for a two-level sum, a thread's chunk run
// again) would kick a particle twice. The value is the index itself, so the sum also checks
// that every index was combined once.
struct CountingLoad {
  using Value = int64_t;
  std::atomic<int>* calls;
  static Value identity() { return 0; }
  static Value combine(Value a, Value b) { return a + b; }
  Value operator()(int64_t i) const {
    calls[i].fetch_add(1, std::memory_order_relaxed);
    return i;
  }
};

template <class Exec>
void expect_each_index_loaded_once(const Exec& exec, int64_t n, const std::string& what) {
  std::unique_ptr<std::atomic<int>[]> calls(new std::atomic<int>[static_cast<size_t>(n)]);
  for (int64_t i = 0; i < n; ++i) calls[i] = 0;
  int64_t total = -1;
  int finishes = 0;
  exec.reduce(n, CountingLoad{calls.get()}, [&](int64_t sum) {
    total = sum;
    ++finishes;
  }, "count");
  int64_t wrong = 0, first_wrong = -1;
  for (int64_t i = 0; i < n; ++i)
    if (calls[i] != 1 && wrong++ == 0) first_wrong = i;
  EXPECT_EQ(wrong, 0) << what << ", n = " << n << ": index " << first_wrong << " loaded "
                      << (first_wrong >= 0 ? calls[first_wrong].load() : 0) << " times";
  EXPECT_EQ(finishes, 1) << what << ", n = " << n;
  EXPECT_EQ(total, n * (n - 1) / 2) << what << ", n = " << n;  // every index combined once
}

}  // namespace

// The contract the fused end-of-step load (StepLoad) relies on: OpenMpExec::reduce (on 1 to
// 4 threads, n below, at and above the thread count and not a multiple of it) and the
// emulated device reduction (ReverseBlockExec: grid-stride blocks as the CUDA kernel loads)
// call the load exactly once per index.
TEST(StepEmulation, ReduceLoadsEachIndexExactlyOnce) {
  PdSystem s;
  const OpenMpExec cpu(s);
  const ReverseBlockExec emulated(s);
  const int threads_before = omp_get_max_threads();
  for (int threads : {1, 2, 3, 4}) {
    omp_set_num_threads(threads);
    for (int64_t n : {int64_t{0}, int64_t{1}, int64_t{3}, int64_t{1000}, int64_t{3 * 68921 + 1}})
      expect_each_index_loaded_once(cpu, n, "OpenMpExec on " + std::to_string(threads) + " threads");
  }
  omp_set_num_threads(threads_before);
  for (int64_t n : {int64_t{0}, int64_t{1}, int64_t{255}, int64_t{7 * 256}, int64_t{7 * 256 * 3 + 5}})
    expect_each_index_loaded_once(emulated, n, "ReverseBlockExec");
}

TEST(StepEmulation, PmbDoubleReproducesTheOpenMpStepBitForBit) { run_both("emu_pmb", plate("pmb", "", ""), 400); }

TEST(StepEmulation, LpsDoubleReproducesTheOpenMpStepBitForBit) { run_both("emu_lps", plate("lps", "", ""), 400); }

TEST(StepEmulation, Float32AndTheLammpsRulesReproduceTheOpenMpStepBitForBit) {
  run_both("emu_pmb_f32", plate("pmb", ", precision: float32", ""), 400);
  run_both("emu_lps_alpha", plate("lps", ", compressive_enhancement: 0.25, break_check: after_force", ""), 400);
}

TEST(StepEmulation, SofteningBondsReproduceTheOpenMpStepBitForBit) {
  run_both("emu_soft", plate("pmb", "", ", tensile_strength: 8 MPa"), 400);
}
