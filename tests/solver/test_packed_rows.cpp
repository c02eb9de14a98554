// The host's packed bond rows (pd_kernels.hpp: pmb_packed_row, lps_packed_dilatation_row,
// lps_packed_row), which force_kernel and lps_dilatation_kernel run in double on the CPU,
// against the device's form of the same passes: one entry at a time in row order
// (ordered_fast_loop with the entry functions pmb_fast_entry, lps_fast_entry,
// lps_dilatation_entry). The forces, dilatations, bond states and released energy must agree
// bit for bit on a block whose displacement leaves most rows intact (the packed loops) and
// gives others a broken entry or an entry past its critical stretch (handed back to the
// two-stage loop, which selects and breaks).
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <random>
#include <vector>

#include "breccia/solver/pd_kernels.hpp"
#include "helpers.hpp"

using namespace breccia::solver;
using namespace breccia::solver::testing;

namespace {

std::string block(const char* model) {
  return std::string("specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.006, 0.004, 0.003], spacing: 0.5 mm}}\n") +
         "model: {type: " + model + ", horizon_factor: 3.015}\n"
         "materials: [{name: glass, density: 2440, youngs_modulus: 72 GPa, poisson_ratio: 0.25, fracture_energy: 3.8}]\n"
         "time: {steps: 1}\n";
}

// A uniform stretch below every critical one, a few particles pushed far enough that some of
// their bonds pass it, and a few entries broken.
void deform(PdSystem& s) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> noise(-1.0, 1.0);
  double s0_min = 1e300;
  for (float s0 : s.s0_own) s0_min = std::min(s0_min, double(s0));
  for (size_t k = 0; k < s.u.size(); ++k) s.u[k] = 0.2 * s0_min * s.x0[k] + 1e-3 * s0_min * 5e-4 * noise(rng);
  for (size_t i = 0; i < s.n; i += 61) s.u[3 * i] += 1.5 * s0_min * 5e-4;  // its nearest bonds pass s0
  for (size_t k = 0; k < s.state.size(); k += 997) s.state[k] = 0;
  s.x.resize(s.x0.size());
  for (size_t k = 0; k < s.x.size(); ++k) s.x[k] = s.x0[k] + s.u[k];
  s.diagnostics = false;
}

void expect_same(const PdSystem& a, const PdSystem& b, const char* what) {
  EXPECT_EQ(0, std::memcmp(a.force.data(), b.force.data(), a.force.size() * sizeof(double))) << what;
  EXPECT_EQ(0, std::memcmp(a.dissipated.data(), b.dissipated.data(), a.n * sizeof(double))) << what;
  EXPECT_EQ(a.state, b.state) << what;
}

// The one-entry fast loop's force pass over every row of q (LPS after its dilatation is stored):
// the order the packed rows must reproduce.
void one_entry_force_rows(const PdView& q) {
  const bool lps = q.model == static_cast<int>(PdModel::LPS);
  for (int64_t i = 0; i < q.n; ++i) {
    const BondOriginT<double> origin(q, i);
    const int64_t begin = q.offsets[i], count = q.offsets[i + 1] - begin;
    if (lps)
      ordered_fast_loop<double>(q, i, count, LpsFastPath<double>{origin, q.lps_a[i], q.lps_b[i]}, CsrRow{begin},
                                NoBreakHook{});
    else
      ordered_fast_loop<double>(q, i, count, PmbFastPath<double>{origin}, CsrRow{begin}, NoBreakHook{});
  }
}

