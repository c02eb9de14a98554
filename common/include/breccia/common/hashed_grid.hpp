#pragma once
// The hashed cell grid's two pieces of arithmetic, shared by every contact search that runs
// on it: PD's short-range forces (solver/include/breccia/solver/contact_cells.hpp) and MPS
// particle contact (solver/mps/include/breccia/mps/contact_grid.hpp, host and CUDA). Cell
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

}  // namespace breccia

#undef BRECCIA_GRID_HD
