#include "breccia/solver/partition.hpp"

#include <algorithm>
#include <stdexcept>
#include <utility>

namespace breccia::solver {

int Partition::owner(int64_t i) const {
  // The last rank whose range starts at or before i (empty ranks share their start).
  return static_cast<int>(std::upper_bound(begin.begin(), begin.end() - 1, i) - begin.begin()) - 1;
}

Partition MortonRangePartitioner::partition(const std::vector<int64_t>& offsets, int ranks) const {
  const int64_t n = static_cast<int64_t>(offsets.size()) - 1;
  if (ranks < 1) throw std::invalid_argument("partition: at least one rank");
  if (ranks > n)
    throw std::invalid_argument("partition: " + std::to_string(ranks) + " ranks for " + std::to_string(n) +
                                " particles (at most one rank per particle)");
  // cum[i]: work of particles [0, i).
  std::vector<double> cum(static_cast<size_t>(n) + 1, 0.0);
  for (int64_t i = 0; i < n; ++i) cum[i + 1] = cum[i] + static_cast<double>(offsets[i + 1] - offsets[i]) + particle_weight_;
  Partition p;
  p.begin.assign(static_cast<size_t>(ranks) + 1, 0);
  p.begin[ranks] = n;
  for (int r = 1; r < ranks; ++r) {
    const double target = cum[n] * r / ranks;
    int64_t i = std::lower_bound(cum.begin(), cum.end(), target) - cum.begin();
    if (i > 0 && target - cum[i - 1] < cum[i] - target) --i;  // the nearer cut
    // Every rank keeps at least one particle: ranges stay non-empty while ranks <= n.
    i = std::clamp<int64_t>(i, p.begin[r - 1] + 1, n - (ranks - r));
    p.begin[r] = i;
  }
  return p;
}

Halo build_halo(const Partition& part, int rank, const std::vector<int64_t>& offsets,
                const std::vector<int32_t>& neighbor) {
  Halo h;
  h.rank = rank;
  const int64_t b = part.begin[rank], e = part.begin[rank + 1];
  std::vector<std::pair<int, int32_t>> sends;  // (destination rank, owned particle)
  for (int64_t i = b; i < e; ++i)
    for (int64_t k = offsets[i]; k < offsets[i + 1]; ++k) {
      const int32_t j = neighbor[k];
      if (j >= b && j < e) continue;
      h.ghosts.push_back(j);
      sends.emplace_back(part.owner(j), static_cast<int32_t>(i));  // families are symmetric: j's rank reads i
    }
  std::sort(h.ghosts.begin(), h.ghosts.end());
  h.ghosts.erase(std::unique(h.ghosts.begin(), h.ghosts.end()), h.ghosts.end());
  for (size_t g = 0; g < h.ghosts.size(); ++g) {
    const int src = part.owner(h.ghosts[g]);
    if (h.recv_ranks.empty() || h.recv_ranks.back() != src) {
      h.recv_ranks.push_back(src);
      h.recv_begin.push_back(static_cast<int64_t>(g));
    }
  }
  h.recv_begin.push_back(static_cast<int64_t>(h.ghosts.size()));
  std::sort(sends.begin(), sends.end());
  sends.erase(std::unique(sends.begin(), sends.end()), sends.end());
  for (const auto& [dst, i] : sends) {
    if (h.send_ranks.empty() || h.send_ranks.back() != dst) {
      h.send_ranks.push_back(dst);
      h.send_lists.emplace_back();
    }
    h.send_lists.back().push_back(i);
  }
  return h;
}

DecompositionStats decomposition_stats(const Partition& part, const std::vector<int64_t>& offsets,
                                       const std::vector<int32_t>& neighbor, double bytes_per_ghost) {
  DecompositionStats s;
  s.ranks = part.ranks();
  s.min_owned = s.max_owned = part.owned(0);
  double bonds_sum = 0.0, bonds_max = 0.0, ratio_sum = 0.0, bytes_sum = 0.0;
  for (int r = 0; r < s.ranks; ++r) {
    const Halo h = build_halo(part, r, offsets, neighbor);
    const int64_t owned = part.owned(r);
    s.min_owned = std::min(s.min_owned, owned);
    s.max_owned = std::max(s.max_owned, owned);
    const double bonds = static_cast<double>(offsets[part.begin[r + 1]] - offsets[part.begin[r]]);
    bonds_sum += bonds;
    bonds_max = std::max(bonds_max, bonds);
    const double ratio = owned > 0 ? static_cast<double>(h.ghosts.size()) / static_cast<double>(owned) : 0.0;
    ratio_sum += ratio;
    s.max_ghost_ratio = std::max(s.max_ghost_ratio, ratio);
    const double bytes = static_cast<double>(h.ghosts.size()) * bytes_per_ghost;
    bytes_sum += bytes;
    s.max_halo_bytes = std::max(s.max_halo_bytes, bytes);
    s.max_neighbour_ranks = std::max<int>(s.max_neighbour_ranks, static_cast<int>(std::max(h.recv_ranks.size(), h.send_ranks.size())));
  }
  s.max_over_mean_bonds = bonds_sum > 0 ? bonds_max / (bonds_sum / s.ranks) : 1.0;
  s.mean_ghost_ratio = ratio_sum / s.ranks;
  s.mean_halo_bytes = bytes_sum / s.ranks;
  return s;
}

}  // namespace breccia::solver
