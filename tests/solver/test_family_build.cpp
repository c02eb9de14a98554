// The bond families built through an execution space (family_build.hpp: the kernels of
// family_kernels.hpp launched by exec.for_each, the CUDA backend's set-up path) equal
// build_families' (whose rows tests/common/test_cell_list.cpp checks against a brute-force
// pair test) offset for offset and partner for partner: launched on the OpenMP loop of
// the step (OpenMpExec) and in reverse order (ReverseBlockExec, as a GPU's threads may run;
// its atomics then hand the cells' slots out in the opposite order). Every kernel must
// therefore be independent of the order its indices run in; this is what the device path
// rests on, checked without a GPU.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <utility>
#include <vector>

#if defined(_OPENMP)
#include <omp.h>
#endif

#include "breccia/common/family_build.hpp"
#include "breccia/solver/exec_openmp.hpp"
#include "family_clouds.hpp"
#include "reverse_block_exec.hpp"

using namespace breccia;
using breccia::solver::OpenMpExec;
using breccia::solver::PdSystem;
using breccia::solver::testing::ReverseBlockExec;
using breccia::testing::Cloud;
using breccia::testing::graded;
using breccia::testing::lattice;

namespace {

template <class Exec>
Families through(const Exec& exec, const Cloud& c, int64_t row_begin = 0, int64_t row_end = -1) {
  FamilyHostMemory mem;
  return build_families_with(exec, mem, c.x, c.horizon, c.pad, row_begin, row_end);
}

void expect_same(const Families& got, const Families& want, const std::string& what) {
  EXPECT_EQ(got.offsets, want.offsets) << what;
  EXPECT_EQ(got.neighbors, want.neighbors) << what;
}

// The OpenMP loop and the reverse-order launch against build_families, on the whole and on rows.
void expect_every_space_agrees(const Cloud& c, const std::string& what) {
  PdSystem sys;
  const OpenMpExec openmp(sys);
  const ReverseBlockExec reverse(sys);
  const Families want = build_families(c.x, c.horizon, c.pad);
  expect_same(through(openmp, c), want, what + ", OpenMpExec");
  expect_same(through(reverse, c), want, what + ", ReverseBlockExec");
  const int64_t n = static_cast<int64_t>(c.horizon.size());
  // a distributed set-up's rows: the middle, the first and the last row, none
  for (const auto [b, e] : {std::pair<int64_t, int64_t>{n / 3, 2 * n / 3}, {0, 1}, {n - 1, n}, {n / 2, n / 2}}) {
    const Families part = build_families(c.x, c.horizon, c.pad, b, e);
    const std::string rows = ", rows " + std::to_string(b) + "-" + std::to_string(e);
    expect_same(through(openmp, c, b, e), part, what + rows + ", OpenMpExec");
    expect_same(through(reverse, c, b, e), part, what + rows + ", ReverseBlockExec");
  }
}

}  // namespace

TEST(FamilyBuild, UniformLatticeInAnyLaunchOrder) {
  const Cloud c = lattice(14, 1e-3);
  ASSERT_EQ(plan_families(c.x, c.horizon, c.pad, 0, -1).classes, 1);
  expect_every_space_agrees(c, "lattice 14^3");
  // a lattice row far from the faces has the full stencil: the nonzero integer offsets o with
  // |o| <= 3.015 + 0.866 spacings (the horizon and the pad), i.e. |o|^2 <= 15
  int stencil = 0;
  for (int a = -4; a <= 4; ++a)
    for (int b = -4; b <= 4; ++b)
      for (int d = -4; d <= 4; ++d) {
        const double r = std::sqrt(static_cast<double>(a * a + b * b + d * d));
        stencil += (a || b || d) && r * 1e-3 <= (3.015 + 0.5 * std::sqrt(3.0)) * 1e-3;
      }
  const Families f = build_families(c.x, c.horizon, c.pad);
  const int64_t middle = (7 * 14 + 7) * 14 + 7;
  EXPECT_EQ(f.offsets[middle + 1] - f.offsets[middle], stencil);
}

