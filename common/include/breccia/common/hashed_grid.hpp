#pragma once
// The hashed cell grid's arithmetic and its walk over a particle's neighbour cells, shared by
// every contact search that runs on it: PD's short-range forces
// (solver/include/breccia/solver/contact_cells.hpp) and MPS particle contact
// (solver/mps/include/breccia/mps/contact_grid.hpp, host and CUDA). Cell
// coordinates hash into a power-of-two number of buckets, so a particle flung far away costs
// nothing; two cells sharing a bucket only add candidates, which the cell test drops.
// Callable from host and device code (the callers' own BRECCIA_HD macros differ, so these
// spell out their qualifiers).
#include <cmath>

#if defined(__CUDACC__)
#define BRECCIA_GRID_HD __host__ __device__
#else
#define BRECCIA_GRID_HD
#endif

namespace breccia {

// The cell of position x: floor(x / cell) on the first `dimension` axes, 0 beyond.
BRECCIA_GRID_HD inline void grid_cell_of(const double x[3], double cell_m, int dimension, long long c[3]) {
  for (int a = 0; a < 3; ++a) c[a] = a < dimension ? static_cast<long long>(std::floor(x[a] / cell_m)) : 0;
}

BRECCIA_GRID_HD inline unsigned long long grid_bucket(const long long c[3], unsigned long long buckets) {
  const unsigned long long h = static_cast<unsigned long long>(c[0]) * 73856093ull ^
                               static_cast<unsigned long long>(c[1]) * 19349663ull ^
                               static_cast<unsigned long long>(c[2]) * 83492791ull;
  return (h ^ (h >> 29)) & (buckets - 1);
}

// The walk every contact search makes: the particles in particle i's cell and its neighbours
// (3 x 3 x 3 cells, or 3 x 3 with reach_z = 0), cell by cell in a fixed order and within a
// cell in the order `order` holds them, calling visit(j) for each j != i (the other cells of
// a shared bucket dropped). cell_of: 3 cell coordinates per particle; start: buckets + 1
// offsets into order. visit returns false to stop; returns whether the walk ran to its end.
template <class Offset, class Index, class Visit>
BRECCIA_GRID_HD inline bool grid_visit_neighbours(long long i, const long long* cell_of, unsigned long long buckets,
                                                  const Offset* start, const Index* order, int reach_z,
                                                  Visit&& visit) {
  const long long* ci = &cell_of[3 * i];
  for (long long oz = -reach_z; oz <= reach_z; ++oz)
    for (long long oy = -1; oy <= 1; ++oy)
      for (long long ox = -1; ox <= 1; ++ox) {
        const long long c[3] = {ci[0] + ox, ci[1] + oy, ci[2] + oz};
        const unsigned long long b = grid_bucket(c, buckets);
        for (Offset q = start[b]; q < start[b + 1]; ++q) {
          const long long j = order[q];
          const long long* cj = &cell_of[3 * j];
          if (j == i || cj[0] != c[0] || cj[1] != c[1] || cj[2] != c[2]) continue;  // another cell in this bucket
          if (!visit(j)) return false;
        }
      }
  return true;
}

}  // namespace breccia

#undef BRECCIA_GRID_HD
