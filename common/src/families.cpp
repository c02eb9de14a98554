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

namespace {

// One cell list of a subset of the particles, with copies of what the search reads in cell
// order (sorted[k] for members[k]: consecutive reads instead of gathers) and, per cell, the
// largest horizon and pad of its particles (a cell is searched only as far as they reach).
struct ReachGrid {
  CellList cells;
  struct Candidate {
    double x[3];
    double pad, horizon;
    int32_t index;
  };
  std::vector<Candidate> sorted;
  std::vector<double> cell_horizon, cell_pad;
  double max_horizon = 0.0, max_pad = 0.0;  // over the grid's particles
};

// The grid of the particles `subset` (ascending) with cells of edge `cell` over `box`.
ReachGrid make_grid(std::span<const double> x, std::span<const double> horizon, std::span<const double> pad,
                    const std::vector<int32_t>& subset, const BoundingBox& box, double cell) {
  ReachGrid g;
  const CellGrid grid = CellGrid::covering(box, cell);
  std::vector<long long> cell_of(subset.size());
  for (size_t k = 0; k < subset.size(); ++k) cell_of[k] = grid.index_of(&x[3 * static_cast<size_t>(subset[k])]);
  g.cells.grid = grid;
  group_by_key(std::span<const long long>(cell_of), static_cast<size_t>(grid.cells()), g.cells.start, g.cells.members);
  g.sorted.resize(subset.size());
#pragma omp parallel for schedule(static)
  for (int64_t k = 0; k < static_cast<int64_t>(subset.size()); ++k) {
    const size_t j = static_cast<size_t>(subset[static_cast<size_t>(g.cells.members[static_cast<size_t>(k)])]);
    g.sorted[static_cast<size_t>(k)] = {{x[3 * j], x[3 * j + 1], x[3 * j + 2]}, pad.empty() ? 0.0 : pad[j], horizon[j],
                                        static_cast<int32_t>(j)};
  }
  g.cell_horizon.assign(static_cast<size_t>(grid.cells()), 0.0);
  g.cell_pad.assign(static_cast<size_t>(grid.cells()), 0.0);
#pragma omp parallel for schedule(static)
  for (long long c = 0; c < grid.cells(); ++c)
    for (int64_t k = g.cells.start[c]; k < g.cells.start[c + 1]; ++k) {
      const auto& cj = g.sorted[static_cast<size_t>(k)];
      g.cell_horizon[static_cast<size_t>(c)] = std::max(g.cell_horizon[static_cast<size_t>(c)], cj.horizon);
      g.cell_pad[static_cast<size_t>(c)] = std::max(g.cell_pad[static_cast<size_t>(c)], cj.pad);
    }
  for (const auto& cj : g.sorted) {
    g.max_horizon = std::max(g.max_horizon, cj.horizon);
    g.max_pad = std::max(g.max_pad, cj.pad);
  }
  return g;
}

}  // namespace

