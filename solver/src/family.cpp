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
  double max_reach = 0.0;
  for (size_t i = 0; i < n; ++i)
    max_reach = std::max(max_reach, horizon[i] + (pad.empty() ? 0.0 : pad[i]));
  const Box box = bounding_box(x, n);
  // Cells of edge max_reach: a neighbour is at most one cell away.
  const double cell = std::max(max_reach, 1e-300);
  long long dims[3];
  for (int d = 0; d < 3; ++d)
    dims[d] = std::max<long long>(1, static_cast<long long>(std::floor((box.hi[d] - box.lo[d]) / cell)) + 1);
  // Guard against absurd grids (one far outlier): cap the cell count near N.
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
  auto pad_of = [&](size_t i) { return pad.empty() ? 0.0 : pad[i]; };
  // Two passes (count, fill) keep memory exact for 10^8 bonds.
  auto visit = [&](size_t i, auto&& emit) {
    const long long cx = cell_of[i] % dims[0];
    const long long cy = (cell_of[i] / dims[0]) % dims[1];
    const long long cz = cell_of[i] / (dims[0] * dims[1]);
    for (long long dz = -1; dz <= 1; ++dz)
      for (long long dy = -1; dy <= 1; ++dy)
        for (long long dx = -1; dx <= 1; ++dx) {
          const long long ax = cx + dx, ay = cy + dy, az = cz + dz;
          if (ax < 0 || ay < 0 || az < 0 || ax >= dims[0] || ay >= dims[1] || az >= dims[2]) continue;
          const long long c = (az * dims[1] + ay) * dims[0] + ax;
          for (int64_t k = cell_start[c]; k < cell_start[c + 1]; ++k) {
            const size_t j = static_cast<size_t>(cell_members[k]);
            if (j == i) continue;
            const double reach = std::max(horizon[i], horizon[j]) + std::max(pad_of(i), pad_of(j));
            double r2 = 0.0;
            for (int d = 0; d < 3; ++d) {
              const double e = x[3 * j + d] - x[3 * i + d];
              r2 += e * e;
            }
            if (r2 <= reach * reach) emit(j);
          }
        }
  };
  std::vector<int64_t> count(n, 0);
#pragma omp parallel for schedule(dynamic, 256)
  for (size_t i = 0; i < n; ++i) {
    int64_t c = 0;
    visit(i, [&](size_t) { ++c; });
    count[i] = c;
  }
  for (size_t i = 0; i < n; ++i) fam.offsets[i + 1] = fam.offsets[i] + count[i];
  fam.neighbors.resize(static_cast<size_t>(fam.offsets[n]));
#pragma omp parallel for schedule(dynamic, 256)
  for (size_t i = 0; i < n; ++i) {
    int64_t k = fam.offsets[i];
    visit(i, [&](size_t j) { fam.neighbors[k++] = static_cast<int32_t>(j); });
    std::sort(fam.neighbors.begin() + fam.offsets[i], fam.neighbors.begin() + fam.offsets[i + 1]);
  }
  return fam;
}

std::vector<int32_t> morton_order(std::span<const double> x) {
  const size_t n = x.size() / 3;
  const Box box = bounding_box(x, n);
  double extent = 0.0;
  for (int d = 0; d < 3; ++d) extent = std::max(extent, box.hi[d] - box.lo[d]);
  if (extent <= 0) extent = 1.0;
  auto spread = [](uint64_t v) {  // 21 bits -> every third bit
    v &= 0x1fffff;
    v = (v | v << 32) & 0x1f00000000ffffull;
    v = (v | v << 16) & 0x1f0000ff0000ffull;
    v = (v | v << 8) & 0x100f00f00f00f00full;
    v = (v | v << 4) & 0x10c30c30c30c30c3ull;
    v = (v | v << 2) & 0x1249249249249249ull;
    return v;
  };
  std::vector<uint64_t> key(n);
  for (size_t i = 0; i < n; ++i) {
    uint64_t k = 0;
    for (int d = 0; d < 3; ++d) {
      const double t = (x[3 * i + d] - box.lo[d]) / extent;
      k |= spread(static_cast<uint64_t>(t * 2097151.0)) << d;
    }
    key[i] = k;
  }
  std::vector<int32_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int32_t a, int32_t b) { return key[a] < key[b]; });
  return order;
}

}  // namespace breccia::solver
