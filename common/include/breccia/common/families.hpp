#pragma once
// Peridynamic families (bonds): for each particle i, every j != i whose reference distance is
// within reach(i, j) = max(horizon_i, horizon_j) + max(pad_i, pad_j). Full lists (each
// pair appears from both ends) so a particle sums its own force without atomics.
// Built with cell lists (cell_list.hpp) per reach class (horizons in octaves; cells of half
// the class's largest reach), each row searching every j within the pair's reach (both ends'
// test): O(N) for bounded density contrast, about the same cells scanned per row whatever
// its horizon. Shared by the solver (set-up, breccia-plan's bond counts) and
// post-processing (the bond list of results.h5 and its fragment graph), so that both see
// the same bonds in the same order.
// The search is written as per-index kernels (family_kernels.hpp) that family_build.hpp
// launches through any execution space: the CUDA backend's set-up builds these same arrays on
// the device (solver/cuda/src/cuda_families.cu).
#include <cstdint>
#include <span>
#include <vector>

namespace breccia {

struct Families {
  std::vector<int64_t> offsets;   // N + 1
  std::vector<int32_t> neighbors; // offsets[N], sorted ascending within a family
  size_t particle_count() const { return offsets.empty() ? 0 : offsets.size() - 1; }
  size_t bond_count() const { return neighbors.size(); }
};

// position: 3N (x, y, z interleaved); horizon_m, pad_m: N (pad may be empty = 0).
// The pad lets partial-volume rules include neighbours whose cell straddles the horizon.
// rows [row_begin, row_end) only (default: all): the other rows are left empty, so a
// distributed set-up builds the families of the particles it owns alone: the same rows, in
// the same order, as the whole build's.
Families build_families(std::span<const double> position, std::span<const double> horizon_m,
                        std::span<const double> pad_m = {}, int64_t row_begin = 0, int64_t row_end = -1);

// Whether build_families takes its rows from a uniform lattice's offsets (one horizon, one
// pad, at most one point per site of a lattice of one spacing) rather than a cell search: the
// same rows either way; this says which path a test exercised.
bool families_on_lattice(std::span<const double> position, std::span<const double> horizon_m,
                         std::span<const double> pad_m = {});

}  // namespace breccia