Families build_families(std::span<const double> x, std::span<const double> horizon,
                        std::span<const double> pad, int64_t row_begin, int64_t row_end) {
  const size_t n = horizon.size();
  if (x.size() != 3 * n) throw std::invalid_argument("build_families: position must be 3N");
  if (!pad.empty() && pad.size() != n) throw std::invalid_argument("build_families: pad must be empty or N");
  if (row_end < 0) row_end = static_cast<int64_t>(n);
  if (row_begin < 0 || row_begin > row_end || row_end > static_cast<int64_t>(n))
    throw std::invalid_argument("build_families: rows outside [0, N]");
  Families fam;
  fam.offsets.assign(n + 1, 0);
  if (n == 0) return fam;
  auto pad_of = [&](size_t i) { return pad.empty() ? 0.0 : pad[i]; };
  // reach(i, j) = max(h_i, h_j) + max(p_i, p_j). Each row searches every j within it (the
  // test of both ends), so the lists come out symmetric with no transposed search to merge.
  // Reach classes: the particles grouped by horizon in octaves from the smallest (class K:
  // h in [2^K, 2^(K+1)) h_min; at most kClasses, the last open-ended). Class K's grids have
  // cells of half the class's largest reach, so a row's search spans 5 cells per axis (125)
  // whatever its horizon: with one grid sized for the finest particles a coarse particle of a
  // graded mesh scanned up to 3,375 (the full concrete case's horizons span 2.9-22 mm).
  // Row i of class K finds the particles of classes <= K in the grid "up to K" (all of them
  // binned in K's cells) and those of each coarser class L in the grid "only L" (L's cells),
  // so it visits every particle at most once; each cell is skipped when its box lies beyond
  // the reach of its own particles' largest horizon and pad.
  constexpr int kClasses = 8;
  double h_min = horizon[0];
  for (size_t i = 0; i < n; ++i) h_min = std::min(h_min, horizon[i]);
  std::vector<uint8_t> klass(n, 0);
  int classes = 1;
  if (h_min > 0.0)
    for (size_t i = 0; i < n; ++i) {
      int k = 0;
      double top = 2.0 * h_min;
      while (k + 1 < kClasses && horizon[i] >= top) {
        ++k;
        top *= 2.0;
      }
      klass[i] = static_cast<uint8_t>(k);
      classes = std::max(classes, k + 1);
    }
  const BoundingBox box = bounding_box(x);
  std::vector<double> class_reach(static_cast<size_t>(classes), 0.0);  // largest h + largest pad of the class
  {
    std::vector<double> hk(static_cast<size_t>(classes), 0.0), pk(static_cast<size_t>(classes), 0.0);
    for (size_t i = 0; i < n; ++i) {
      hk[klass[i]] = std::max(hk[klass[i]], horizon[i]);
      pk[klass[i]] = std::max(pk[klass[i]], pad_of(i));
    }
    for (int k = 0; k < classes; ++k) class_reach[static_cast<size_t>(k)] = hk[static_cast<size_t>(k)] + pk[static_cast<size_t>(k)];
  }
  // A grid's cell: half the class's reach, or larger where the bounding box would otherwise
  // hold more than 8 cells per particle (and 2^16): sparse points in a large box.
  auto cell_of_class = [&](int k) {
    double cell = std::max(0.5 * class_reach[static_cast<size_t>(k)], 1e-300);
    for (;;) {
      double cells = 1.0;
      for (int d = 0; d < 3; ++d) cells *= std::floor((box.hi[d] - box.lo[d]) / cell) + 1.0;
      if (cells <= std::max(8.0 * static_cast<double>(n), 65536.0)) return cell;
      cell *= 1.25;
    }
  };
  std::vector<ReachGrid> up_to(static_cast<size_t>(classes)), only(static_cast<size_t>(classes));
  for (int k = 0; k < classes; ++k) {
    std::vector<int32_t> subset_up_to, subset_only;
    for (size_t i = 0; i < n; ++i) {
      if (klass[i] <= k) subset_up_to.push_back(static_cast<int32_t>(i));
      if (klass[i] == k && k > 0) subset_only.push_back(static_cast<int32_t>(i));
    }
    const double cell = cell_of_class(k);
    // Only the classes that some row searches: "up to K" where a row is of class K, "only
    // L" for L above the smallest class present.
    bool rows_of_k = false;
    for (size_t i = static_cast<size_t>(row_begin); i < static_cast<size_t>(row_end) && !rows_of_k; ++i) rows_of_k = klass[i] == k;
    if (rows_of_k) up_to[static_cast<size_t>(k)] = make_grid(x, horizon, pad, subset_up_to, box, cell);
    if (k > 0) only[static_cast<size_t>(k)] = make_grid(x, horizon, pad, subset_only, box, cell);
  }
  // Every j of grid g with r2 <= max(h_i, h_j) + max(p_i, p_j), tested as "i's own reach or
  // j's": r2 is the same bits from either end (x_i - x_j = -(x_j - x_i) exactly), so the row
  // is the union of what i finds and what finds i, bit for bit.
  auto visit = [&](size_t i, const ReachGrid& g, auto&& emit) {
    if (g.sorted.empty()) return;
    const CellGrid& grid = g.cells.grid;
    const double pad_i = pad_of(i), horizon_i = horizon[i];
    const double margin = 1e-9 * grid.cell[0];  // the rounding of a point's cell coordinate
    const double search = std::max(horizon_i, g.max_horizon) + std::max(pad_i, g.max_pad);
    const long long ring = static_cast<long long>(std::ceil(search / grid.cell[0]));
    const double skip2 = (search + margin) * (search + margin);
    long long ci[3];
    for (int d = 0; d < 3; ++d) ci[d] = grid.coordinate(d, x[3 * i + d]);
    const double xi[3] = {x[3 * i], x[3 * i + 1], x[3 * i + 2]};
    auto gap = [&](int d, long long a) {
      const double lo = grid.origin[d] + static_cast<double>(a) * grid.cell[d], hi = lo + grid.cell[d];
      const double v = xi[d];
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
          const double g2 = gz * gz + gy * gy + gx * gx;
          if (g2 > skip2) continue;
          const long long c = grid.index(ax, ay, az);
          const int64_t begin = g.cells.start[c], end = g.cells.start[c + 1];
          if (begin == end) continue;
          // this cell's own reach: its particles' largest horizon and pad (the same margin)
          const double cell_search = std::max(horizon_i, g.cell_horizon[static_cast<size_t>(c)]) +
                                     std::max(pad_i, g.cell_pad[static_cast<size_t>(c)]) + margin;
          if (g2 > cell_search * cell_search) continue;
          for (int64_t k = begin; k < end; ++k) {
            const ReachGrid::Candidate& cj = g.sorted[static_cast<size_t>(k)];
            const size_t j = static_cast<size_t>(cj.index);
            if (j == i) continue;
            const double p = std::max(pad_i, cj.pad);
            const double reach = horizon_i + p, reach_j = cj.horizon + p;
            double r2 = 0.0;
            for (int d = 0; d < 3; ++d) {
              const double e = cj.x[d] - xi[d];
              r2 += e * e;
            }
            if (r2 <= reach * reach || r2 <= reach_j * reach_j) emit(j);
          }
        }
      }
    }
  };
  // Each block of 512 rows is searched into a scratch buffer of its thread (sorted per row),
  // then appended to the thread's store: chunks of 16M entries (64 MB) on huge pages, written
  // once and never moved; the lists are copied into place once the counts are known. Buffers
  // of their own per block, grown by doubling, copied themselves several times and faulted
  // in every 4 KiB page of them one by one.
  constexpr size_t block = 512;
  const size_t blocks = (n + block - 1) / block;
