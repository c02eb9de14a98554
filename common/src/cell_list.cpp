#include "breccia/common/cell_list.hpp"

#include <algorithm>
#include <cmath>

namespace breccia {

BoundingBox bounding_box(std::span<const double> x) {
  BoundingBox b{{1e300, 1e300, 1e300}, {-1e300, -1e300, -1e300}};
  const size_t n = x.size() / 3;
  for (size_t i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d) {
      b.lo[d] = std::min(b.lo[d], x[3 * i + d]);
      b.hi[d] = std::max(b.hi[d], x[3 * i + d]);
    }
  return b;
}

CellGrid CellGrid::covering(const BoundingBox& box, double cell) {
  CellGrid g;
  for (int d = 0; d < 3; ++d) {
    g.origin[d] = box.lo[d];
    g.cell[d] = cell;
    g.count[d] = std::max<long long>(1, static_cast<long long>(std::floor((box.hi[d] - box.lo[d]) / cell)) + 1);
  }
  return g;
}

CellList sort_into_cells(const CellGrid& grid, std::span<const double> x) {
  const size_t n = x.size() / 3;
  CellList list;
  list.grid = grid;
  std::vector<long long> cell_of(n);
  for (size_t i = 0; i < n; ++i) cell_of[i] = grid.index_of(&x[3 * i]);
  group_by_key(std::span<const long long>(cell_of), static_cast<size_t>(grid.cells()), list.start, list.members);
  return list;
}

}  // namespace breccia
