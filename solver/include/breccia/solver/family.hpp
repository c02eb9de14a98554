#pragma once
// Peridynamic families: for each particle i, every j != i whose reference distance is
// within reach(i, j) = max(horizon_i, horizon_j) + max(pad_i, pad_j). Full lists (each
// pair appears from both ends) so a particle sums its own force without atomics.
// Built with a uniform cell list sized to the smallest reach (each particle scans the
// cells its own reach covers; the family is the union of both directions): O(N) for
// bounded density contrast.
#include <cstdint>
#include <span>
#include <vector>

namespace breccia::solver {

struct Families {
  std::vector<int64_t> offsets;   // N + 1
  std::vector<int32_t> neighbors; // offsets[N], sorted ascending within a family
  size_t particle_count() const { return offsets.empty() ? 0 : offsets.size() - 1; }
  size_t bond_count() const { return neighbors.size(); }
};

// position: 3N (x, y, z interleaved); horizon_m, pad_m: N (pad may be empty = 0).
// The pad lets partial-volume rules include neighbours whose cell straddles the horizon.
Families build_families(std::span<const double> position, std::span<const double> horizon_m,
                        std::span<const double> pad_m = {});

// Permutation that sorts particles along a Morton (Z-order) curve: new index k holds old
// particle order[k]. Neighbouring particles end up close in memory.
std::vector<int32_t> morton_order(std::span<const double> position);
// The low 21 bits of v spread to every third bit (a coordinate's share of a Morton key).
uint64_t morton_spread(uint64_t v);

}  // namespace breccia::solver
