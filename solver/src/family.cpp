#include "breccia/solver/family.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace breccia::solver {
namespace {

struct Box {
  double lo[3], hi[3];
};

Box bounding_box(std::span<const double> x, size_t n) {
  Box b{{1e300, 1e300, 1e300}, {-1e300, -1e300, -1e300}};
  for (size_t i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d) {
      b.lo[d] = std::min(b.lo[d], x[3 * i + d]);
      b.hi[d] = std::max(b.hi[d], x[3 * i + d]);
    }
  return b;
}

}  // namespace

Families build_families(std::span<const double> x, std::span<const double> horizon,
                        std::span<const double> pad) {
  const size_t n = horizon.size();
  if (x.size() != 3 * n) throw std::invalid_argument("build_families: position must be 3N");
  Families fam;
  fam.offsets.assign(n + 1, 0);
  if (n == 0) return fam;
  auto pad_of = [&](size_t i) { return pad.empty() ? 0.0 : pad[i]; };
  double max_pad = 0.0, min_horizon = horizon[0], max_horizon = horizon[0];
  for (size_t i = 0; i < n; ++i) {
    max_pad = std::max(max_pad, pad_of(i));
    min_horizon = std::min(min_horizon, horizon[i]);
    max_horizon = std::max(max_horizon, horizon[i]);
  }
  const bool uniform = min_horizon == max_horizon;
  // reach(i, j) = max(h_i, h_j) + max(p_i, p_j) is the larger of the two "own" reaches
  // h_i + max(p_i, p_j) and h_j + max(p_i, p_j). Each particle searches its own reach; the
  // family is the union of what i found and what found i. With one horizon the own lists
  // are already symmetric. Cells are sized to the smallest reach (at least 1/8 of the
  // largest), so a fine region of a graded mesh with a 3x smaller horizon does not scan
  // cells sized for the coarse one (that made a 291k-particle dual-horizon family build
  // take a minute).
  const double max_reach = max_horizon + max_pad;
  const double cell = std::max({min_horizon + max_pad, max_reach / 8.0, 1e-300});
  const Box box = bounding_box(x, n);
  long long dims[3];
  for (int d = 0; d < 3; ++d)
    dims[d] = std::max<long long>(1, static_cast<long long>(std::floor((box.hi[d] - box.lo[d]) / cell)) + 1);
  const long long cell_count = dims[0] * dims[1] * dims[2];
  std::vector<int64_t> cell_of(n);
  for (size_t i = 0; i < n; ++i) {
    long long c[3];
    for (int d = 0; d < 3; ++d)
      c[d] = std::min<long long>(dims[d] - 1, static_cast<long long>((x[3 * i + d] - box.lo[d]) / cell));
    cell_of[i] = (c[2] * dims[1] + c[1]) * dims[0] + c[0];
  }
  std::vector<int64_t> cell_start(static_cast<size_t>(cell_count) + 1, 0);
  for (size_t i = 0; i < n; ++i) ++cell_start[cell_of[i] + 1];
  for (long long c = 0; c < cell_count; ++c) cell_start[c + 1] += cell_start[c];
  std::vector<int32_t> cell_members(n);
  {
    std::vector<int64_t> fill(cell_start.begin(), cell_start.end() - 1);
    for (size_t i = 0; i < n; ++i) cell_members[fill[cell_of[i]]++] = static_cast<int32_t>(i);
  }
  // Own search of particle i: every j within h_i + max(p_i, p_j).
  auto visit = [&](size_t i, auto&& emit) {
    const long long cx = cell_of[i] % dims[0];
    const long long cy = (cell_of[i] / dims[0]) % dims[1];
    const long long cz = cell_of[i] / (dims[0] * dims[1]);
    const long long ring = static_cast<long long>(std::ceil((horizon[i] + max_pad) / cell));
    for (long long az = std::max(0LL, cz - ring); az <= std::min(dims[2] - 1, cz + ring); ++az)
      for (long long ay = std::max(0LL, cy - ring); ay <= std::min(dims[1] - 1, cy + ring); ++ay)
        for (long long ax = std::max(0LL, cx - ring); ax <= std::min(dims[0] - 1, cx + ring); ++ax) {
          const long long c = (az * dims[1] + ay) * dims[0] + ax;
          for (int64_t k = cell_start[c]; k < cell_start[c + 1]; ++k) {
            const size_t j = static_cast<size_t>(cell_members[k]);
            if (j == i) continue;
            const double reach = horizon[i] + std::max(pad_of(i), pad_of(j));
            double r2 = 0.0;
            for (int d = 0; d < 3; ++d) {
              const double e = x[3 * j + d] - x[3 * i + d];
              r2 += e * e;
            }
            if (r2 <= reach * reach) emit(j);
          }
        }
  };
  // Two passes (count, fill) keep memory exact for 10^8 bonds.
  Families own;
  own.offsets.assign(n + 1, 0);
  {
    std::vector<int64_t> count(n, 0);
#pragma omp parallel for schedule(dynamic, 256)
    for (size_t i = 0; i < n; ++i) {
      int64_t c = 0;
      visit(i, [&](size_t) { ++c; });
      count[i] = c;
    }
    for (size_t i = 0; i < n; ++i) own.offsets[i + 1] = own.offsets[i] + count[i];
  }
  own.neighbors.resize(static_cast<size_t>(own.offsets[n]));
#pragma omp parallel for schedule(dynamic, 256)
  for (size_t i = 0; i < n; ++i) {
    int64_t k = own.offsets[i];
    visit(i, [&](size_t j) { own.neighbors[k++] = static_cast<int32_t>(j); });
    std::sort(own.neighbors.begin() + own.offsets[i], own.neighbors.begin() + own.offsets[i + 1]);
  }
  if (uniform) return own;
  // Transpose (who found i), filled in ascending i, so each list comes out sorted.
  std::vector<int64_t> t_offsets(n + 1, 0);
  for (int32_t j : own.neighbors) ++t_offsets[static_cast<size_t>(j) + 1];
  for (size_t i = 0; i < n; ++i) t_offsets[i + 1] += t_offsets[i];
  std::vector<int32_t> t_neighbors(own.neighbors.size());
  {
    std::vector<int64_t> fill(t_offsets.begin(), t_offsets.end() - 1);
    for (size_t i = 0; i < n; ++i)
      for (int64_t k = own.offsets[i]; k < own.offsets[i + 1]; ++k)
        t_neighbors[fill[own.neighbors[k]]++] = static_cast<int32_t>(i);
  }
  auto merged = [&](size_t i, auto&& emit) {
    int64_t a = own.offsets[i], b = t_offsets[i];
    const int64_t ae = own.offsets[i + 1], be = t_offsets[i + 1];
    while (a < ae || b < be) {
      int32_t v;
      if (b >= be || (a < ae && own.neighbors[a] < t_neighbors[b])) v = own.neighbors[a++];
      else if (a >= ae || t_neighbors[b] < own.neighbors[a]) v = t_neighbors[b++];
      else {
        v = own.neighbors[a++];
        ++b;
      }
      emit(v);
    }
  };
  {
    std::vector<int64_t> count(n, 0);
#pragma omp parallel for schedule(dynamic, 256)
    for (size_t i = 0; i < n; ++i) {
      int64_t c = 0;
      merged(i, [&](int32_t) { ++c; });
      count[i] = c;
    }
    for (size_t i = 0; i < n; ++i) fam.offsets[i + 1] = fam.offsets[i] + count[i];
  }
  fam.neighbors.resize(static_cast<size_t>(fam.offsets[n]));
#pragma omp parallel for schedule(dynamic, 256)
  for (size_t i = 0; i < n; ++i) {
    int64_t k = fam.offsets[i];
    merged(i, [&](int32_t v) { fam.neighbors[k++] = v; });
  }
  return fam;
}

