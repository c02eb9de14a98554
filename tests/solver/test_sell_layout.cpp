// The SELL-C-sigma bond layout (sell_layout.hpp) and the fast passes over it (sell_kernels.hpp),
// driven on the host through step.hpp's pd_step as the CUDA launcher drives them (one call per
// slice lane): the state must be the CSR passes' bit for bit, since each lane walks its
// particle's entries in the CSR row's order with the same per-entry functions.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <numeric>
#include <stdexcept>

#include <set>
#include <string>

#include "breccia/solver/exec_openmp.hpp"
#include "breccia/solver/sell_host.hpp"
#include "breccia/solver/sell_layout.hpp"
#include "breccia/solver/step.hpp"
#include "helpers.hpp"
#include "measures.hpp"

using namespace breccia::solver;
using namespace breccia::solver::testing;

namespace {

std::vector<int64_t> offsets_of(const std::vector<int64_t>& lengths) {
  std::vector<int64_t> o(lengths.size() + 1, 0);
  for (size_t i = 0; i < lengths.size(); ++i) o[i + 1] = o[i] + lengths[i];
  return o;
}

// The structural properties every layout must have, whatever its rows.
void expect_valid_layout(const std::vector<int64_t>& offsets, const SellLayout& s) {
  const int64_t n = static_cast<int64_t>(offsets.size()) - 1, nnz = offsets.back();
  ASSERT_EQ(s.slices, (n + s.chunk - 1) / s.chunk);
  ASSERT_EQ(static_cast<int64_t>(s.particle.size()), s.lanes());
  ASSERT_EQ(static_cast<int64_t>(s.csr_entry.size()), s.padded_entries());
  // Every particle has exactly one lane, the lanes after the last are empty.
  std::vector<int> seen(static_cast<size_t>(n), 0);
  for (int64_t l = 0; l < s.lanes(); ++l) {
    if (l < n) {
      ASSERT_GE(s.particle[l], 0);
      ++seen[s.particle[l]];
      EXPECT_EQ(s.row_length[l], offsets[s.particle[l] + 1] - offsets[s.particle[l]]);
    } else {
      EXPECT_EQ(s.particle[l], -1);
      EXPECT_EQ(s.row_length[l], 0);
    }
  }
  for (int64_t i = 0; i < n; ++i) EXPECT_EQ(seen[i], 1) << "particle " << i;
  // Each particle's entries in its row's order; every CSR entry exactly once; the rest padding.
  const SellView v = s.view(nullptr);
  std::vector<int> used(static_cast<size_t>(nnz), 0);
  int64_t pads = 0;
  for (int64_t l = 0; l < s.lanes(); ++l) {
    const int64_t slice = l / s.chunk;
    int64_t width = 0;
    for (int64_t m = slice * s.chunk; m < (slice + 1) * s.chunk; ++m) width = std::max<int64_t>(width, s.row_length[m]);
    EXPECT_EQ(s.width(slice), width) << "a slice is as wide as its longest row";
    for (int64_t k = 0; k < s.width(slice); ++k) {
      const int64_t e = v.entry(l, k);
      ASSERT_GE(e, s.slice_offset[slice]);
      ASSERT_LT(e, s.slice_offset[slice + 1]);
      if (k < s.row_length[l]) {
        ASSERT_EQ(s.csr_entry[e], offsets[s.particle[l]] + k) << "lane " << l << " entry " << k;
        ++used[s.csr_entry[e]];
      } else {
        EXPECT_EQ(s.csr_entry[e], -1) << "padding is marked";
        ++pads;
      }
    }
  }
  for (int64_t k = 0; k < nnz; ++k) EXPECT_EQ(used[k], 1) << "CSR entry " << k;
  EXPECT_EQ(pads + nnz, s.padded_entries());
}

}  // namespace

