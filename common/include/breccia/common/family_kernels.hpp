#pragma once
// The bond families' per-index kernels (families.hpp's search, written once): plain functors
// over raw pointers that any execution space launches one index at a time, the host's OpenMP
// loop (families.cpp) and a CUDA thread per index (solver/cuda/src/cuda_families.cu) alike.
// No allocation, exception or standard container inside; the driver that sequences them and
// owns the arrays is family_build.hpp.
//
// Every kernel's result is independent of the order its indices run in: the counting sort's
// slots are taken with atomics and each cell's members then sorted by index; every row writes
// its own slice only and sorts it. So a launch in any order, on any number of threads, gives
// the families of the serial search bit for bit (tests/solver/test_family_build.cpp runs them
// in reverse order to show it).
#include <cmath>
#include <cstdint>

#include "breccia/common/cell_list.hpp"

#if defined(__CUDACC__)
#define BRECCIA_FAMILY_HD __host__ __device__ inline
#else
#define BRECCIA_FAMILY_HD inline
#endif

namespace breccia::family {

// At most this many reach classes (horizons in octaves from the smallest; the last open-ended).
constexpr int kClasses = 8;

// value += add, returning the value before; atomic (relaxed) on host threads and GPU threads.
BRECCIA_FAMILY_HD int64_t fetch_add(int64_t* value, int64_t add) {
#if defined(__CUDA_ARCH__)
  return static_cast<int64_t>(
      atomicAdd(reinterpret_cast<unsigned long long*>(value), static_cast<unsigned long long>(add)));
#else
  return __atomic_fetch_add(value, add, __ATOMIC_RELAXED);
#endif
}

BRECCIA_FAMILY_HD double larger(double a, double b) { return a < b ? b : a; }  // std::max's choice

// a[0 .. m) ascending (distinct values: a row's partners, a cell's members, so any correct
// sort gives the same array). Quicksort on an explicit stack (the smaller side first, so 64
// levels suffice for any m < 2^63), insertion sort below 24 entries.
BRECCIA_FAMILY_HD void sort_ascending(int32_t* a, int64_t m) {
  int64_t stack[2 * 64];
  int top = 0;
  int64_t lo = 0, hi = m;  // the range [lo, hi) in hand
  for (;;) {
    while (hi - lo > 24) {
      // median of three as the pivot, moved to a[lo]
      const int64_t mid = lo + (hi - lo) / 2;
      int32_t x = a[lo], y = a[mid], z = a[hi - 1];
      const int64_t median = (x < y) ? (y < z ? mid : (x < z ? hi - 1 : lo)) : (x < z ? lo : (y < z ? hi - 1 : mid));
      const int32_t pivot = a[median];
      a[median] = a[lo];
      a[lo] = pivot;
      // Hoare partition of (lo, hi) around the pivot
      int64_t i = lo, j = hi;
      for (;;) {
        do ++i;
        while (i < hi && a[i] < pivot);
        do --j;
        while (a[j] > pivot);
        if (i >= j) break;
        const int32_t t = a[i];
        a[i] = a[j];
        a[j] = t;
      }
      a[lo] = a[j];
      a[j] = pivot;
      // [lo, j) and [j + 1, hi): keep the smaller, push the larger
      if (j - lo < hi - (j + 1)) {
        stack[top++] = j + 1;
        stack[top++] = hi;
        hi = j;
      } else {
        stack[top++] = lo;
        stack[top++] = j;
        lo = j + 1;
      }
    }
    for (int64_t i = lo + 1; i < hi; ++i) {
      const int32_t v = a[i];
      int64_t k = i;
      for (; k > lo && a[k - 1] > v; --k) a[k] = a[k - 1];
      a[k] = v;
    }
    if (top == 0) return;
    hi = stack[--top];
    lo = stack[--top];
  }
}

// What a row's search reads of a candidate, in cell order (consecutive reads, not gathers).
struct Candidate {
  double x[3];
  double pad, horizon;
  int32_t index;
};

// One reach grid: a cell list of a subset of the particles (those of reach classes
// [class_lo, class_hi]) with cubic cells, each cell's members in ascending index.
struct GridView {
  double origin[3];
  double cell;
  long long count[3];
  int class_lo, class_hi;
  int64_t size;                  // particles in the grid
  double max_horizon, max_pad;   // over them
  const int64_t* start;          // cells + 1 (cell c: sorted[start[c]] ... sorted[start[c + 1] - 1])
  const Candidate* sorted;       // size
  const double* cell_horizon;    // cells: the largest horizon of the cell's particles
  const double* cell_pad;        // cells: the largest pad
  BRECCIA_FAMILY_HD long long cells() const { return count[0] * count[1] * count[2]; }
  BRECCIA_FAMILY_HD long long coordinate(int d, double v) const { return cell_coordinate(v, origin[d], cell, count[d]); }
  BRECCIA_FAMILY_HD long long index(long long cx, long long cy, long long cz) const {
    return (cz * count[1] + cy) * count[0] + cx;
  }
};

// The particles every kernel reads: position 3N, horizon N, pad N (null: 0), reach class N.
struct Points {
  const double* x;
  const double* horizon;
  const double* pad;
  const uint8_t* klass;
  BRECCIA_FAMILY_HD double pad_of(int64_t i) const { return pad ? pad[i] : 0.0; }
};

// ---------------------------------------------------------------------------------------
// Binning (a counting sort per grid): key, count, exclusive scan (below), fill, then each
// cell's members sorted by index and copied into the candidates.

// key[i]: particle i's cell in grid g, or g.cells() (a last bucket, ignored) when i is not one
// of its classes'.
struct BinKey {
  Points p;
  GridView g;
  int64_t* key;
  BRECCIA_FAMILY_HD void operator()(int64_t i) const {
    const int k = p.klass[i];
    const double* xi = p.x + 3 * i;
    key[i] = (k < g.class_lo || k > g.class_hi)
                 ? g.cells()
                 : g.index(g.coordinate(0, xi[0]), g.coordinate(1, xi[1]), g.coordinate(2, xi[2]));
  }
};

struct Fill64 {  // value[k] = v
  int64_t* value;
  int64_t v;
  BRECCIA_FAMILY_HD void operator()(int64_t k) const { value[k] = v; }
};

struct Copy64 {  // to[k] = from[k]
  const int64_t* from;
  int64_t* to;
  BRECCIA_FAMILY_HD void operator()(int64_t k) const { to[k] = from[k]; }
};

struct BinCount {  // count[key[i]] += 1
  const int64_t* key;
  int64_t* count;
  BRECCIA_FAMILY_HD void operator()(int64_t i) const { fetch_add(&count[key[i]], 1); }
};

// members[a slot of i's cell] = i; the slot's order within a cell is whatever the threads'
// is, put right by SortCell.
struct BinFill {
  const int64_t* key;
  int64_t* cursor;  // the cells' starts on entry
  int32_t* members;
  BRECCIA_FAMILY_HD void operator()(int64_t i) const {
    members[fetch_add(&cursor[key[i]], 1)] = static_cast<int32_t>(i);
  }
};

// Cell c's members in ascending index, their candidates, and the cell's largest horizon and pad.
struct SortCell {
  Points p;
  const int64_t* start;
  int32_t* members;
  Candidate* sorted;
  double* cell_horizon;
  double* cell_pad;
  BRECCIA_FAMILY_HD void operator()(int64_t c) const {
    const int64_t begin = start[c], end = start[c + 1];
    sort_ascending(members + begin, end - begin);
    double h = 0.0, pad = 0.0;
    for (int64_t k = begin; k < end; ++k) {
      const int64_t j = members[k];
      Candidate& cj = sorted[k];
      for (int d = 0; d < 3; ++d) cj.x[d] = p.x[3 * j + d];
      cj.pad = p.pad_of(j);
      cj.horizon = p.horizon[j];
      cj.index = static_cast<int32_t>(j);
      h = larger(h, cj.horizon);
      pad = larger(pad, cj.pad);
    }
    cell_horizon[c] = h;
    cell_pad[c] = pad;
  }
};

// ---------------------------------------------------------------------------------------
// Exclusive scan of value[0 .. n) into out[0 .. n] (out[n] the total) in blocks of `block`:
// each block's sum, the sums' scan by one index, each block's running sum. Integer sums, so
// the same in any order.
struct ScanBlockSums {
  const int64_t* value;
  int64_t n, block;
  int64_t* block_sum;
  BRECCIA_FAMILY_HD void operator()(int64_t b) const {
    int64_t s = 0;
    const int64_t end = (b + 1) * block < n ? (b + 1) * block : n;
    for (int64_t k = b * block; k < end; ++k) s += value[k];
    block_sum[b] = s;
  }
};
struct ScanBlockStarts {  // one index: block_sum[0 .. blocks) -> their exclusive scan, total at [blocks]
  int64_t* block_sum;
  int64_t blocks;
  BRECCIA_FAMILY_HD void operator()(int64_t) const {
    int64_t s = 0;
    for (int64_t b = 0; b < blocks; ++b) {
      const int64_t v = block_sum[b];
      block_sum[b] = s;
      s += v;
    }
    block_sum[blocks] = s;
  }
};
struct ScanBlockWrite {
  const int64_t* value;
  int64_t n, block;
  const int64_t* block_start;  // blocks + 1
  int64_t* out;                // n + 1
  int64_t blocks;
  BRECCIA_FAMILY_HD void operator()(int64_t b) const {
    int64_t s = block_start[b];
    const int64_t end = (b + 1) * block < n ? (b + 1) * block : n;
    for (int64_t k = b * block; k < end; ++k) {
      const int64_t v = value[k];
      out[k] = s;
      s += v;
    }
    if (b == blocks - 1) out[n] = block_start[blocks];
  }
};

// ---------------------------------------------------------------------------------------
// The rows. Row i of class K searches the grid "up to K" (every particle of classes <= K in
// K's cells) and, for each coarser class L, the grid "only L"; so it meets each particle at
// most once. j is i's partner when r2 <= reach(i, j)^2 from either end, reach = max(h_i,
// h_j) + max(p_i, p_j): r2 is the same bits from i or from j (x_i - x_j = -(x_j - x_i)
// exactly), so the rows come out symmetric. A cell is skipped when its box lies beyond the
// reach of its own particles' largest horizon and pad.
// j is i's partner (the test every row search makes, the cells' and the lattice's in
// families.cpp alike): r2 <= reach^2 from either end.
BRECCIA_FAMILY_HD bool within_reach(const double xi[3], double horizon_i, double pad_i, const double xj[3],
                                    double horizon_j, double pad_j) {
  const double pad = larger(pad_i, pad_j);
  const double reach = horizon_i + pad, reach_j = horizon_j + pad;
  double r2 = 0.0;
  for (int d = 0; d < 3; ++d) {
    const double e = xj[d] - xi[d];
    r2 += e * e;
  }
  return r2 <= reach * reach || r2 <= reach_j * reach_j;
}

template <class Emit>
BRECCIA_FAMILY_HD void search_grid(const Points& p, int64_t i, const GridView& g, Emit& emit) {
  if (g.size == 0) return;
  const double pad_i = p.pad_of(i), horizon_i = p.horizon[i];
  const double margin = 1e-9 * g.cell;  // the rounding of a point's cell coordinate
  const double search = larger(horizon_i, g.max_horizon) + larger(pad_i, g.max_pad);
  const long long ring = static_cast<long long>(std::ceil(search / g.cell));
  const double skip2 = (search + margin) * (search + margin);
  const double xi[3] = {p.x[3 * i], p.x[3 * i + 1], p.x[3 * i + 2]};
  long long lo[3], hi[3];
  for (int d = 0; d < 3; ++d) {
    const long long c = g.coordinate(d, xi[d]);
    lo[d] = c - ring < 0 ? 0 : c - ring;
    hi[d] = c + ring > g.count[d] - 1 ? g.count[d] - 1 : c + ring;
  }
  // distance from xi to cell a's slab on axis d (0 inside)
  auto gap = [&](int d, long long a) {
    const double low = g.origin[d] + static_cast<double>(a) * g.cell, high = low + g.cell;
    const double v = xi[d];
    return v < low ? low - v : (v > high ? v - high : 0.0);
  };
  for (long long az = lo[2]; az <= hi[2]; ++az) {
    const double gz = gap(2, az);
    if (gz * gz > skip2) continue;
    for (long long ay = lo[1]; ay <= hi[1]; ++ay) {
      const double gy = gap(1, ay);
      if (gz * gz + gy * gy > skip2) continue;
      for (long long ax = lo[0]; ax <= hi[0]; ++ax) {
        const double gx = gap(0, ax);
        const double g2 = gz * gz + gy * gy + gx * gx;
        if (g2 > skip2) continue;
        const long long c = g.index(ax, ay, az);
        const int64_t begin = g.start[c], end = g.start[c + 1];
        if (begin == end) continue;
        const double cell_search = larger(horizon_i, g.cell_horizon[c]) + larger(pad_i, g.cell_pad[c]) + margin;
        if (g2 > cell_search * cell_search) continue;
        for (int64_t k = begin; k < end; ++k) {
          const Candidate& cj = g.sorted[k];
          if (cj.index == i) continue;
          if (within_reach(xi, horizon_i, pad_i, cj.x, cj.horizon, cj.pad)) emit(cj.index);
        }
      }
    }
  }
}

// The grids a row searches: up_to[K] for rows of class K, only[L] (L >= 1) for coarser classes.
struct Grids {
  GridView up_to[kClasses];
  GridView only[kClasses];
  int classes;
};

template <class Emit>
BRECCIA_FAMILY_HD void search_row(const Points& p, const Grids& grids, int64_t i, Emit& emit) {
  const int k = p.klass[i];
  search_grid(p, i, grids.up_to[k], emit);
  for (int l = k + 1; l < grids.classes; ++l) search_grid(p, i, grids.only[l], emit);
}

struct CountEmit {
  int64_t found = 0;
  BRECCIA_FAMILY_HD void operator()(int32_t) { ++found; }
};
struct StoreEmit {
  int32_t* out;
  BRECCIA_FAMILY_HD void operator()(int32_t j) { *out++ = j; }
};

// count[row_begin + r]: row (row_begin + r)'s partners.
struct RowCount {
  Points p;
  Grids grids;
  int64_t row_begin;
  int64_t* count;
  BRECCIA_FAMILY_HD void operator()(int64_t r) const {
    const int64_t i = row_begin + r;
    CountEmit emit;
    search_row(p, grids, i, emit);
    count[i] = emit.found;
  }
};

// Row (row_begin + r)'s partners into neighbors[offsets[i] ...], ascending.
struct RowFill {
  Points p;
  Grids grids;
  int64_t row_begin;
  const int64_t* offsets;
  int32_t* neighbors;
  BRECCIA_FAMILY_HD void operator()(int64_t r) const {
    const int64_t i = row_begin + r;
    StoreEmit emit{neighbors + offsets[i]};
    search_row(p, grids, i, emit);
    sort_ascending(neighbors + offsets[i], offsets[i + 1] - offsets[i]);
  }
};

}  // namespace breccia::family

#undef BRECCIA_FAMILY_HD