uint64_t morton_spread(uint64_t v) {
  v &= 0x1fffff;
  v = (v | v << 32) & 0x1f00000000ffffull;
  v = (v | v << 16) & 0x1f0000ff0000ffull;
  v = (v | v << 8) & 0x100f00f00f00f00full;
  v = (v | v << 4) & 0x10c30c30c30c30c3ull;
  v = (v | v << 2) & 0x1249249249249249ull;
  return v;
}

std::vector<int32_t> morton_order(std::span<const double> x) {
  const size_t n = x.size() / 3;
  const Box box = bounding_box(x, n);
  double extent = 0.0;
  for (int d = 0; d < 3; ++d) extent = std::max(extent, box.hi[d] - box.lo[d]);
  if (extent <= 0) extent = 1.0;
  std::vector<uint64_t> key(n);
  for (size_t i = 0; i < n; ++i) {
    uint64_t k = 0;
    for (int d = 0; d < 3; ++d) {
      const double t = (x[3 * i + d] - box.lo[d]) / extent;
      k |= morton_spread(static_cast<uint64_t>(t * 2097151.0)) << d;
    }
    key[i] = k;
  }
  std::vector<int32_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int32_t a, int32_t b) { return key[a] < key[b]; });
  return order;
}

}  // namespace breccia::solver