TEST(SellLayout, EveryEntryOnceInRowOrderWithMarkedPadding) {
  // Rows of irregular length (0 to 12), 37 particles: the last slice of 8 holds 5.
  std::vector<int64_t> lengths(37);
  for (size_t i = 0; i < lengths.size(); ++i) lengths[i] = static_cast<int64_t>((i * 7 + 3) % 13);
  const std::vector<int64_t> offsets = offsets_of(lengths);
  for (int sigma : {1, 8, 16, 64}) {
    const SellLayout s = build_sell_layout(offsets, 8, sigma);
    expect_valid_layout(offsets, s);
    EXPECT_EQ(s.slices, 5);
    EXPECT_GE(s.particle[36], 0);
    for (int l = 37; l < 40; ++l) EXPECT_EQ(s.particle[l], -1) << "short last slice";
  }
}

TEST(SellLayout, SortsEachSigmaWindowByRowLengthKeepingTiesInIndexOrder) {
  std::vector<int64_t> lengths(37);
  for (size_t i = 0; i < lengths.size(); ++i) lengths[i] = static_cast<int64_t>((i * 7 + 3) % 5);
  const std::vector<int64_t> offsets = offsets_of(lengths);
  const SellLayout s = build_sell_layout(offsets, 4, 16);
  for (int64_t w = 0; w < 37; w += 16) {
    const int64_t end = std::min<int64_t>(37, w + 16);
    std::vector<int32_t> members;
    for (int64_t l = w; l < end; ++l) {
      members.push_back(s.particle[l]);
      if (l > w) {
        const int64_t a = lengths[s.particle[l - 1]], b = lengths[s.particle[l]];
        EXPECT_GE(a, b) << "window " << w << " lane " << l << ": longest first";
        if (a == b) EXPECT_LT(s.particle[l - 1], s.particle[l]) << "ties in index order";
      }
    }
    std::sort(members.begin(), members.end());
    for (int64_t l = w; l < end; ++l) EXPECT_EQ(members[l - w], l) << "a window keeps its own particles";
  }
  // Sorting shrinks the padding of these rows (the unsorted slices each hold a long row).
  EXPECT_LT(s.padding_factor(), build_sell_layout(offsets, 4, 1).padding_factor());
  // sigma 1: the lanes in index order.
  const SellLayout plain = build_sell_layout(offsets, 4, 1);
  for (int64_t l = 0; l < 37; ++l) EXPECT_EQ(plain.particle[l], l);
}

TEST(SellLayout, EmptyRowsEmptyCaseAndBadArguments) {
  const std::vector<int64_t> offsets = offsets_of({0, 3, 0, 1, 0});  // the second slice: one empty row
  const SellLayout s = build_sell_layout(offsets, 4, 4);
  expect_valid_layout(offsets, s);
  EXPECT_EQ(s.slices, 2);
  EXPECT_EQ(s.width(1), 0);  // one particle without bonds
  EXPECT_EQ(s.padded_entries(), 3 * 4);
  const SellLayout none = build_sell_layout({0}, 32, 256);
  EXPECT_EQ(none.slices, 0);
  EXPECT_EQ(none.padded_entries(), 0);
  EXPECT_EQ(none.padding_factor(), 1.0);
  EXPECT_THROW(build_sell_layout(offsets, 0, 1), std::invalid_argument);
  EXPECT_THROW(build_sell_layout(offsets, 8, 12), std::invalid_argument);
  EXPECT_THROW(build_sell_layout({}, 8, 8), std::invalid_argument);
  EXPECT_THROW(build_sell_layout({0, 2, 1}, 8, 8), std::invalid_argument);
  try {
    build_sell_layout(offsets, 8, 12);
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("sigma 12"), std::string::npos) << e.what();
  }
}

