#include "breccia/solver/family.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "breccia/common/cell_list.hpp"

namespace breccia::solver {

uint64_t morton_spread(uint64_t v) {
  v &= 0x1fffff;
  v = (v | v << 32) & 0x1f00000000ffffull;
  v = (v | v << 16) & 0x1f0000ff0000ffull;
  v = (v | v << 8) & 0x100f00f00f00f00full;
  v = (v | v << 4) & 0x10c30c30c30c30c3ull;
  v = (v | v << 2) & 0x1249249249249249ull;
  return v;
}

double morton_extent(const BoundingBox& box) {
  double extent = 0.0;
  for (int d = 0; d < 3; ++d) extent = std::max(extent, box.hi[d] - box.lo[d]);
  return extent <= 0 ? 1.0 : extent;
}

uint64_t morton_key(const double* p, const BoundingBox& box, double extent) {
  uint64_t k = 0;
  for (int d = 0; d < 3; ++d) {
    const double t = (p[d] - box.lo[d]) / extent;
    k |= morton_spread(static_cast<uint64_t>(t * 2097151.0)) << d;
  }
  return k;
}

std::vector<int32_t> morton_order(std::span<const double> x) {
  const size_t n = x.size() / 3;
  const BoundingBox box = bounding_box(x);
  const double extent = morton_extent(box);
  std::vector<uint64_t> key(n);
  for (size_t i = 0; i < n; ++i) key[i] = morton_key(&x[3 * i], box, extent);
  std::vector<int32_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int32_t a, int32_t b) { return key[a] < key[b]; });
  return order;
}

}  // namespace breccia::solver
