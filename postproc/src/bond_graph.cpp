#include "breccia/postproc/bond_graph.hpp"

#include <algorithm>
#include <bit>

#include "breccia/common/error.hpp"
#include "breccia/common/union_find.hpp"

namespace breccia::postproc {

void validate_pairs(std::span<const int64_t> pairs, size_t n, const std::string& file, const std::string& dataset) {
  if (pairs.size() % 2 != 0)
    throw InputError(file, dataset, "odd number of entries " + std::to_string(pairs.size()), "B x 2 pairs");
  for (size_t k = 0; k < pairs.size(); k += 2) {
    const int64_t i = pairs[k], j = pairs[k + 1];
    if (i < 0 || j < 0 || static_cast<size_t>(i) >= n || static_cast<size_t>(j) >= n || i == j)
      throw InputError(file, dataset + "[" + std::to_string(k / 2) + "]",
                       "pair (" + std::to_string(i) + ", " + std::to_string(j) + ")",
                       "two different particle indices in [0, " + std::to_string(n) + ")");
  }
}

RemovedBonds::RemovedBonds(std::span<const int64_t> pairs, size_t n) : offsets_(n + 1, 0) {
  const size_t b = pairs.size() / 2;
  for (size_t k = 0; k < b; ++k) ++offsets_[std::min(pairs[2 * k], pairs[2 * k + 1]) + 1];
  for (size_t i = 0; i < n; ++i) offsets_[i + 1] += offsets_[i];
  partners_.resize(b);
  std::vector<int64_t> fill(offsets_.begin(), offsets_.end() - 1);
  for (size_t k = 0; k < b; ++k) {
    const int64_t lo = std::min(pairs[2 * k], pairs[2 * k + 1]);
    partners_[fill[lo]++] = static_cast<int32_t>(std::max(pairs[2 * k], pairs[2 * k + 1]));
  }
  for (size_t i = 0; i < n; ++i) std::sort(partners_.begin() + offsets_[i], partners_.begin() + offsets_[i + 1]);
}

bool RemovedBonds::contains(int64_t i, int64_t j) const {
  if (offsets_.empty()) return false;
  if (i > j) std::swap(i, j);
  const auto p = partners_above(static_cast<size_t>(i));
  return std::binary_search(p.begin(), p.end(), static_cast<int32_t>(j));
}

std::vector<int32_t> intact_components(const Families& fam, const RemovedBonds& broken,
                                       const RemovedBonds& precracks, int32_t* component_count) {
  const size_t n = fam.particle_count();
  UnionFind uf(n);
  for (size_t i = 0; i < n; ++i) {
    const auto b = broken.size() ? broken.partners_above(i) : std::span<const int32_t>{};
    const auto p = precracks.size() ? precracks.partners_above(i) : std::span<const int32_t>{};
    auto bi = b.begin();
    auto pi = p.begin();
    // Neighbours are sorted ascending, as are the removed partners: one merge walk.
    for (int64_t k = fam.offsets[i]; k < fam.offsets[i + 1]; ++k) {
      const int32_t j = fam.neighbors[k];
      if (j <= static_cast<int32_t>(i)) continue;
      while (bi != b.end() && *bi < j) ++bi;
      while (pi != p.end() && *pi < j) ++pi;
      if ((bi != b.end() && *bi == j) || (pi != p.end() && *pi == j)) continue;
      uf.unite(static_cast<int32_t>(i), j);
    }
  }
  return uf.labels(component_count);
}

size_t count_bits(std::span<const uint8_t> bits) {
  size_t c = 0;
  for (uint8_t byte : bits) c += static_cast<size_t>(std::popcount(byte));
  return c;
}

int64_t bond_index(const Families& half, int64_t i, int64_t j) {
  if (i > j) std::swap(i, j);
  if (i < 0 || static_cast<size_t>(i) >= half.particle_count()) return -1;
  const auto first = half.neighbors.begin() + half.offsets[i], last = half.neighbors.begin() + half.offsets[i + 1];
  const auto it = std::lower_bound(first, last, static_cast<int32_t>(j));
  return it != last && *it == j ? static_cast<int64_t>(it - half.neighbors.begin()) : -1;
}

std::vector<int32_t> intact_components(const Families& half, std::span<const uint8_t> graph,
                                       std::span<const uint8_t> broken, const RemovedBonds& precracks,
                                       int32_t* component_count) {
  const size_t n = half.particle_count();
  UnionFind uf(n);
  for (size_t i = 0; i < n; ++i) {
    const auto p = precracks.size() ? precracks.partners_above(i) : std::span<const int32_t>{};
    auto pi = p.begin();
    for (int64_t b = half.offsets[i]; b < half.offsets[i + 1]; ++b) {
      if ((!graph.empty() && !bond_bit(graph, b)) || bond_bit(broken, b)) continue;
      const int32_t j = half.neighbors[b];
      while (pi != p.end() && *pi < j) ++pi;  // both ascending: one merge walk
      if (pi != p.end() && *pi == j) continue;
      uf.unite(static_cast<int32_t>(i), j);
    }
  }
  return uf.labels(component_count);
}

}  // namespace breccia::postproc