TEST(SellLayout, GathersThePerEntryArraysAndPadsSafely) {
  const std::vector<int64_t> offsets = offsets_of({2, 0, 3});
  const SellLayout s = build_sell_layout(offsets, 2, 2);  // lanes: (0, 1) sorted to (0, 1); (2, -)
  const std::vector<int32_t> neighbor{1, 2, 0, 1, 0};
  const SellBondArrays<double> b =
      gather_sell_bonds<double>(s, neighbor, {1, 2, 3, 4, 5}, {6, 7, 8, 9, 10}, {.1f, .2f, .3f, .4f, .5f}, {3, 3, 3, 0, 3});
  const SellView v = s.view(nullptr);
  for (int64_t l = 0; l < s.lanes(); ++l)
    for (int64_t k = 0; k < s.width(l / 2); ++k) {
      const int64_t e = v.entry(l, k), c = s.csr_entry[e];
      if (c >= 0) {
        EXPECT_EQ(b.neighbor[e], neighbor[c]);
        EXPECT_EQ(b.xi_len[e], double(c + 1));
      } else {
        EXPECT_EQ(b.state[e], 0) << "padding is broken";
        EXPECT_EQ(b.k_own[e], 0.0);
        EXPECT_EQ(b.neighbor[e], s.particle[l] < 0 ? 0 : s.particle[l]);
      }
    }
  std::vector<uint8_t> back(5, 9);
  s.scatter(b.state, back);
  EXPECT_EQ(back, (std::vector<uint8_t>{3, 3, 3, 0, 3}));
}

