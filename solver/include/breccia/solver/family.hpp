#pragma once
// The bond families (build_families) live in common/ (families.hpp), shared with
// post-processing; the solver's code names them as its own. Morton order is the solver's.
#include <cstdint>
#include <span>
#include <vector>

#include "breccia/common/cell_list.hpp"
#include "breccia/common/families.hpp"

namespace breccia::solver {

using breccia::build_families;
using breccia::Families;

// Permutation that sorts particles along a Morton (Z-order) curve: new index k holds old
// particle order[k]. Neighbouring particles end up close in memory.
std::vector<int32_t> morton_order(std::span<const double> position);
// The Morton key of position p (3 values) in `box`, the bounding box of every particle, and
// its longest side (morton_extent): morton_order's keys, the one expression for both the
// whole body's sort and the ranks' (distributed_morton_sort, distributed_setup.hpp).
double morton_extent(const BoundingBox& box);
uint64_t morton_key(const double* p, const BoundingBox& box, double extent);
// The low 21 bits of v spread to every third bit (a coordinate's share of a Morton key).
uint64_t morton_spread(uint64_t v);

}  // namespace breccia::solver
