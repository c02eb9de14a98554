#pragma once
// Particle contact of the stress solid as one thread per particle (the CUDA launcher,
// mps_solid_cuda.cu, and its host emulation in the tests): a hashed cell grid on the current
// positions, then each particle gathers its contact partners and sums the pair forces itself.
// Contact::pair_forces (contact.cpp) visits each pair once instead (i < j, +f on i, -f on j);
// the gather below reproduces its sums to the bit, because
//   - the partners are the same set (unbonded, closer than the search radius), and
//   - a particle's contributions arrive in ascending partner order in both: the CPU's pair
//     list is sorted by (i, j), so particle p meets its pairs (a, p), a < p, before (p, b),
//     and each pair's force is computed from (min, max) with the same arithmetic.
// The grid is hashed (cell coordinates to a fixed number of buckets), so a particle flung far
// away costs nothing; two cells in one bucket only add candidates, which the cell test drops.
#include <cmath>

#include "breccia/common/hashed_grid.hpp"
#include "breccia/mps/contact_kernels.hpp"
#include "breccia/mps/kernels.hpp"

namespace breccia::mps {

// The pair law of contact.particles (contact.hpp ParticleContact) as plain values.
struct PairContactParams {
  double distance_m = 0.0, window_m = 0.0, stiffness_n_m = 0.0;
  int distribution = 0;  // 1: neighbour-distribution normal, 0: pair direction
};

// Geometry of the pair (i, j), i < j, dx = x_i - x_j; m_i, m_j the surface directions (used
// with the distribution normal only).
BRECCIA_HD inline PairContactGeometry pair_contact_geometry(const double dx[3], const double* m_i, const double* m_j,
                                                            const PairContactParams& p) {
  if (!p.distribution) return pair_direction_geometry(dx, p.distance_m);
  return distribution_normal_geometry(dx, m_i, m_j, p.distance_m, p.window_m);
}

// Search radius: the contact distance, or with the distribution normal the planar pairs'
// reach one window sideways (as Contact::pair_candidates).
BRECCIA_HD inline double pair_search_radius(const PairContactParams& p) {
  return p.distribution ? std::hypot(p.distance_m, p.window_m) : p.distance_m;
}

struct ContactGrid {
  double cell_m = 0.0;            // cell edge (the search radius)
  unsigned long long buckets = 1; // a power of two
  int dimension = 2;
  const long long* cell = nullptr;  // 3 per particle: its cell coordinates
  const int* start = nullptr;       // buckets + 1 offsets into order
  const int* order = nullptr;       // particle indices by bucket
};

using breccia::grid_bucket;   // common/include/breccia/common/hashed_grid.hpp
using breccia::grid_visit_neighbours;
using breccia::grid_cell_of;

// Particle p's contact partners: every j != p closer than `reach` (x: 3N current positions,
// z = 0 in 2D) that p is not bonded to now (a bond of nonzero weight), in ascending order.
// Returns their number, or -1 when more than `capacity` were found.
BRECCIA_HD inline int contact_partners_at(long long p, const ContactGrid& g, const double* x, BondsView b, double reach,
                                          int* partners, int capacity) {
  int count = 0;
  const int reach_z = g.dimension == 3 ? 1 : 0;
  const bool all = grid_visit_neighbours(p, g.cell, g.buckets, g.start, g.order, reach_z, [&](long long l) {
    const int j = static_cast<int>(l);
    const double dx[3] = {x[3 * p] - x[3 * j], x[3 * p + 1] - x[3 * j + 1], x[3 * p + 2] - x[3 * j + 2]};
    if (dx[0] * dx[0] + dx[1] * dx[1] + dx[2] * dx[2] >= reach * reach) return true;
    bool bonded = false;
    for (long long m = b.offset[p]; m < b.offset[p + 1] && !bonded; ++m)
      bonded = b.neighbour[m] == j && b.weight[m] != 0.0;
    if (bonded) return true;
    if (count == capacity) return false;
    int k = count++;  // insertion in ascending order
    while (k > 0 && partners[k - 1] > j) {
      partners[k] = partners[k - 1];
      --k;
    }
    partners[k] = j;
    return true;
  });
  return all ? count : -1;
}

// The contact force on p from its partners (ascending), as Contact::pair_forces sums it:
// each pair's force from (min, max), +f on the smaller index, -f on the larger, pairs out of
// contact skipped. *pairs counts the pairs in contact that p is the smaller index of.
BRECCIA_HD inline void particle_contact_force_at(long long p, const int* partners, int count, const double* x,
                                                 const double* surface, const PairContactParams& params, double sum[3],
                                                 long long* pairs) {
  for (int k = 0; k < count; ++k) {
    const long long q = partners[k];
    const long long lo = p < q ? p : q, hi = p < q ? q : p;
    const double dx[3] = {x[3 * lo] - x[3 * hi], x[3 * lo + 1] - x[3 * hi + 1], x[3 * lo + 2] - x[3 * hi + 2]};
    const PairContactGeometry g = pair_contact_geometry(dx, surface ? &surface[3 * lo] : nullptr,
                                                        surface ? &surface[3 * hi] : nullptr, params);
    double f[3] = {0.0, 0.0, 0.0}, normal_force = 0.0;
    pair_normal_force(g, params.stiffness_n_m, f, &normal_force);
    if (normal_force <= 0.0) continue;
    if (p == lo) {
      ++*pairs;
      for (int a = 0; a < 3; ++a) sum[a] += f[a];
    } else {
      for (int a = 0; a < 3; ++a) sum[a] -= f[a];
    }
  }
}

}  // namespace breccia::mps