namespace {

// The layout's arrays of a system (with variable horizons the dual halves too, as the CUDA
// launcher gathers them), and the step's arrays pointing at them.
SellBondArrays<double> gather_bonds(const SellLayout& layout, const PdSystem& s) {
  if (s.symmetric_halves) return gather_sell_bonds(layout, s.neighbor, s.xi_len, s.k_own, s.s0_own, s.state);
  return gather_sell_bonds(layout, s.neighbor, s.xi_len, s.k_own, s.s0_own, s.state, s.k_dual_halves(),
                           s.s0_dual_halves(), s.vol_own, s.own_count);
}
struct HostSell {
  SellLayout layout;
  SellBondArrays<double> bonds;
  HostSell(const PdSystem& s, int chunk, int sigma)
      : layout(build_sell_layout(s.offsets, chunk, sigma)), bonds(gather_bonds(layout, s)) {}
  void attach(PdSystem& s, StepArrays<double>& a) {
    a.sell = layout.view(s.state.data());
    a.sell_entries = {bonds.neighbor.data(), bonds.xi_len.data(), bonds.k_own.data(), bonds.s0_own.data(),
                      bonds.state.data(),    bonds.k_dual.empty() ? nullptr : bonds.k_dual.data(),
                      bonds.s0_dual.empty() ? nullptr : bonds.s0_dual.data(),
                      bonds.vol_own.empty() ? nullptr : bonds.vol_own.data(),
                      bonds.own_count.empty() ? nullptr : bonds.own_count.data()};
  }
};

// The OpenMP execution space, recording the names of the loops it ran: which passes a step
// took (the layout's, or the CSR's and the state refresh).
class RecordingExec : public OpenMpExec {
public:
  explicit RecordingExec(PdSystem& sys, std::set<std::string>& launched) : OpenMpExec(sys), launched_(launched) {}
  template <class F>
  void for_each(int64_t n, const F& f, const char* name) const {
    launched_.insert(name);
    OpenMpExec::for_each(n, f, name);
  }

private:
  std::set<std::string>& launched_;
};

// 2D LPS with fracture rescales each complete family's s0 (setup.cpp), so its halves differ
// and it never takes the fast paths: LPS is checked on a 3D block, pulled until bonds break.
std::string block3d() {
  return "specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.006, 0.004, 0.002], spacing: 0.5 mm}}\n"
         "model: {type: lps, horizon_factor: 3.015}\n"
         "materials: [{name: glass, density: 2440, youngs_modulus: 72 GPa, poisson_ratio: 0.25, fracture_energy: 3.8, "
         "weibull: {modulus: 5, seed: 3}}]\n"
         "loads:\n"
         "  - {type: traction, surface: ymax, value: [0, 120 MPa, 0], history: {type: ramp, value: 1, ramp_time: 10 us}}\n"
         "boundary:\n"
         "  - {type: fixed, set: ymin}\n"
         "time: {steps: 1}\n";
}

std::string plate_2d(const char* model) {
  return std::string("specimen: {lattice: {dimension: 2, box: [0, 0, 0.02, 0.01], spacing: 0.5 mm, thickness: 1 mm}}\n") +
         "model: {type: " + model + ", planar: plane_strain, horizon_factor: 3.015}\n"
         "materials: [{name: glass, density: 2440, youngs_modulus: 72 GPa, poisson_ratio: 0.25, fracture_energy: 3.8, "
         "weibull: {modulus: 5, seed: 3}}]\n"
         "precracks: [{type: segment, from: [0, 0.005], to: [0.008, 0.005]}]\n"
         "loads:\n"
         "  - {type: traction, surface: ymax, value: [0, 12 MPa, 0], history: {type: ramp, value: 1, ramp_time: 20 us}}\n"
         "boundary:\n"
         "  - {type: fixed, set: ymin}\n"
         "time: {steps: 1}\n";
}

std::string plate(const char* model) {
  if (std::string(model) == "lps") return block3d();
  return plate_2d(model);
}

// The dual-horizon cases. 2D LPS with fracture: each complete family's s0 is rescaled
// (setup.cpp), so the halves of an entry differ and force_kernel takes the general loop.
std::string lps_plate_2d() { return plate_2d("lps"); }
// A graded strip (spacing 0.5 mm, then 1 mm beyond the middle) with variable horizons, its ends
// pulled apart: the dual horizon proper (own and dual halves of different horizons).
std::string graded_pmb_strip(const std::string& extra_model_keys) {
  const std::string file = breccia::atlas::write_graded_strip(process_temp_dir() + "/sell_graded_strip.h5", 0.02,
                                                              0.01, 0.5e-3, 2.0);
  return "specimen: {particles: " + file + "}\n"
         "model: {type: pmb, planar: plane_strain, horizon_factor: 3.015, variable_horizon: true" + extra_model_keys +
         "}\n"
         "materials: [{name: rock, density: 2600, youngs_modulus: 50 GPa, poisson_ratio: 0.25, fracture_energy: 2, "
         "weibull: {modulus: 3, seed: 5}}]\n"
         "sets: [{name: left, box: [-1, -1, 0.0015, 1]}, {name: right, box: [0.0185, -1, 1, 1]}]\n"
         "boundary:\n"
         "  - {type: velocity, set: left, value: [-4, 0, 0], components: [x]}\n"
         "  - {type: velocity, set: right, value: [4, 0, 0], components: [x]}\n"
         "time: {steps: 1}\n";
}

// Steps a case on the CSR (cpu_step) and through the layout (pd_step with the SELL arrays),
// diagnostics on every 10th step only (the run loop's pattern: the layout's passes in between;
// on those steps with one horizon the CSR's diagnostic pass and the layout's state refresh,
// with variable horizons the layout's diagnostic pass), and compares.
// `force_kernel`: the layout's force pass the steps between must launch (and never the CSR's).
// `general`: the case's halves are declared different (symmetric_halves false), which makes
// both sides take the general (dual-horizon) loop on a one-horizon case, as the CUDA tests do.
void run_sell_against_csr(const std::string& name, const std::string& deck, int chunk, int sigma, int steps,
                          const std::string& force_kernel, bool general = false) {
  PdSystem cpu = system_from_yaml("sell_cpu_" + name, deck);
  PdSystem sell = system_from_yaml("sell_lanes_" + name, deck);
  if (general) cpu.symmetric_halves = sell.symmetric_halves = false;
  const bool dual = force_kernel == "sell_dual_horizon_force_kernel";
  ASSERT_EQ(cpu.symmetric_halves, !dual) << name << ": the case must take the " << force_kernel << "'s path";
  HostSell h(sell, chunk, sigma);
  long long broken_in_sell_passes = 0;
  for (int k = 0; k < steps; ++k) {
    const bool diagnostics = k % 10 == 9 || k == steps - 1;
    cpu.diagnostics = sell.diagnostics = diagnostics;
    cpu_step(cpu);
    const long long before = measure(sell).broken_half_bonds;
    std::set<std::string> launched;
    RecordingExec exec(sell, launched);
    StepArrays<double> a = cpu_step_arrays(sell);
    h.attach(sell, a);
    pd_step(exec, a, sell);
    if (!diagnostics) {
      broken_in_sell_passes += measure(sell).broken_half_bonds - before;
      ASSERT_EQ(launched.count(force_kernel), 1u) << name << " step " << k;
      ASSERT_EQ(launched.count("force_kernel"), 0u) << name << " step " << k << ": the CSR's pass ran";
    } else if (dual) {  // one pass, no refresh
      broken_in_sell_passes += measure(sell).broken_half_bonds - before;
      ASSERT_EQ(launched.count("sell_dual_horizon_diagnostics_kernel"), 1u) << name << " step " << k;
      ASSERT_EQ(launched.count("force_kernel") + launched.count("sell_state_from_csr"), 0u) << name << " step " << k;
    } else {
      ASSERT_EQ(launched.count("sell_state_from_csr"), 1u) << name << " step " << k;
    }
  }
  const Energies e = measure(cpu);
  const std::string& model = name;
  ASSERT_GT(e.broken_half_bonds, 0) << model << ": the case should break bonds";
  EXPECT_GT(broken_in_sell_passes, 0) << model << ": bonds should break in the layout's passes";
  EXPECT_EQ(0, std::memcmp(cpu.u.data(), sell.u.data(), cpu.u.size() * sizeof(double))) << model;
  EXPECT_EQ(0, std::memcmp(cpu.v.data(), sell.v.data(), cpu.v.size() * sizeof(double))) << model;
  EXPECT_EQ(0, std::memcmp(cpu.force.data(), sell.force.data(), cpu.force.size() * sizeof(double))) << model;
  EXPECT_EQ(0, std::memcmp(cpu.damage.data(), sell.damage.data(), cpu.damage.size() * sizeof(double))) << model;
  EXPECT_EQ(0, std::memcmp(cpu.energy_density.data(), sell.energy_density.data(), cpu.n * sizeof(double))) << model;
  EXPECT_EQ(cpu.state, sell.state) << model;
  std::vector<uint8_t> from_layout(sell.state.size(), 9);
  h.layout.scatter(h.bonds.state, from_layout);
  EXPECT_EQ(sell.state, from_layout) << model << ": the layout's state and the CSR's agree";
  EXPECT_EQ(cpu.dissipated_energy, sell.dissipated_energy) << model;  // same reduction, same values
  EXPECT_EQ(cpu.external_work, sell.external_work) << model;
  std::printf("[ sell %s C=%d sigma=%d ] %lld broken half-bonds, %lld in the layout's passes, padding %.4f\n",
              model.c_str(), chunk, sigma, e.broken_half_bonds, broken_in_sell_passes, h.layout.padding_factor());
}

}  // namespace

