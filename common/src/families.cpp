#include "breccia/common/families.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "breccia/common/cell_list.hpp"
#include "breccia/common/huge_pages.hpp"

#if defined(_OPENMP)
#include <omp.h>
#endif

namespace breccia {

Families build_families(std::span<const double> x, std::span<const double> horizon,
                        std::span<const double> pad, int64_t row_begin, int64_t row_end) {
  const size_t n = horizon.size();
  if (x.size() != 3 * n) throw std::invalid_argument("build_families: position must be 3N");
  if (row_end < 0) row_end = static_cast<int64_t>(n);
  if (row_begin < 0 || row_begin > row_end || row_end > static_cast<int64_t>(n))
    throw std::invalid_argument("build_families: rows outside [0, N]");
  Families fam;
  fam.offsets.assign(n + 1, 0);
  if (n == 0) return fam;
  auto pad_of = [&](size_t i) { return pad.empty() ? 0.0 : pad[i]; };
  double max_pad = 0.0, min_horizon = horizon[0], max_horizon = horizon[0];
  for (size_t i = 0; i < n; ++i) {
    max_pad = std::max(max_pad, pad_of(i));
    min_horizon = std::min(min_horizon, horizon[i]);
    max_horizon = std::max(max_horizon, horizon[i]);
  }
  const bool uniform = min_horizon == max_horizon;
  const bool all_rows = row_begin == 0 && row_end == static_cast<int64_t>(n);
  // A row range with several horizons cannot take the transpose (it reads every row): each
  // of its rows searches the largest reach instead and keeps j when either end's own test
  // holds. Both tests read the same r2 (x_i - x_j = -(x_j - x_i) exactly), so the row is the
  // merged union's, bit for bit.
  const bool both_ends = !uniform && !all_rows;
  // reach(i, j) = max(h_i, h_j) + max(p_i, p_j) is the larger of the two "own" reaches
  // h_i + max(p_i, p_j) and h_j + max(p_i, p_j). Each particle searches its own reach; the
  // family is the union of what i found and what found i. With one horizon the own lists
  // are already symmetric. Cells are sized to half the smallest reach (at least 1/8 of the
  // largest reach), so a fine region of a graded mesh with a 3x smaller horizon does not scan
  // cells sized for the coarse one (that made a 291k-particle dual-horizon family build
  // take a minute).
  const double max_reach = max_horizon + max_pad;
  // Cells of half the smallest reach: a search scans (2 ring + 1)^3 cells, and halving the
  // cell roughly halves the scanned volume around the reach's sphere (27 reach^3 with cells of
  // one reach, 15.6 with half), and cells wholly beyond the reach are skipped by their box.
  const double cell = std::max({0.5 * (min_horizon + max_pad), max_reach / 8.0, 1e-300});
  const CellList cells = sort_into_cells(CellGrid::covering(bounding_box(x), cell), x);
  const CellGrid& grid = cells.grid;
  // The search reads each candidate's position, pad and horizon: copies in cell order
  // (sorted[k] for cells.members[k]) turn its gathers into reads of consecutive memory.
  // The same values, so the same tests and lists.
  struct Candidate {
    double x[3];
    double pad, horizon;
    int32_t index;
  };
  std::vector<Candidate> sorted(cells.members.size());
#pragma omp parallel for schedule(static)
  for (int64_t k = 0; k < static_cast<int64_t>(sorted.size()); ++k) {
    const size_t j = static_cast<size_t>(cells.members[static_cast<size_t>(k)]);
    sorted[static_cast<size_t>(k)] = {{x[3 * j], x[3 * j + 1], x[3 * j + 2]}, pad_of(j), horizon[j], static_cast<int32_t>(j)};
  }
  // The largest pad in each cell: a cell is searched only as far as its own particles'
  // pads reach. On a graded mesh the largest pad is a coarse particle's, several times a
  // fine one's, and fine particles (most of them) searched a sphere of twice their reach:
  // the full concrete case tested 281 million candidates for 70 million entries, 145
  // million with this bound. The same lists: every skipped j lies beyond its own reach.
  std::vector<double> cell_pad;
  if (max_pad > 0.0) {
    cell_pad.assign(static_cast<size_t>(grid.cells()), 0.0);
#pragma omp parallel for schedule(static)
    for (long long c = 0; c < grid.cells(); ++c)
      for (int64_t k = cells.start[c]; k < cells.start[c + 1]; ++k)
        cell_pad[static_cast<size_t>(c)] = std::max(cell_pad[static_cast<size_t>(c)], sorted[static_cast<size_t>(k)].pad);
  }
  // Own search of particle i: every j within h_i + max(p_i, p_j).
  auto visit = [&](size_t i, auto&& emit) {
    long long ci[3];
    for (int d = 0; d < 3; ++d) ci[d] = grid.coordinate(d, x[3 * i + d]);
    const double reach_base = both_ends ? max_horizon : horizon[i];
    const double search = reach_base + max_pad;
    const long long ring = static_cast<long long>(std::ceil(search / cell));
    // A cell is skipped when its box lies beyond the search radius (with a margin for the
    // rounding of a point's cell coordinate, so that no neighbour is ever lost).
    const double skip2 = (search + 1e-9 * cell) * (search + 1e-9 * cell);
    const double xi[3] = {x[3 * i], x[3 * i + 1], x[3 * i + 2]};
    const double pad_i = pad_of(i), horizon_i = horizon[i];
    auto gap = [&](int d, long long a) {
      const double lo = grid.origin[d] + static_cast<double>(a) * grid.cell[d], hi = lo + grid.cell[d];
      const double v = x[3 * i + d];
      return v < lo ? lo - v : (v > hi ? v - hi : 0.0);
    };
    for (long long az = std::max(0LL, ci[2] - ring); az <= std::min(grid.count[2] - 1, ci[2] + ring); ++az) {
      const double gz = gap(2, az);
      if (gz * gz > skip2) continue;
      for (long long ay = std::max(0LL, ci[1] - ring); ay <= std::min(grid.count[1] - 1, ci[1] + ring); ++ay) {
        const double gy = gap(1, ay);
        if (gz * gz + gy * gy > skip2) continue;
        for (long long ax = std::max(0LL, ci[0] - ring); ax <= std::min(grid.count[0] - 1, ci[0] + ring); ++ax) {
          const double gx = gap(0, ax);
          if (gz * gz + gy * gy + gx * gx > skip2) continue;
          const long long c = grid.index(ax, ay, az);
          if (!cell_pad.empty()) {  // this cell's own reach (the same margin)
            const double cell_search = reach_base + std::max(pad_i, cell_pad[static_cast<size_t>(c)]) + 1e-9 * cell;
            if (gz * gz + gy * gy + gx * gx > cell_search * cell_search) continue;
          }
          for (int64_t k = cells.start[c]; k < cells.start[c + 1]; ++k) {
            const Candidate& cj = sorted[static_cast<size_t>(k)];
            const size_t j = static_cast<size_t>(cj.index);
            if (j == i) continue;
            const double p = std::max(pad_i, cj.pad);
            const double reach = horizon_i + p;
            double r2 = 0.0;
            for (int d = 0; d < 3; ++d) {
              const double e = cj.x[d] - xi[d];
              r2 += e * e;
            }
            const double reach_j = cj.horizon + p;  // j's own test of i (both_ends only)
            if (r2 <= reach * reach || (both_ends && r2 <= reach_j * reach_j)) emit(j);
          }
        }
      }
    }
  };
  // One search per particle: each block of particles fills a buffer of its own (sorted per
  // particle), then the buffers are copied into place. The buffers hold what the list will,
  // so the peak stays below the three lists of the merge further below.
  Families own;
  own.offsets.assign(n + 1, 0);
  {
    constexpr size_t block = 512;
    const size_t blocks = (n + block - 1) / block;
    std::vector<std::vector<int32_t>> found(blocks);
    std::vector<int64_t> count(n, 0);
#pragma omp parallel for schedule(dynamic, 4)
    for (size_t b = 0; b < blocks; ++b) {
      std::vector<int32_t>& list = found[b];
      for (size_t i = b * block; i < std::min(n, (b + 1) * block); ++i) {
        if (static_cast<int64_t>(i) < row_begin || static_cast<int64_t>(i) >= row_end) continue;  // left empty
        const size_t first = list.size();
        visit(i, [&](size_t j) { list.push_back(static_cast<int32_t>(j)); });
        std::sort(list.begin() + static_cast<std::ptrdiff_t>(first), list.end());
        count[i] = static_cast<int64_t>(list.size() - first);
      }
    }
    for (size_t i = 0; i < n; ++i) own.offsets[i + 1] = own.offsets[i] + count[i];
    assign_on_huge_pages(own.neighbors, static_cast<size_t>(own.offsets[n]));
#pragma omp parallel for schedule(dynamic, 4)
    for (size_t b = 0; b < blocks; ++b) {
      std::copy(found[b].begin(), found[b].end(), own.neighbors.begin() + own.offsets[b * block]);
      std::vector<int32_t>().swap(found[b]);
    }
  }
  if (uniform || both_ends) return own;
  // Transpose (who found i), each list in ascending i, so it comes out sorted. A counting
  // sort by column over row chunks: chunk c counts its columns, its entries of column j go
  // after those of the chunks before it, and each chunk fills in ascending i, so every list
  // holds what one pass in ascending i would write, in the same order, with the chunks
  // filled side by side (the scatter over the whole list is what costs). The chunks'
  // counts take chunks x N x 4 bytes, so their number stays small.
  const size_t own_entries = own.neighbors.size();
#if defined(_OPENMP)
  const size_t chunks = static_cast<size_t>(std::clamp(omp_get_max_threads(), 1, 8));
#else
  const size_t chunks = 1;
#endif
  std::vector<size_t> chunk_row(chunks + 1, n);  // rows [chunk_row[c], chunk_row[c + 1]): about equal entries
  chunk_row[0] = 0;
  for (size_t c = 1; c < chunks; ++c) {
    const int64_t target = static_cast<int64_t>(own_entries * c / chunks);
    chunk_row[c] = static_cast<size_t>(std::lower_bound(own.offsets.begin(), own.offsets.end(), target) - own.offsets.begin());
    chunk_row[c] = std::clamp(chunk_row[c], chunk_row[c - 1], n);
  }
  std::vector<std::vector<int32_t>> place(chunks);  // per chunk: count of column j, then its place within j's list
#pragma omp parallel for schedule(static, 1)
  for (size_t c = 0; c < chunks; ++c) {
    place[c].assign(n, 0);
    for (int64_t k = own.offsets[chunk_row[c]]; k < own.offsets[chunk_row[c + 1]]; ++k) ++place[c][static_cast<size_t>(own.neighbors[k])];
  }
  std::vector<int64_t> t_offsets(n + 1, 0);
  for (size_t j = 0; j < n; ++j) {
    int32_t before = 0;
    for (size_t c = 0; c < chunks; ++c) {
      const int32_t count = place[c][j];
      place[c][j] = before;
      before += count;
    }
    t_offsets[j + 1] = t_offsets[j] + before;
  }
  std::vector<int32_t> t_neighbors;
  assign_on_huge_pages(t_neighbors, own_entries);
#pragma omp parallel for schedule(static, 1)
  for (size_t c = 0; c < chunks; ++c) {
    std::vector<int32_t>& at = place[c];
    for (size_t i = chunk_row[c]; i < chunk_row[c + 1]; ++i)
      for (int64_t k = own.offsets[i]; k < own.offsets[i + 1]; ++k) {
        const size_t j = static_cast<size_t>(own.neighbors[k]);
        t_neighbors[static_cast<size_t>(t_offsets[j]) + static_cast<size_t>(at[j]++)] = static_cast<int32_t>(i);
      }
    std::vector<int32_t>().swap(at);
  }
  auto merged = [&](size_t i, auto&& emit) {
    int64_t a = own.offsets[i], b = t_offsets[i];
    const int64_t ae = own.offsets[i + 1], be = t_offsets[i + 1];
    while (a < ae || b < be) {
      int32_t v;
      if (b >= be || (a < ae && own.neighbors[a] < t_neighbors[b])) v = own.neighbors[a++];
      else if (a >= ae || t_neighbors[b] < own.neighbors[a]) v = t_neighbors[b++];
      else {
        v = own.neighbors[a++];
        ++b;
      }
      emit(v);
    }
  };
  {
    std::vector<int64_t> count(n, 0);
#pragma omp parallel for schedule(dynamic, 256)
    for (size_t i = 0; i < n; ++i) {
      int64_t c = 0;
      merged(i, [&](int32_t) { ++c; });
      count[i] = c;
    }
    for (size_t i = 0; i < n; ++i) fam.offsets[i + 1] = fam.offsets[i] + count[i];
  }
  assign_on_huge_pages(fam.neighbors, static_cast<size_t>(fam.offsets[n]));
#pragma omp parallel for schedule(dynamic, 256)
  for (size_t i = 0; i < n; ++i) {
    int64_t k = fam.offsets[i];
    merged(i, [&](int32_t v) { fam.neighbors[k++] = v; });
  }
  return fam;
}

}  // namespace breccia
