#pragma once
// The dense uniform cell list every neighbour search over a bounded set of points shares:
// the grid's arithmetic (cell of a point, index of a cell) and the particles sorted by cell
// (a counting sort, so each cell lists its particles in ascending index and a search visits
// them in the same order on every run). Users: the bond families (families.hpp), MPS bonds
// (solver/mps/src/neighbours.cpp, periodic axes) and MPS pair contact (contact.cpp), and
// post-processing's crack-plane fit (postproc/src/cracks.cpp, the grid only). Each sizes its
// own grid (cells of the search radius or larger, a cap on the cell count, ...), so the
// sizing stays with them; what a cell holds and how a cell is found is written here once.
//
// Searches over positions that move every step without bound (PD short-range contact, MPS
// particle contact on host and GPU) use the hashed grid instead (hashed_grid.hpp): a fixed
// number of buckets, so a particle flung far away does not grow the grid. Both sort their
// particles with group_by_key below.
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#if defined(__CUDACC__)
#define BRECCIA_CELL_HD __host__ __device__
#else
#define BRECCIA_CELL_HD
#endif

namespace breccia {

// floor((v - origin) / cell) clamped into [0, count - 1]: a point's cell coordinate on one
// axis (a point outside the grid's box counts in the nearest cell). Callable from device code
// too: the bond families' row kernels (family_kernels.hpp) bin and search with it, so host
// and GPU put every point in the same cell.
BRECCIA_CELL_HD inline long long cell_coordinate(double v, double origin, double cell, long long count) {
  const long long c = static_cast<long long>(std::floor((v - origin) / cell));
  return c < 0 ? 0 : (c > count - 1 ? count - 1 : c);
}

// The indices 0 ... N-1 grouped by key (key[i] < key_count), ascending within a key (a
// counting sort): key k holds members[start[k]] ... members[start[k + 1] - 1].
template <class Key>
void group_by_key(std::span<const Key> key, size_t key_count, std::vector<int64_t>& start,
                  std::vector<int32_t>& members) {
  const size_t n = key.size();
  start.assign(key_count + 1, 0);
  for (size_t i = 0; i < n; ++i) ++start[static_cast<size_t>(key[i]) + 1];
  for (size_t k = 0; k < key_count; ++k) start[k + 1] += start[k];
  members.resize(n);
  std::vector<int64_t> fill(start.begin(), start.end() - 1);
  for (size_t i = 0; i < n; ++i) members[static_cast<size_t>(fill[static_cast<size_t>(key[i])]++)] = static_cast<int32_t>(i);
}

struct BoundingBox {
  double lo[3], hi[3];
};
// The smallest box holding every point of position (3N, x y z interleaved); for N = 0,
// lo = +1e300 and hi = -1e300.
BoundingBox bounding_box(std::span<const double> position);

struct CellGrid {
  double origin[3] = {0.0, 0.0, 0.0};
  double cell[3] = {1.0, 1.0, 1.0};  // edge of a cell on each axis
  long long count[3] = {1, 1, 1};    // cells on each axis

  // Cells of edge `cell` on every axis from box.lo, as many as cover the box:
  // floor(extent / cell) + 1 per axis.
  static CellGrid covering(const BoundingBox& box, double cell);

  long long cells() const { return count[0] * count[1] * count[2]; }
  // floor((v - origin) / cell) on `axis`, clamped into the grid (a point outside the
  // grid's box counts in the nearest cell).
  long long coordinate(int axis, double v) const { return cell_coordinate(v, origin[axis], cell[axis], count[axis]); }
  long long index(long long cx, long long cy, long long cz) const { return (cz * count[1] + cy) * count[0] + cx; }
  long long index_of(const double x[3]) const {
    return index(coordinate(0, x[0]), coordinate(1, x[1]), coordinate(2, x[2]));
  }
};

// Particles sorted by cell: cell c holds members[start[c]] ... members[start[c + 1] - 1],
// in ascending particle index.
struct CellList {
  CellGrid grid;
  std::vector<int64_t> start;    // grid.cells() + 1
  std::vector<int32_t> members;  // N
};
CellList sort_into_cells(const CellGrid& grid, std::span<const double> position);

}  // namespace breccia

#undef BRECCIA_CELL_HD