TEST(FamilyBuild, GradedCloudAcrossReachClassesInAnyLaunchOrder) {
  const Cloud c = graded(4000);
  double lo = c.horizon[0], hi = c.horizon[0];
  for (const double h : c.horizon) lo = std::min(lo, h), hi = std::max(hi, h);
  ASSERT_GT(hi / lo, 4.0);
  ASSERT_GE(plan_families(c.x, c.horizon, c.pad, 0, -1).classes, 3);
  expect_every_space_agrees(c, "graded cloud");
}

TEST(FamilyBuild, EmptyAndOneParticle) {
  PdSystem sys;
  const ReverseBlockExec reverse(sys);
  const Cloud none;
  const Families empty = through(reverse, none);
  EXPECT_EQ(empty.offsets, std::vector<int64_t>{0});
  EXPECT_TRUE(empty.neighbors.empty());
  expect_same(empty, build_families(none.x, none.horizon, none.pad), "no particles");
  const Cloud one{{0.1, 0.2, 0.3}, {0.05}, {0.01}};
  const Families single = through(reverse, one);
  EXPECT_EQ(single.offsets, (std::vector<int64_t>{0, 0}));
  EXPECT_TRUE(single.neighbors.empty());
  expect_same(single, build_families(one.x, one.horizon, one.pad), "one particle");
  expect_same(through(reverse, one, 1, 1), build_families(one.x, one.horizon, one.pad, 1, 1), "one particle, no rows");
}

// The counting sort's fill takes each cell's slots with atomics, in whatever order the
// threads run; each cell is then sorted. Launched in reverse order it must still give
// group_by_key's serial counting sort: the same starts, each cell ascending.
TEST(FamilyBuild, BinningInReverseOrderIsTheSerialCountingSort) {
  const Cloud c = graded(3000);
  const int64_t n = static_cast<int64_t>(c.horizon.size());
  const FamilyPlan plan = plan_families(c.x, c.horizon, c.pad, 0, -1);
  const FamilyPlan::Grid& grid = plan.up_to[plan.classes - 1];  // every particle
  ASSERT_TRUE(grid.built);
  ASSERT_EQ(grid.size, n);
  PdSystem sys;
  FamilyHostMemory mem;
  const family::Points p = family_detail::points(mem, plan, c.x, c.horizon, c.pad);
  const family::GridView g =
      family_detail::bin(ReverseBlockExec(sys), mem, p, grid, n, mem.make<int64_t>(plan.n));
  const CellList serial = sort_into_cells(grid.cells, c.x);
  ASSERT_EQ(g.cells(), serial.grid.cells());
  EXPECT_EQ(std::vector<int64_t>(g.start, g.start + g.cells() + 1), serial.start);
  std::vector<int32_t> members;
  for (int64_t k = 0; k < n; ++k) members.push_back(g.sorted[k].index);
  EXPECT_EQ(members, serial.members);
  int64_t occupied = 0, crowded = 0;  // cells with more than one particle: the sort had work
  for (long long cell = 0; cell < g.cells(); ++cell) {
    occupied += g.start[cell + 1] > g.start[cell];
    crowded += g.start[cell + 1] - g.start[cell] > 1;
  }
  EXPECT_GT(crowded, occupied / 4);
}

// The device's sort of a row (family_kernels.hpp, quicksort with insertion sort below 24) on
// lengths around its thresholds and on inputs in order, reversed and shuffled.
TEST(FamilyBuild, RowSortOrdersAnyInput) {
  std::mt19937 rng(9);
  for (const int64_t m : {0, 1, 2, 23, 24, 25, 100, 1000, 20000}) {
    std::vector<int32_t> want(static_cast<size_t>(m));
    for (int64_t k = 0; k < m; ++k) want[k] = static_cast<int32_t>(3 * k + 1);
    std::vector<int32_t> ascending = want, descending(want.rbegin(), want.rend()), shuffled = want;
    std::shuffle(shuffled.begin(), shuffled.end(), rng);
    for (auto* v : {&ascending, &descending, &shuffled}) {
      family::sort_ascending(v->data(), m);
      EXPECT_EQ(*v, want) << "length " << m;
    }
  }
}