void compare(const char* model) {
  PdSystem packed = system_from_yaml(std::string("packed_rows_") + model, block(model));
  ASSERT_TRUE(packed.symmetric_halves) << model << ": one constant horizon, the fast loops' case";
  deform(packed);
  PdSystem one_by_one = packed;
  one_by_one.x = packed.x;
  const std::vector<uint8_t> one_by_one_state_before = one_by_one.state;
  const PdView p = packed.view(), q = one_by_one.view();
  ASSERT_TRUE(p.x && !p.diagnostics && fast_bond_loop(p));
  const bool lps = p.model == static_cast<int>(PdModel::LPS);
  const int64_t n = p.n;
#if defined(BRECCIA_HOST_PACK)
  // Both kinds of rows occur: packed, and handed back (a broken entry, or one past s0).
  int64_t accepted = 0;
  {
    PdSystem scratch = packed;
    scratch.x = packed.x;
    const PdView t = scratch.view();
    for (int64_t i = 0; i < n; ++i) {
      double sum = 0.0;
      accepted += on_host_pack([&](auto pack) {
        using P = typename decltype(pack)::type;
        return lps ? lps_packed_dilatation_row<P>(t, i, BondOriginT<double>(t, i), sum)
                   : pmb_packed_row<P>(t, i, BondOriginT<double>(t, i));
      });
    }
  }
  EXPECT_GT(accepted, n / 2) << model;
  EXPECT_LT(accepted, n) << model;
#endif
  if (lps) {
    for (int64_t i = 0; i < n; ++i) lps_dilatation_kernel(p, i);
    for (int64_t i = 0; i < n; ++i) {
      const BondOriginT<double> origin(q, i);
      double sum = 0.0;
      for (int64_t k = q.offsets[i]; k < q.offsets[i + 1]; ++k) sum += lps_dilatation_entry(q, origin, k);
      lps_store_dilatation(q, i, sum);
    }
    EXPECT_EQ(0, std::memcmp(packed.dilatation.data(), one_by_one.dilatation.data(), n * sizeof(double))) << model;
    EXPECT_EQ(0, std::memcmp(packed.lps_a.data(), one_by_one.lps_a.data(), n * sizeof(double))) << model;
  }
  for (int64_t i = 0; i < n; ++i) force_kernel(p, i);
  one_entry_force_rows(q);
  expect_same(packed, one_by_one, model);
  if (!lps) {
    // PMB's order (RowForceSums): entry q of the row to partial sum q mod 4, in row order, the
    // four combined as (s0 + s1) + (s2 + s3); formed here from the entries' terms, the deformed
    // block's state before the pass (`reference`), and compared with the one-entry loop's forces.
    PdSystem reference = packed;
    reference.x = packed.x;
    reference.state = one_by_one_state_before;
    const PdView r = reference.view();
    for (int64_t i = 0; i < n; ++i) {
      const BondOriginT<double> origin(r, i);
      double sx[4] = {0.0, 0.0, 0.0, 0.0}, sy[4] = {0.0, 0.0, 0.0, 0.0}, sz[4] = {0.0, 0.0, 0.0, 0.0};
      for (int64_t k = r.offsets[i]; k < r.offsets[i + 1]; ++k) {
        double cx, cy, cz;
        pmb_fast_entry(r, origin, k, cx, cy, cz);
        const int64_t q = (k - r.offsets[i]) % 4;
        sx[q] += cx;
        sy[q] += cy;
        sz[q] += cz;
      }
      const double expected[3] = {(sx[0] + sx[1]) + (sx[2] + sx[3]), (sy[0] + sy[1]) + (sy[2] + sy[3]),
                                  (sz[0] + sz[1]) + (sz[2] + sz[3])};
      ASSERT_EQ(0, std::memcmp(expected, &one_by_one.force[3 * i], sizeof expected)) << "row " << i;
    }
  }
  int64_t broke = 0;
  for (size_t k = 0; k < packed.state.size(); k += 1) broke += packed.state[k] == 0 && k % 997 != 0;
  EXPECT_GT(broke, 0) << model << ": bonds past s0 should break in the pass";
}

#if defined(BRECCIA_HOST_PACK)
// `row` at the given width: 4 lanes through the AVX function the solver runs on a CPU with AVX
// (on_avx_pack), 2 lanes as on one without.
template <class Row>
bool at_width(int lanes, const Row& row) {
  if (lanes == 4) return on_avx_pack(row);
  return row(PackKind<PackD2>{});
}