TEST(SellKernels, PmbFastPassOverTheLayoutReproducesTheCsrStepBitForBit) {
  run_sell_against_csr("pmb", plate("pmb"), 32, 256, 400, "sell_pmb_force_kernel");
}

TEST(SellKernels, LpsFastPassesOverTheLayoutReproduceTheCsrStepBitForBit) {
  run_sell_against_csr("lps", plate("lps"), 32, 256, 400, "sell_lps_force_kernel");
}

TEST(SellKernels, SmallSlicesAndNoSortingReproduceTheCsrStepBitForBit) {
  run_sell_against_csr("pmb", plate("pmb"), 8, 1, 250, "sell_pmb_force_kernel");
}

// The dual-horizon pass over the layout (sell_general_force_lane: the CSR's general loop over a
// lane's entries), half-bonds breaking one at a time and copied to the CSR's state.
TEST(SellKernels, DualHorizonPassOverTheLayoutReproducesTheCsrStepBitForBit) {
  run_sell_against_csr("lps_2d_dual", lps_plate_2d(), 32, 256, 400, "sell_dual_horizon_force_kernel");
  run_sell_against_csr("pmb_graded_dual", graded_pmb_strip(""), 32, 256, 300, "sell_dual_horizon_force_kernel");
  // Small slices without sorting: rows of unequal length side by side (the graded strip's).
  run_sell_against_csr("pmb_graded_dual_c8", graded_pmb_strip(""), 8, 1, 200, "sell_dual_horizon_force_kernel");
}

