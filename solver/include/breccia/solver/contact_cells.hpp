#pragma once
// Particles close in the current configuration that are not family members: the short-range
// forces' second half (model.short_range_forces; LAMMPS PERI applies its contact term to every
// pair of its neighbour list, so fragments that meet repel). A hashed cell grid on the current
// positions, rebuilt every force pass (a counting sort, O(N): cell_list.hpp's group_by_key);
// each particle gathers its own partners, so the kernel writes only its own force (no
// atomics, any thread count gives the same sums: partners are visited in a fixed cell
// order, then ascending within a cell). The cell and bucket arithmetic is the hashed grid's
// (common/hashed_grid.hpp), shared with MPS.
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "breccia/common/cell_list.hpp"
#include "breccia/common/hashed_grid.hpp"
#include "breccia/solver/pd_kernels.hpp"

namespace breccia::solver {

struct ContactCellsView {
  double cell = 0.0;                    // cell edge [m]: the largest reach
  unsigned long long buckets = 1;       // a power of two
  const long long* cell_of = nullptr;   // 3 per particle: its cell coordinates
  const int64_t* start = nullptr;       // buckets + 1 offsets into order
  const int32_t* order = nullptr;       // particle indices by bucket, ascending within one
  // Null: the families' partners are particle indices. Else the order key of each index (a
  // rank's local indices -> their global ones, in which the rows are sorted).
  const int32_t* key = nullptr;
};

// Is j in i's family? CSR rows are sorted ascending (family.cpp), so a binary search, over
// the keys when given (a rank's rows hold local indices, whose ghosts do not follow the
// owned particles' global order: the rows are sorted by the global indices).
template <class Real>
BRECCIA_HD bool family_member(const PdViewT<Real>& p, int64_t i, int64_t j, const int32_t* key = nullptr) {
  const int64_t want = key ? key[j] : j;
  int64_t lo = p.offsets[i], hi = p.offsets[i + 1];
  while (lo < hi) {
    const int64_t mid = lo + (hi - lo) / 2;
    const int64_t v = key ? key[p.neighbor[mid]] : p.neighbor[mid];
    if (v == want) return true;
    if (v < want) lo = mid + 1;
    else hi = mid;
  }
  return false;
}

// The short-range force on i from the particles that are not its family members and are
// closer than 1.35 x their mean spacing (for them 0.9 |xi| > 1.35 l always: |xi| exceeds the
// horizon). The same law as short_range_kernel, adding to force and energy density.
template <class Real>
BRECCIA_HD void short_range_contact_kernel(const PdViewT<Real>& p, const ContactCellsView& g, int64_t i) {
  const BondOriginT<Real> origin(p, i);
  const Real l_i = p.spacing[i];
  Real fx = Real(0), fy = Real(0), fz = Real(0);
  double w = 0.0;
  grid_visit_neighbours(i, g.cell_of, g.buckets, g.start, g.order, 1, [&](int64_t j) {
    Real dx, dy, dz, len;
    origin.to(p, j, Real(0), dx, dy, dz, len);
    const Real reach = Real(0.675) * (l_i + p.spacing[j]);
    if (!(len < reach) || !(len > Real(0)) || family_member(p, i, j, g.key)) return true;
    add_short_range_pair(p, i, j, reach, dx, dy, dz, len, fx, fy, fz, w);
    return true;
  });
  p.force[3 * i] += fx;
  p.force[3 * i + 1] += fy;
  p.force[3 * i + 2] += fz;
  if (p.diagnostics) p.energy_density[i] += w;
}

// The grid's storage, built on the host from double positions.
struct ContactCells {
  double cell = 0.0;
  unsigned long long buckets = 1;
  std::vector<long long> cell_of;
  std::vector<int64_t> start;
  std::vector<int32_t> order;
  const int32_t* key = nullptr;  // ContactCellsView::key (held by the caller)

  // x: 3N current positions; cell: the largest reach.
  void build(const double* x, int64_t n, double cell_edge) { build(x, n, cell_edge, {}, nullptr); }

  // The grid over the particles `members` only (indices below n, listed in the order a
  // bucket must hold them; empty: every particle 0 ... n-1 in index order). A distributed run
  // (solver/mpi/) lists its owned particles and the other ranks' within reach, in global
  // order, so each cell is walked in one process's order: the same partners, summed in the
  // same order. `family_key`: ContactCellsView::key (null: none).
  void build(const double* x, int64_t n, double cell_edge, std::span<const int32_t> members,
             const int32_t* family_key) {
    cell = cell_edge;
    key = family_key;
    const int64_t count = members.empty() ? n : static_cast<int64_t>(members.size());
    buckets = 1;
    while (buckets < static_cast<unsigned long long>(2 * count)) buckets <<= 1;
    cell_of.resize(3 * static_cast<size_t>(n));
    std::vector<unsigned long long> bucket(static_cast<size_t>(count));
    for (int64_t q = 0; q < count; ++q) {
      const int64_t i = members.empty() ? q : members[q];
      grid_cell_of(&x[3 * i], cell, 3, &cell_of[3 * i]);  // 2D: z = 0, cell 0
      bucket[q] = grid_bucket(&cell_of[3 * i], buckets);
    }
    group_by_key(std::span<const unsigned long long>(bucket), static_cast<size_t>(buckets), start, order);
    if (!members.empty())
      for (int32_t& q : order) q = members[q];  // positions in `members` (ascending) -> particles
  }
  ContactCellsView view() const { return {cell, buckets, cell_of.data(), start.data(), order.data(), key}; }
};

}  // namespace breccia::solver
