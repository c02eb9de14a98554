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
};

// Is j in i's family? CSR rows are sorted ascending (family.cpp), so a binary search.
template <class Real>
BRECCIA_HD bool family_member(const PdViewT<Real>& p, int64_t i, int64_t j) {
  int64_t lo = p.offsets[i], hi = p.offsets[i + 1];
  while (lo < hi) {
    const int64_t mid = lo + (hi - lo) / 2;
    const int64_t v = p.neighbor[mid];
    if (v == j) return true;
    if (v < j) lo = mid + 1;
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
  const long long* ci = &g.cell_of[3 * i];
  const Real l_i = p.spacing[i];
  Real fx = Real(0), fy = Real(0), fz = Real(0);
  double w = 0.0;
  for (long long oz = -1; oz <= 1; ++oz)
    for (long long oy = -1; oy <= 1; ++oy)
      for (long long ox = -1; ox <= 1; ++ox) {
        const long long c[3] = {ci[0] + ox, ci[1] + oy, ci[2] + oz};
        const unsigned long long b = grid_bucket(c, g.buckets);
        for (int64_t q = g.start[b]; q < g.start[b + 1]; ++q) {
          const int64_t j = g.order[q];
          const long long* cj = &g.cell_of[3 * j];
          if (j == i || cj[0] != c[0] || cj[1] != c[1] || cj[2] != c[2]) continue;
          Real dx, dy, dz, len;
          origin.to(p, j, Real(0), dx, dy, dz, len);
          const Real reach = Real(0.675) * (l_i + p.spacing[j]);
          if (!(len < reach) || !(len > Real(0)) || family_member(p, i, j)) continue;
          add_short_range_pair(p, i, j, reach, dx, dy, dz, len, fx, fy, fz, w);
        }
      }
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

  // x: 3N current positions; cell: the largest reach.
  void build(const double* x, int64_t n, double cell_edge) {
    cell = cell_edge;
    buckets = 1;
    while (buckets < static_cast<unsigned long long>(2 * n)) buckets <<= 1;
    cell_of.resize(3 * static_cast<size_t>(n));
    std::vector<unsigned long long> bucket(static_cast<size_t>(n));
    for (int64_t i = 0; i < n; ++i) {
      grid_cell_of(&x[3 * i], cell, 3, &cell_of[3 * i]);  // 2D: z = 0, cell 0
      bucket[i] = grid_bucket(&cell_of[3 * i], buckets);
    }
    group_by_key(std::span<const unsigned long long>(bucket), static_cast<size_t>(buckets), start, order);
  }
  ContactCellsView view() const { return {cell, buckets, cell_of.data(), start.data(), order.data()}; }
};

}  // namespace breccia::solver