// The general loop's other per-particle state on the layout: the compressive enhancement's
// s_min (read at both ends, written by the lane's particle) and the after-force break order.
TEST(SellKernels, DualHorizonPassWithLammpsRulesReproducesTheCsrStepBitForBit) {
  run_sell_against_csr("pmb_graded_lammps", graded_pmb_strip(", compressive_enhancement: 0.25, break_check: after_force"),
                       32, 256, 300, "sell_dual_horizon_force_kernel");
  run_sell_against_csr("pmb_plate_general", plate("pmb"), 32, 256, 400, "sell_dual_horizon_force_kernel", true);
}

// Where the layout carries no pass, the CSR's runs and the layout's state follows it: one
// constant horizon with the compressive enhancement (the symmetric loop's s_min), and
// softening bonds (per-entry damage).
TEST(SellKernels, PassesTheLayoutDoesNotCarryRunOnTheCsr) {
  for (const bool softening : {false, true}) {
    std::string deck = plate("pmb");
    if (softening) {
      const std::string at = "fracture_energy: 3.8,";
      deck.replace(deck.find(at), at.size(), at + " tensile_strength: 8 MPa,");
    } else {
      deck.replace(deck.find("horizon_factor: 3.015"), 21, "horizon_factor: 3.015, compressive_enhancement: 0.25");
    }
    PdSystem s = system_from_yaml(softening ? "sell_csr_softening" : "sell_csr_enhancement", deck);
    ASSERT_EQ(s.bond_damage.empty(), !softening);
    s.diagnostics = false;
    HostSell h(s, 32, 256);
    std::set<std::string> launched;
    RecordingExec exec(s, launched);
    StepArrays<double> a = cpu_step_arrays(s);
    h.attach(s, a);
    EXPECT_FALSE(sell_fast_pass(a.p));
    EXPECT_FALSE(sell_general_pass(a.p, a.sell_entries));
    pd_step(exec, a, s);
    EXPECT_EQ(launched.count("force_kernel"), 1u);
    EXPECT_EQ(launched.count("sell_state_from_csr"), 1u);
  }
}

// The checks above can fail: a layout whose rows are walked in reverse (the same entries, another
// summation order) gives other forces, in the fast pass and in the dual-horizon pass (the
// plate's halves declared different; the graded strip's own rows).
TEST(SellKernels, ReversedRowOrderChangesTheForces) {
  for (const int path : {0, 1, 2}) {
    PdSystem cpu = system_from_yaml(path == 2 ? "sell_rev_graded" : "sell_rev_cpu",
                                    path == 2 ? graded_pmb_strip("") : plate("pmb"));
    if (path == 1) cpu.symmetric_halves = false;
    for (size_t k = 0; k < cpu.u.size(); ++k) cpu.u[k] = 1e-6 * std::sin(0.37 * double(k)) * cpu.x0[k];
    PdSystem sell = cpu;
    cpu.diagnostics = sell.diagnostics = false;
    cpu_compute_forces(cpu);
    HostSell h(sell, 32, 256);
    for (int64_t l = 0; l < h.layout.lanes(); ++l) {  // reverse every lane's row
      const SellView v = h.layout.view(nullptr);
      for (int64_t q = 0, r = h.layout.row_length[l] - 1; q < r; ++q, --r) {
        const int64_t a = v.entry(l, q), b = v.entry(l, r);
        std::swap(h.layout.csr_entry[a], h.layout.csr_entry[b]);
      }
    }
    h.bonds = gather_bonds(h.layout, sell);
    std::set<std::string> launched;
    RecordingExec exec(sell, launched);
    StepArrays<double> a = cpu_step_arrays(sell);
    h.attach(sell, a);
    pd_force_pass(exec, a, true);
    EXPECT_EQ(launched.count(path == 0 ? "sell_pmb_force_kernel" : "sell_dual_horizon_force_kernel"), 1u) << path;
    int64_t differ = 0;
    for (size_t k = 0; k < cpu.force.size(); ++k) differ += cpu.force[k] != sell.force[k];
    EXPECT_GT(differ, 0) << "path " << path << ": a different summation order should change some force in its last bit";
    double scale = 0.0;
    for (double f : cpu.force) scale = std::max(scale, std::fabs(f));
    // Round-off only: the same terms in another order (1e-9 of the largest force: far above
    // the ~1e-15 relative of a 30-term reordering, far below a missing or doubled bond).
    for (size_t k = 0; k < cpu.force.size(); ++k) EXPECT_NEAR(cpu.force[k], sell.force[k], 1e-9 * scale) << path << " " << k;
  }
}