// Each width's packed rows against the one-entry loop, row by row: the rows a width accepts
// must hold the one-entry loop's forces (and, for LPS, dilatation sums) bit for bit, and both
// widths must accept the same rows. The solver runs one width per CPU (on_host_pack), so
// without this a CPU with AVX would never check the 2-lane rows, nor one without the 4-lane.
void compare_widths(const char* model) {
  PdSystem base = system_from_yaml(std::string("packed_widths_") + model, block(model));
  deform(base);
  PdSystem reference = base;
  reference.x = base.x;
  const PdView q = reference.view();
  const bool lps = q.model == static_cast<int>(PdModel::LPS);
  const int64_t n = q.n;
  std::vector<double> theta_sum(n, 0.0);
  for (int64_t i = 0; i < n; ++i) {
    const BondOriginT<double> origin(q, i);
    for (int64_t k = q.offsets[i]; k < q.offsets[i + 1]; ++k)
      theta_sum[i] += lps ? lps_dilatation_entry(q, origin, k) : 0.0;
    if (lps) lps_store_dilatation(q, i, theta_sum[i]);
  }
  one_entry_force_rows(q);
  std::vector<uint8_t> accepted_at[2];
  for (int lanes : {2, 4}) {
    if (lanes == 4 && !host_runs_avx()) {
      std::printf("[ SKIPPED  ] %s: 4-lane rows, this CPU has no AVX\n", model);
      continue;
    }
    PdSystem s = base;
    s.x = base.x;
    if (lps) {  // the factors the force rows read: the reference's (its rows equal, checked below)
      s.dilatation = reference.dilatation;
      s.lps_a = reference.lps_a;
      s.lps_b = reference.lps_b;
    }
    const PdView t = s.view();
    std::vector<uint8_t>& accepted = accepted_at[lanes / 4];
    accepted.assign(n, 0);
    int64_t rows = 0;
    for (int64_t i = 0; i < n; ++i) {
      const BondOriginT<double> origin(t, i);
      double sum = 0.0;
      bool took;
      if (lps) {
        const bool summed = at_width(lanes, [&](auto pack) {
          return lps_packed_dilatation_row<typename decltype(pack)::type>(t, i, origin, sum);
        });
        if (summed) EXPECT_EQ(0, std::memcmp(&sum, &theta_sum[i], sizeof sum)) << model << " lanes " << lanes << " row " << i;
        took = at_width(lanes, [&](auto pack) {
          return lps_packed_row<typename decltype(pack)::type>(t, i, origin, t.lps_a[i], t.lps_b[i]);
        });
      } else {
        took = at_width(lanes, [&](auto pack) { return pmb_packed_row<typename decltype(pack)::type>(t, i, origin); });
      }
      accepted[i] = took;
      rows += took;
      if (took)
        EXPECT_EQ(0, std::memcmp(&s.force[3 * i], &reference.force[3 * i], 3 * sizeof(double)))
            << model << " lanes " << lanes << " row " << i;
    }
    EXPECT_GT(rows, n / 2) << model << " lanes " << lanes;
    EXPECT_LT(rows, n) << model << " lanes " << lanes;
  }
  if (!accepted_at[1].empty()) EXPECT_EQ(accepted_at[0], accepted_at[1]) << model;
}
#endif

}  // namespace

TEST(PackedRows, PmbRowsEqualTheOneEntryLoopBitForBit) { compare("pmb"); }

TEST(PackedRows, LpsRowsEqualTheOneEntryLoopsBitForBit) { compare("lps"); }

#if defined(BRECCIA_HOST_PACK)
TEST(PackedRows, PmbRowsOfBothWidthsEqualTheOneEntryLoop) { compare_widths("pmb"); }

TEST(PackedRows, LpsRowsOfBothWidthsEqualTheOneEntryLoops) { compare_widths("lps"); }
#endif

// The general loop's and the dilatation's skip of broken entries (last_of_zero_run): walking
// a row as those loops do visits exactly the entries with a nonzero state, in row order,
// whatever the runs of zeros (shorter than a word, whole words, a row's tail, a whole row).
TEST(PackedRows, ZeroRunSkipVisitsEveryLiveEntryOnceInRowOrder) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 2000; ++trial) {
    const int64_t begin = static_cast<int64_t>(rng() % 13);  // rows start anywhere in the array
    const int64_t count = static_cast<int64_t>(rng() % 70);
    std::vector<uint8_t> state(static_cast<size_t>(begin + count + 8), 0);
    const double live = (trial % 4) * 0.3;  // 0: a dead row; up to 0.9 live
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int64_t q = 0; q < count; ++q) state[begin + q] = u(rng) < live ? uint8_t(1 + rng() % 3) : uint8_t(0);
    std::vector<int64_t> expected, visited;
    for (int64_t q = 0; q < count; ++q)
      if (state[begin + q]) expected.push_back(q);
    const CsrRow at{begin};
    for (int64_t q = 0; q < count; ++q) {
      if (!state[at(q)]) {
        const int64_t last = last_of_zero_run(state.data(), at, q, count);
        ASSERT_GE(last, q);
        ASSERT_LT(last, count);
        for (int64_t r = q; r <= last; ++r) ASSERT_EQ(state[at(r)], 0) << "skipped a live entry";
        q = last;
        continue;
      }
      visited.push_back(q);
    }
    ASSERT_EQ(visited, expected) << "trial " << trial;
  }
}
