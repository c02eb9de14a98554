#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <utility>

#include "breccia/common/cell_list.hpp"
#include "breccia/common/families.hpp"

using namespace breccia;

TEST(CellList, EveryParticleInItsCellInAscendingOrder) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 3.0);
  std::vector<double> x(3 * 500);
  for (double& v : x) v = u(rng);
  const CellList cells = sort_into_cells(CellGrid::covering(bounding_box(x), 0.37), x);
  ASSERT_EQ(cells.start.size(), static_cast<size_t>(cells.grid.cells()) + 1);
  ASSERT_EQ(cells.members.size(), 500u);
  for (long long c = 0; c < cells.grid.cells(); ++c) {
    EXPECT_TRUE(std::is_sorted(cells.members.begin() + cells.start[c], cells.members.begin() + cells.start[c + 1]));
    for (int64_t k = cells.start[c]; k < cells.start[c + 1]; ++k) {
      const int32_t i = cells.members[k];
      EXPECT_EQ(cells.grid.index_of(&x[3 * i]), c);
      for (int d = 0; d < 3; ++d) {  // the cell holds the point (brute force from the definition)
        const long long cd = static_cast<long long>(std::floor((x[3 * i + d] - cells.grid.origin[d]) / 0.37));
        EXPECT_EQ(std::min(cd, cells.grid.count[d] - 1), cells.grid.coordinate(d, x[3 * i + d]));
      }
    }
  }
}

TEST(CellList, GroupByKeyIsAStableCountingSort) {
  const std::vector<unsigned long long> key{3, 0, 3, 1, 0};
  std::vector<int64_t> start;
  std::vector<int32_t> members;
  group_by_key(std::span<const unsigned long long>(key), 4, start, members);
  EXPECT_EQ(start, (std::vector<int64_t>{0, 2, 3, 3, 5}));
  EXPECT_EQ(members, (std::vector<int32_t>{1, 4, 3, 0, 2}));
}

// Particle i's family by testing every pair: j is in it when |x_j - x_i| <= max(h_i, h_j) +
// max(p_i, p_j), the reach build_families promises.
static std::vector<int32_t> brute_force_family(const std::vector<double>& x, const std::vector<double>& h,
                                               const std::vector<double>& pad, size_t i) {
  std::vector<int32_t> family;
  for (size_t j = 0; j < h.size(); ++j) {
    if (j == i) continue;
    const double reach = std::max(h[i], h[j]) + std::max(pad[i], pad[j]);
    double r2 = 0;
    for (int d = 0; d < 3; ++d) r2 += (x[3 * j + d] - x[3 * i + d]) * (x[3 * j + d] - x[3 * i + d]);
    if (r2 <= reach * reach) family.push_back(static_cast<int32_t>(j));
  }
  return family;
}

TEST(Families, MatchBruteForceWithGradedHorizonsAndPads) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const size_t n = 400;
  std::vector<double> x(3 * n), h(n), pad(n);
  for (double& v : x) v = u(rng);
  for (size_t i = 0; i < n; ++i) {
    h[i] = 0.08 + 0.1 * u(rng);
    pad[i] = 0.02 * u(rng);
  }
  const Families f = build_families(x, h, pad);
  for (size_t i = 0; i < n; ++i) {
    const std::vector<int32_t> expected = brute_force_family(x, h, pad, i);
    EXPECT_EQ(std::vector<int32_t>(f.neighbors.begin() + f.offsets[i], f.neighbors.begin() + f.offsets[i + 1]), expected)
        << "particle " << i;
  }
}