// The host's slice-wide form (sell_host.hpp: the lanes of a slice side by side) gives the lane
// form's results bit for bit, on a cracked plate stretched further so that many bonds break
// in the compared pass.
TEST(SellKernels, HostSliceFormMatchesTheLaneForm) {
  for (const char* model : {"pmb", "lps"}) {
    PdSystem lanes = system_from_yaml(std::string("sell_slice_") + model, plate(model));
    ASSERT_TRUE(lanes.symmetric_halves) << model;
    HostSell h(lanes, 32, 256);
    lanes.diagnostics = false;
    for (int k = 0; k < 300; ++k) {
      OpenMpExec exec(lanes);
      StepArrays<double> a = cpu_step_arrays(lanes);
      h.attach(lanes, a);
      pd_step(exec, a, lanes);
    }
    for (double& u : lanes.u) u *= 1.5;
    PdSystem slices = lanes;
    HostSell hs = h;
    const long long before = measure(lanes).broken_half_bonds;
    {
      OpenMpExec exec(lanes);
      StepArrays<double> a = cpu_step_arrays(lanes);
      h.attach(lanes, a);
      pd_force_pass(exec, a, false);
    }
    ASSERT_GT(measure(lanes).broken_half_bonds, before) << model << ": the compared pass should break bonds";
    {
      OpenMpExec exec(slices);
      StepArrays<double> a = cpu_step_arrays(slices);
      hs.attach(slices, a);
      for (size_t c = 0; c < slices.x.size(); ++c) slices.x[c] = slices.x0[c] + slices.u[c];  // CurrentPositions
      const PdView e = sell_entry_view(a.p, a.sell_entries);
      if (e.model == static_cast<int>(PdModel::LPS))
        for (int64_t lane = 0; lane < a.sell.lanes; ++lane) sell_lps_dilatation_lane(e, a.sell, lane);
      for (int64_t slice = 0; slice < hs.layout.slices; ++slice) sell_fast_force_slice_host<32>(e, a.sell, slice);
    }
    EXPECT_EQ(0, std::memcmp(lanes.force.data(), slices.force.data(), lanes.force.size() * sizeof(double))) << model;
    EXPECT_EQ(0, std::memcmp(lanes.dissipated.data(), slices.dissipated.data(), lanes.n * sizeof(double))) << model;
    EXPECT_EQ(lanes.state, slices.state) << model;
    EXPECT_EQ(h.bonds.state, hs.bonds.state) << model;
  }
}

TEST(SellLayout, CaseKeyModelCudaLayout) {
  const std::string deck = plate("pmb");
  EXPECT_FALSE(parse_case_file(write_case("sell_key_default", deck)).cuda_sell_layout) << "csr by default";
  std::string sell = deck;
  sell.replace(sell.find("horizon_factor: 3.015"), 21, "horizon_factor: 3.015, cuda_layout: sell");
  EXPECT_TRUE(parse_case_file(write_case("sell_key_sell", sell)).cuda_sell_layout);
  std::string bad = deck;
  bad.replace(bad.find("horizon_factor: 3.015"), 21, "horizon_factor: 3.015, cuda_layout: ell");
  try {
    parse_case_file(write_case("sell_key_bad", bad));
    ADD_FAILURE() << "an unknown layout should be refused";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("model.cuda_layout"), std::string::npos) << e.what();
  }
}