// build_families on a uniform lattice takes each row from the lattice's offsets and the
// site-to-point map (families.cpp) instead of the cell search, which build_families_with
// still runs: the rows must be the same entry for entry. Points in a shuffled order (as the
// set-up's Morton order), sites missing, a box not a cube (every face an edge of some rows),
// an origin off zero (the differences round), horizons of m = 3.015 and 2.6 spacings (not
// integers), the partial-volume pad, 3D and 2D; and a lattice jittered past the tolerance,
// which must take the cell search.
TEST(FamilyBuild, LatticeOffsetRowsEqualTheCellSearch) {
  PdSystem sys;
  const OpenMpExec openmp(sys);
  std::mt19937 rng(11);
  for (const int dimension : {3, 2})
    for (const double m : {3.015, 2.6}) {
      const double dx = 0.37e-3;
      const int nx = 13, ny = 9, nz = dimension == 3 ? 7 : 1;
      Cloud c;
      for (int k = 0; k < nz; ++k)
        for (int j = 0; j < ny; ++j)
          for (int i = 0; i < nx; ++i) {
            if ((i * 7 + j * 3 + k * 5) % 11 == 0) continue;  // a missing site
            c.x.insert(c.x.end(), {0.0123 + (i + 0.5) * dx, -0.007 + (j + 0.5) * dx, 0.5 * dx + k * dx});
            c.horizon.push_back(m * dx);
            c.pad.push_back(0.5 * std::sqrt(static_cast<double>(dimension)) * dx * (5.0 / 6.0) * (1.0 + 1e-6));
          }
      const size_t n = c.horizon.size();
      std::vector<size_t> order(n);
      for (size_t q = 0; q < n; ++q) order[q] = q;
      std::shuffle(order.begin(), order.end(), rng);
      Cloud s;
      for (const size_t q : order) {
        s.x.insert(s.x.end(), {c.x[3 * q], c.x[3 * q + 1], c.x[3 * q + 2]});
        s.horizon.push_back(c.horizon[q]);
        s.pad.push_back(c.pad[q]);
      }
      const std::string what = std::to_string(dimension) + "D, m " + std::to_string(m);
      ASSERT_TRUE(families_on_lattice(s.x, s.horizon, s.pad)) << what;
      const Families want = through(openmp, s);
      expect_same(build_families(s.x, s.horizon, s.pad), want, what);
#if defined(_OPENMP)
      // one thread takes the rows by transposition (no sort), more threads search and sort each
      const int threads = omp_get_max_threads();
      for (const int t : {1, 2}) {
        omp_set_num_threads(t);
        expect_same(build_families(s.x, s.horizon, s.pad), want, what + ", threads " + std::to_string(t));
      }
      omp_set_num_threads(threads);
#endif
      const int64_t rows = static_cast<int64_t>(n);
      expect_same(build_families(s.x, s.horizon, s.pad, rows / 3, 2 * rows / 3), through(openmp, s, rows / 3, 2 * rows / 3),
                  what + ", a third of the rows");
      // a row in the middle has partners, so the comparison is not of empty rows
      EXPECT_GT(want.offsets[n / 2 + 1] - want.offsets[n / 2], 10) << what;
      // moved by 1e-5 spacings: no longer a lattice to the tolerance, the cell search
      Cloud moved = s;
      moved.x[3] += 1e-5 * dx;
      EXPECT_FALSE(families_on_lattice(moved.x, moved.horizon, moved.pad)) << what;
      expect_same(build_families(moved.x, moved.horizon, moved.pad), through(openmp, moved), what + ", jittered");
    }
}