// A row range (the distributed set-up's own rows) gives those rows exactly as the whole
// build does and leaves the others empty: with one horizon, and with graded horizons (dual
// horizon), where the whole build unites each search with the transposed one and a range
// tests both ends of each pair instead.
TEST(Families, RowRangeBuildsThoseRowsAsTheWholeBuild) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const size_t n = 600;
  std::vector<double> x(3 * n), one(n, 0.12), graded(n), pad(n);
  for (size_t i = 0; i < n; ++i) {
    for (int d = 0; d < 3; ++d) x[3 * i + d] = u(rng);
    pad[i] = 0.02 * u(rng);
    graded[i] = 0.06 + 0.12 * u(rng);
  }
  for (const auto* h : {&one, &graded}) {
    const Families whole = build_families(x, *h, pad);
    for (const auto [b, e] : {std::pair<int64_t, int64_t>{150, 420}, {0, 1}, {599, 600}}) {
      const Families part = build_families(x, *h, pad, b, e);
      ASSERT_EQ(part.offsets.size(), n + 1);
      for (size_t i = 0; i < n; ++i) {
        const bool own = static_cast<int64_t>(i) >= b && static_cast<int64_t>(i) < e;
        const std::vector<int32_t> got(part.neighbors.begin() + part.offsets[i],
                                       part.neighbors.begin() + part.offsets[i + 1]);
        const std::vector<int32_t> want = own ? std::vector<int32_t>(whole.neighbors.begin() + whole.offsets[i],
                                                                     whole.neighbors.begin() + whole.offsets[i + 1])
                                              : std::vector<int32_t>{};
        EXPECT_EQ(got, want) << (h == &one ? "one horizon" : "graded") << ", rows " << b << "-" << e << ", particle " << i;
      }
      EXPECT_GT(part.bond_count(), 0u);
    }
  }
}

// A cloud graded over more than three octaves of horizon (several reach classes, each with
// grids of its own cells) and pads not proportional to the horizons: every row equals the
// brute-force family (the pair's reach is max(h_i, h_j) + max(p_i, p_j)), and a row range
// gives the whole build's rows. Ten octaves exercise the last, open-ended class.
TEST(Families, MatchBruteForceAcrossReachClasses) {
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const size_t n = 900;
  for (const double octaves : {3.5, 10.0}) {
    std::vector<double> x(3 * n), h(n), pad(n);
    for (size_t i = 0; i < n; ++i) {
      // denser towards x = 0, the horizon growing with x as on a graded mesh
      const double s = u(rng);
      x[3 * i] = s * s;
      x[3 * i + 1] = u(rng);
      x[3 * i + 2] = 0.5 * u(rng);
      h[i] = (octaves < 5.0 ? 0.05 : 0.01) * std::pow(2.0, octaves * x[3 * i] * (0.8 + 0.2 * u(rng)));
      pad[i] = (i % 7 == 0 ? 0.5 : 0.2) * h[i] * u(rng);
    }
    const Families f = build_families(x, h, pad);
    size_t entries = 0;
    for (size_t i = 0; i < n; ++i) {
      const std::vector<int32_t> expected = brute_force_family(x, h, pad, i);
      entries += expected.size();
      ASSERT_EQ(std::vector<int32_t>(f.neighbors.begin() + f.offsets[i], f.neighbors.begin() + f.offsets[i + 1]), expected)
          << octaves << " octaves, particle " << i;
    }
    EXPECT_GT(entries, 10 * n) << octaves << " octaves";  // not a trivially empty family
    EXPECT_LT(entries, n * (n - 1)) << octaves << " octaves";  // nor every pair
    const Families part = build_families(x, h, pad, 300, 640);
    for (size_t i = 0; i < n; ++i) {
      const bool own = i >= 300 && i < 640;
      EXPECT_EQ(part.offsets[i + 1] - part.offsets[i], own ? f.offsets[i + 1] - f.offsets[i] : 0) << "particle " << i;
      if (own)
        EXPECT_TRUE(std::equal(part.neighbors.begin() + part.offsets[i], part.neighbors.begin() + part.offsets[i + 1],
                               f.neighbors.begin() + f.offsets[i]))
            << "particle " << i;
    }
  }
}