#if defined(_OPENMP)
  const size_t threads = static_cast<size_t>(omp_get_max_threads());
#else
  const size_t threads = 1;
#endif
  constexpr size_t chunk_entries = size_t{1} << 24;
  std::vector<std::vector<std::vector<int32_t>>> store(threads);
  std::vector<const int32_t*> found(blocks, nullptr);  // block b's lists, count[] of its rows long
  std::vector<int64_t> count(n, 0);
#pragma omp parallel
  {
#if defined(_OPENMP)
    std::vector<std::vector<int32_t>>& chunks = store[static_cast<size_t>(omp_get_thread_num())];
#else
    std::vector<std::vector<int32_t>>& chunks = store[0];
#endif
    std::vector<int32_t> list;
#pragma omp for schedule(dynamic, 4)
    for (size_t b = 0; b < blocks; ++b) {
      list.clear();
      for (size_t i = b * block; i < std::min(n, (b + 1) * block); ++i) {
        if (static_cast<int64_t>(i) < row_begin || static_cast<int64_t>(i) >= row_end) continue;  // left empty
        const size_t first = list.size();
        auto emit = [&](size_t j) { list.push_back(static_cast<int32_t>(j)); };
        visit(i, up_to[klass[i]], emit);
        for (int k = klass[i] + 1; k < classes; ++k) visit(i, only[static_cast<size_t>(k)], emit);
        std::sort(list.begin() + static_cast<std::ptrdiff_t>(first), list.end());
        count[i] = static_cast<int64_t>(list.size() - first);
      }
      if (chunks.empty() || chunks.back().capacity() - chunks.back().size() < list.size()) {
        chunks.emplace_back();
        const size_t capacity = std::max(chunk_entries, list.size());
        chunks.back().reserve(capacity);
        advise_huge_pages(chunks.back().data(), capacity * sizeof(int32_t));
      }
      std::vector<int32_t>& chunk = chunks.back();
      found[b] = chunk.data() + chunk.size();
      chunk.insert(chunk.end(), list.begin(), list.end());
    }
  }
  for (size_t i = 0; i < n; ++i) fam.offsets[i + 1] = fam.offsets[i] + count[i];
  assign_on_huge_pages(fam.neighbors, static_cast<size_t>(fam.offsets[n]));
#pragma omp parallel for schedule(dynamic, 4)
  for (size_t b = 0; b < blocks; ++b) {
    const int64_t first = fam.offsets[b * block], last = fam.offsets[std::min(n, (b + 1) * block)];
    if (last > first) std::copy(found[b], found[b] + (last - first), fam.neighbors.begin() + first);
  }
  return fam;
}

}  // namespace breccia
