#include "breccia/solver/partition.hpp"

#include "breccia/common/cell_list.hpp"
#include "breccia/solver/family.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <set>
#include <stdexcept>
#include <utility>

namespace breccia::solver {

int Partition::owner(int64_t i) const {
  // The last rank whose range starts at or before i (empty ranks share their start).
  return static_cast<int>(std::upper_bound(begin.begin(), begin.end() - 1, i) - begin.begin()) - 1;
}

namespace {

// The cut for `target` along an order whose work `cum(i)` (particles [0, i)) is
// non-decreasing: the first i in [lo, hi] with cum(i) >= target (hi if none), then the nearer
// side of the target. Searched over [0, n] it is the whole order's; over a slice (lo, hi]
// with cum(lo) < target <= cum(hi), the same i.
template <class Cumulative>
int64_t nearer_cut(double target, int64_t lo, int64_t hi, const Cumulative& cum) {
  while (lo < hi) {
    const int64_t mid = lo + (hi - lo) / 2;
    if (cum(mid) < target) lo = mid + 1;
    else hi = mid;
  }
  int64_t i = lo;
  if (i > 0 && target - cum(i - 1) < cum(i) - target) --i;  // the nearer cut
  return i;
}

// The ranges from the nearer cuts (cut[r] for r in [1, ranks)): every rank keeps at least one
// particle, so ranges stay non-empty while ranks <= n.
Partition clamp_cuts(const std::vector<int64_t>& cut, int64_t n, int ranks) {
  Partition p;
  p.begin.assign(static_cast<size_t>(ranks) + 1, 0);
  p.begin[ranks] = n;
  for (int r = 1; r < ranks; ++r) p.begin[r] = std::clamp<int64_t>(cut[r], p.begin[r - 1] + 1, n - (ranks - r));
  return p;
}

// Ranges of equal work along an order: `cum(i)` is the work of particles [0, i), non-
// decreasing, i in [0, n]. Each cut goes to the nearer side of its target, and every rank
// keeps at least one particle. Shared by MortonRangePartitioner and the lattice figures.
template <class Cumulative>
Partition cut_equal_work(int64_t n, int ranks, const Cumulative& cum) {
  std::vector<int64_t> cut(static_cast<size_t>(ranks), 0);
  for (int r = 1; r < ranks; ++r) cut[r] = nearer_cut(cum(n) * r / ranks, 0, n, cum);
  return clamp_cuts(cut, n, ranks);
}

}  // namespace

void require_ranks_fit(int64_t n, int ranks) {
  if (ranks < 1) throw std::invalid_argument("partition: at least one rank");
  if (ranks > n)
    throw std::invalid_argument("partition: " + std::to_string(ranks) + " ranks for " + std::to_string(n) +
                                " particles (at most one rank per particle)");
}

Partition MortonRangePartitioner::partition(const std::vector<int64_t>& offsets, int ranks) const {
  const int64_t n = static_cast<int64_t>(offsets.size()) - 1;
  require_ranks_fit(n, ranks);
  // cum[i]: work of particles [0, i).
  std::vector<double> cum(static_cast<size_t>(n) + 1, 0.0);
  for (int64_t i = 0; i < n; ++i) cum[i + 1] = cum[i] + static_cast<double>(offsets[i + 1] - offsets[i]) + particle_weight_;
  return cut_equal_work(n, ranks, [&](int64_t i) { return cum[i]; });
}

std::vector<int64_t> MortonRangePartitioner::slice_cuts(const std::vector<int64_t>& sizes, int64_t first,
                                                        int64_t entries_before, int64_t body_n, int64_t body_entries,
                                                        int ranks) const {
  // partition's cum(i) sums integers (row lengths and an integral weight) in doubles: below
  // 2^53 every partial sum is exact, so it equals the integer sum, which the slices' prefix
  // (entries_before, first) gives here without the rows before them.
  const double total = static_cast<double>(body_entries) + particle_weight_ * static_cast<double>(body_n);
  if (particle_weight_ != std::floor(particle_weight_) || particle_weight_ < 0 || !(total < 9007199254740992.0))
    throw std::logic_error("MortonRangePartitioner::slice_cuts: the work is not an exact integer sum");
  const int64_t m = static_cast<int64_t>(sizes.size());
  std::vector<int64_t> prefix(sizes.size() + 1, entries_before);  // entries of rows [0, first + k)
  for (int64_t k = 0; k < m; ++k) prefix[k + 1] = prefix[k] + sizes[k];
  auto cum = [&](int64_t i) {  // i in [first, first + m]
    return static_cast<double>(prefix[i - first]) + particle_weight_ * static_cast<double>(i);
  };
  std::vector<int64_t> cut(static_cast<size_t>(ranks), -1);
  if (m == 0) return cut;
  for (int r = 1; r < ranks; ++r) {
    const double target = total * r / ranks;
    if (cum(first) < target && target <= cum(first + m)) cut[r] = nearer_cut(target, first, first + m, cum);
  }
  return cut;
}

Partition MortonRangePartitioner::from_slice_cuts(const std::vector<int64_t>& cut, int64_t n, int ranks) {
  require_ranks_fit(n, ranks);
  return clamp_cuts(cut, n, ranks);
}

ReachBounds reach_bounds(const std::vector<double>& horizon, const std::vector<double>& half_cell, int dimension) {
  ReachBounds b;
  for (size_t j = 0; j < horizon.size(); ++j) {
    const double r = horizon[j] + partial_volume_reach(half_cell[j], dimension);
    b.rmin = std::min(b.rmin, r);
    b.rmax = std::max(b.rmax, r);
  }
  return b;
}

void ReachBounds::fold(const ReachBounds& b) {
  rmin = std::min(rmin, b.rmin);
  rmax = std::max(rmax, b.rmax);
}

ReachFigures::ReachFigures(const ReachBounds& body) {
  const double q = body.rmin > 0.0 ? std::max(std::pow(2.0, 0.25), std::pow(body.rmax / body.rmin, 1.0 / kReachClasses)) : 2.0;
  for (int c = 0; c < kReachClasses - 1; ++c) bound[c] = body.rmin * std::pow(q, c + 1);
  for (int c = 0; c < kReachClasses; ++c)
    for (int d = 0; d < 3; ++d) box[c].lo[d] = 1e300, box[c].hi[d] = -1e300;
}

int ReachFigures::class_of(double reach) const {
  int c = 0;
  while (c < kReachClasses - 1 && reach >= bound[c]) ++c;
  return c;
}

void ReachFigures::add(const std::vector<double>& x, const std::vector<double>& horizon,
                       const std::vector<double>& half_cell, int dimension) {
  for (size_t j = 0; j < horizon.size(); ++j) {
    const double pad = partial_volume_reach(half_cell[j], dimension);
    const int c = class_of(horizon[j] + pad);
    present[c] = true;
    H[c] = std::max(H[c], horizon[j]);
    P[c] = std::max(P[c], pad);
    for (int d = 0; d < 3; ++d) {
      box[c].lo[d] = std::min(box[c].lo[d], x[3 * j + d]);
      box[c].hi[d] = std::max(box[c].hi[d], x[3 * j + d]);
    }
  }
}

void ReachFigures::fold(const ReachFigures& b) {
  for (int c = 0; c < kReachClasses; ++c) {
    present[c] = present[c] || b.present[c];
    H[c] = std::max(H[c], b.H[c]);
    P[c] = std::max(P[c], b.P[c]);
    for (int d = 0; d < 3; ++d) {
      box[c].lo[d] = std::min(box[c].lo[d], b.box[c].lo[d]);
      box[c].hi[d] = std::max(box[c].hi[d], b.box[c].hi[d]);
    }
  }
}

namespace {

// Reach classes: a particle's own reach h + pad in geometric bins from the smallest (ratio
// q: the spread of reaches over kReachClasses bins, at least 2^(1/4); fewer classes mark fewer
// grids but bound a particle's horizon more loosely: 4 left windows 4 to 7 % larger on
// the demo concrete block's 4 ranks), with each class's largest horizon H[c] and
// largest pad P[c]. A pair (i, j) is within max(h_i, h_j) + max(p_i, p_j) (build_families'
// test from either end), at most max(h_i, H[c]) + max(p_i, P[c]) for j of class c: row i
// marks, per class, the cells within that of its position.
struct ReachClasses {
  std::vector<uint8_t> of;  // each particle's class
  std::vector<double> pad;  // each particle's partial-volume reach (partial_volume_reach of its half cell)
  double H[kReachClasses] = {}, P[kReachClasses] = {};  // each class's largest horizon and pad
  bool present[kReachClasses] = {};
  BoundingBox up_to[kReachClasses];  // the box of classes 0 .. c's particles
};

// The body's classes (its ReachFigures) for the particles of the arrays: their classes and
// pads, the classes' figures the body's.
ReachClasses reach_classes(const std::vector<double>& horizon, const std::vector<double>& half_cell, int dimension,
                           const ReachFigures& body) {
  const size_t n = horizon.size();
  ReachClasses rc;
  rc.pad.resize(n);
  rc.of.resize(n);
  for (size_t j = 0; j < n; ++j) {
    rc.pad[j] = partial_volume_reach(half_cell[j], dimension);
    rc.of[j] = static_cast<uint8_t>(body.class_of(horizon[j] + rc.pad[j]));
  }
  for (int c = 0; c < kReachClasses; ++c) {
    rc.H[c] = body.H[c];
    rc.P[c] = body.P[c];
    rc.present[c] = body.present[c];
    rc.up_to[c] = body.box[c];
  }
  for (int c = 1; c < kReachClasses; ++c)
    for (int d = 0; d < 3; ++d) {
      rc.up_to[c].lo[d] = std::min(rc.up_to[c].lo[d], rc.up_to[c - 1].lo[d]);
      rc.up_to[c].hi[d] = std::max(rc.up_to[c].hi[d], rc.up_to[c - 1].hi[d]);
    }
  return rc;
}

// One grid's marks (geometric_window): bit c of a cell set when some row reaches class c's
// particles in it.
struct ClassMarks {
  bool active = false;
  BoundingBox box;
  CellGrid grid;
  std::vector<uint8_t> bits;
};

// Consecutive rows marked together, with their box.
struct RowGroup {
  std::vector<int64_t> rows;
  double lo[3], hi[3];
};

// Row i marks in grid g, with bit c (c from c_lo to c_hi: its own grid, bits 0 .. k; a
// coarser grid g, bit g), every cell whose box comes within reach[c] of it, plus a margin
// for a point's rounded cell coordinate, among the cells from that of x - most to that of
// x + most on each axis (most: the largest of those reaches; the coordinate is monotone in
// the position, so a point within reach falls in one of them). Row by row that visits
// about 343 cells per grid, and most rows mark 3 or 4 grids, while nearby rows mark nearly
// the same cells. So the rows are marked in groups: consecutive rows (the Morton order
// keeps them close) whose box stays within `group_cells` cells of the grid on each axis,
// one group per grid and kind of call. Each cell about a group is decided once from the
// group's box: the gap from a cell to the box's nearer and farther faces bounds every
// row's gap from below and above (the gap, the squares and their sum are monotone in
// each coordinate, also rounded), and the coordinates of the box's faces grown by the
// smallest and largest `most` bound every row's range. A cell that no row can reach is
// skipped, one that every row reaches is marked for the group, and only a cell in
// between that is not marked yet is tested row by row with the test above. So the marks
// are exactly those of each row alone, at about the cost of the groups' cells. Groups of
// 3 cells: of 1 or 2, more groups visit the same cells; of 4, the cells between "none" and
// "every row" grow, and so do the row tests, for about the same time (demo concrete
// block, 4 ranks: 3.0 to 3.7 times faster than row by row at 2 to 4 cells).
class GroupMarker {
 public:
  GroupMarker(const std::vector<double>& x, const std::vector<double>& horizon, const ReachClasses& rc,
              ClassMarks* grids)
      : x_(x), horizon_(horizon), rc_(rc), grids_(grids) {}
  // Row i's reach to class c's particles, times 1 + 1e-6 against rounding.
  double reach_to(int64_t i, int c) const {
    constexpr double grow = 1.0 + 1e-6;
    return (std::max(horizon_[i], rc_.H[c]) + std::max(rc_.pad[static_cast<size_t>(i)], rc_.P[c])) * grow;
  }
  // Marks grid g's cells for the group's rows (own: rows of class g, towards classes 0 .. g;
  // else rows of finer classes, towards class g) and empties the group.
  void mark(RowGroup& grp, int g, bool own);

 private:
  const std::vector<double>& x_;
  const std::vector<double>& horizon_;
  const ReachClasses& rc_;
  ClassMarks* grids_;
  // Scratch reused from group to group.
  std::vector<double> row_reach_;     // per row: its reach to each class (kReachClasses each)
  std::vector<long long> row_range_;  // per row: its first and last cell on each axis
  std::vector<double> least2_[3], largest2_[3];  // per axis, per cell of the group's range
  std::vector<double> row_gap2_;                 // per row, per axis, per cell of its range
};

void GroupMarker::mark(RowGroup& grp, int g, bool own) {
  if (grp.rows.empty()) return;
  ClassMarks& m = grids_[g];
  const CellGrid& gr = m.grid;
  const double margin = 1e-9 * gr.cell[0];
  const int c_lo = own ? 0 : g, c_hi = g;
  const size_t rows = grp.rows.size();
  row_reach_.assign(rows * kReachClasses, 0.0);
  row_range_.assign(rows * 6, 0);
  double most_min = std::numeric_limits<double>::infinity(), most_max = 0.0;
  for (size_t r = 0; r < rows; ++r) {
    const int64_t i = grp.rows[r];
    double most = 0.0;
    for (int c = c_lo; c <= c_hi; ++c)
      if (rc_.present[c]) most = std::max(most, row_reach_[r * kReachClasses + c] = reach_to(i, c));
    most_min = std::min(most_min, most);
    most_max = std::max(most_max, most);
    for (int d = 0; d < 3; ++d) {
      row_range_[6 * r + 2 * d] = gr.coordinate(d, x_[3 * i + d] - most);
      row_range_[6 * r + 2 * d + 1] = gr.coordinate(d, x_[3 * i + d] + most);
    }
  }
  // Bits whose reach is the same for every row of the group share one test (a row's own
  // reach towards every finer class, as a rule): a mask each, its smallest and largest reach.
  struct Mask {
    uint8_t bits = 0;
    int first = 0;
    double sure = 0.0, can = 0.0;  // (smallest reach + margin)^2, (largest + margin)^2
  };
  Mask masks[kReachClasses];
  int n_masks = 0;
  double can_any = 0.0;
  for (int c = c_lo; c <= c_hi; ++c) {
    if (!rc_.present[c]) continue;
    int k = 0;
    for (; k < n_masks; ++k) {
      bool same = true;
      for (size_t r = 0; r < rows && same; ++r) same = row_reach_[r * kReachClasses + c] == row_reach_[r * kReachClasses + masks[k].first];
      if (same) break;
    }
    if (k == n_masks) {
      double rmin = std::numeric_limits<double>::infinity(), rmax = 0.0;
      for (size_t r = 0; r < rows; ++r) {
        rmin = std::min(rmin, row_reach_[r * kReachClasses + c]);
        rmax = std::max(rmax, row_reach_[r * kReachClasses + c]);
      }
      masks[n_masks].first = c;
      masks[n_masks].sure = (rmin + margin) * (rmin + margin);
      masks[n_masks].can = (rmax + margin) * (rmax + margin);
      can_any = std::max(can_any, masks[n_masks].can);
      ++n_masks;
    }
    masks[k].bits |= static_cast<uint8_t>(1u << c);
  }
  if (most_max <= 0.0) {
    grp.rows.clear();
    return;
  }
  long long o0[3], o1[3], s0[3], s1[3];  // the rows' ranges' union and intersection
  for (int d = 0; d < 3; ++d) {
    o0[d] = gr.coordinate(d, grp.lo[d] - most_max);
    o1[d] = gr.coordinate(d, grp.hi[d] + most_max);
    s0[d] = gr.coordinate(d, grp.hi[d] - most_min);
    s1[d] = gr.coordinate(d, grp.lo[d] + most_min);
  }
  // The gap from a point to cell a on axis d, as each row's test takes it.
  auto gap = [&](int d, long long a, double xd) {
    const double low = gr.origin[d] + static_cast<double>(a) * gr.cell[d], high = low + gr.cell[d];
    return xd < low ? low - xd : (xd > high ? xd - high : 0.0);
  };
  // Its least and largest over the group's box, squared, per cell of the group's ranges (the
  // gap falls, then rises, along an axis, so they are the gaps at the box's faces).
  for (int d = 0; d < 3; ++d) {
    const size_t cells = static_cast<size_t>(o1[d] - o0[d] + 1);
    least2_[d].resize(cells);
    largest2_[d].resize(cells);
    for (long long a = o0[d]; a <= o1[d]; ++a) {
      const double at_lo = gap(d, a, grp.lo[d]), at_hi = gap(d, a, grp.hi[d]);
      const double low = gr.origin[d] + static_cast<double>(a) * gr.cell[d], high = low + gr.cell[d];
      const double least = grp.hi[d] < low ? at_hi : (grp.lo[d] > high ? at_lo : 0.0), largest = std::max(at_lo, at_hi);
      least2_[d][static_cast<size_t>(a - o0[d])] = least * least;
      largest2_[d][static_cast<size_t>(a - o0[d])] = largest * largest;
    }
  }
  // Each row's squared gap to each cell of the group's ranges, infinite outside its own
  // range: a row marks cell (ax, ay, az) for a reach when gz^2 + gy^2 + gx^2 is within
  // (reach + margin)^2, the sum taken in that order as above.
  size_t span[3], at[3];
  for (int d = 0; d < 3; ++d) span[d] = static_cast<size_t>(o1[d] - o0[d] + 1);
  at[0] = 0, at[1] = span[0], at[2] = span[0] + span[1];
  const size_t per_row = span[0] + span[1] + span[2];
  row_gap2_.resize(rows * per_row);
  for (size_t r = 0; r < rows; ++r)
    for (int d = 0; d < 3; ++d) {
      const double xd = x_[3 * grp.rows[r] + d];
      for (long long a = o0[d]; a <= o1[d]; ++a) {
        const bool in = a >= row_range_[6 * r + 2 * d] && a <= row_range_[6 * r + 2 * d + 1];
        const double g = gap(d, a, xd);
        row_gap2_[r * per_row + at[d] + static_cast<size_t>(a - o0[d])] = in ? g * g : std::numeric_limits<double>::infinity();
      }
    }
  auto row_marks = [&](size_t r, long long ax, long long ay, long long az, double reach) {
    const double* g2 = &row_gap2_[r * per_row];
    return g2[at[2] + static_cast<size_t>(az - o0[2])] + g2[at[1] + static_cast<size_t>(ay - o0[1])] +
               g2[at[0] + static_cast<size_t>(ax - o0[0])] <=
           (reach + margin) * (reach + margin);
  };
  for (long long az = o0[2]; az <= o1[2]; ++az) {
    const double z0 = least2_[2][static_cast<size_t>(az - o0[2])], z1 = largest2_[2][static_cast<size_t>(az - o0[2])];
    if (z0 > can_any) continue;
    for (long long ay = o0[1]; ay <= o1[1]; ++ay) {
      const double zy0 = z0 + least2_[1][static_cast<size_t>(ay - o0[1])], zy1 = z1 + largest2_[1][static_cast<size_t>(ay - o0[1])];
      if (zy0 > can_any) continue;
      const bool inner_zy = az >= s0[2] && az <= s1[2] && ay >= s0[1] && ay <= s1[1];
      uint8_t* line = &m.bits[static_cast<size_t>(gr.index(0, ay, az))];
      for (long long ax = o0[0]; ax <= o1[0]; ++ax) {
        const double least = zy0 + least2_[0][static_cast<size_t>(ax - o0[0])];
        if (least > can_any) continue;
        const double largest = zy1 + largest2_[0][static_cast<size_t>(ax - o0[0])];
        const bool inner = inner_zy && ax >= s0[0] && ax <= s1[0];
        uint8_t& cell_bits = line[ax];
        for (int k = 0; k < n_masks; ++k) {
          const Mask& mk = masks[k];
          if (least > mk.can || (cell_bits & mk.bits) == mk.bits) continue;
          if (inner && largest <= mk.sure) {
            cell_bits |= mk.bits;
            continue;
          }
          for (size_t r = 0; r < rows; ++r)
            if (row_marks(r, ax, ay, az, row_reach_[r * kReachClasses + mk.first])) {
              cell_bits |= mk.bits;
              break;
            }
        }
      }
    }
  }
  grp.rows.clear();
}

}  // namespace

struct WindowMarks::Grids {
  ClassMarks g[kReachClasses];
};

WindowMarks::~WindowMarks() { delete grids_; }
int WindowMarks::class_of(int64_t i) const { return of_[static_cast<size_t>(i)]; }

// Particle j of class c is near the rows when a grid g >= c marks its cell with bit c.
bool WindowMarks::near(const double* xj, int c) const {
  for (int g = c; g < kReachClasses; ++g) {
    const ClassMarks& m = grids_->g[g];
    if (!m.active) continue;
    bool inside = true;
    for (int d = 0; d < 3; ++d) inside = inside && xj[d] >= m.box.lo[d] && xj[d] <= m.box.hi[d];
    if (inside && (m.bits[static_cast<size_t>(m.grid.index_of(xj))] >> c & 1u)) return true;
  }
  return false;
}

MarksSummary WindowMarks::summary() const {
  MarksSummary out;
  for (int g = 0; g < kReachClasses; ++g) {
    const ClassMarks& m = grids_->g[g];
    MarksSummary::Grid& s = out.g[g];
    if (!m.active) continue;
    s.active = true;
    s.box = m.box;
    s.grid = m.grid;
    for (int d = 0; d < 3; ++d) s.blocks[d] = (m.grid.count[d] + kMarksBlock - 1) / kMarksBlock;
    std::vector<std::pair<int64_t, uint8_t>> marked;  // (block, a cell's bits), then merged
    for (long long az = 0; az < m.grid.count[2]; ++az)
      for (long long ay = 0; ay < m.grid.count[1]; ++ay)
        for (long long ax = 0; ax < m.grid.count[0]; ++ax)
          if (const uint8_t b = m.bits[static_cast<size_t>(m.grid.index(ax, ay, az))])
            marked.emplace_back(((az / kMarksBlock) * s.blocks[1] + ay / kMarksBlock) * s.blocks[0] + ax / kMarksBlock, b);
    std::sort(marked.begin(), marked.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    for (const auto& [block, b] : marked)
      if (!s.block.empty() && s.block.back() == block) s.bits.back() |= b;
      else s.block.push_back(block), s.bits.push_back(b);
  }
  return out;
}

bool MarksSummary::may_be_near(const double* x, int c) const {
  for (int k = c; k < kReachClasses; ++k) {
    const Grid& s = g[k];
    if (!s.active) continue;
    bool inside = true;
    for (int d = 0; d < 3; ++d) inside = inside && x[d] >= s.box.lo[d] && x[d] <= s.box.hi[d];
    if (!inside) continue;
    long long b[3];
    for (int d = 0; d < 3; ++d) b[d] = s.grid.coordinate(d, x[d]) / kMarksBlock;  // index_of's coordinates
    const int64_t block = (b[2] * s.blocks[1] + b[1]) * s.blocks[0] + b[0];
    const auto at = std::lower_bound(s.block.begin(), s.block.end(), block);
    if (at != s.block.end() && *at == block && (s.bits[static_cast<size_t>(at - s.block.begin())] >> c & 1u)) return true;
  }
  return false;
}

std::vector<char> MarksSummary::bytes() const {
  std::vector<char> out;
  auto put = [&](const void* p, size_t n) { out.insert(out.end(), static_cast<const char*>(p), static_cast<const char*>(p) + n); };
  for (const Grid& s : g) {
    const uint8_t active = s.active;
    put(&active, 1);
    if (!s.active) continue;
    const uint64_t marked = s.block.size();
    put(&s.box, sizeof s.box);
    put(&s.grid, sizeof s.grid);
    put(s.blocks, sizeof s.blocks);
    put(&marked, sizeof marked);
    put(s.block.data(), marked * sizeof(int64_t));
    put(s.bits.data(), marked);
  }
  return out;
}

MarksSummary MarksSummary::from_bytes(const char* p, size_t size) {
  MarksSummary out;
  size_t at = 0;
  auto take = [&](void* to, size_t n) {
    if (at + n > size) throw std::logic_error("MarksSummary: short bytes");
    if (n) std::memcpy(to, p + at, n);
    at += n;
  };
  for (Grid& s : out.g) {
    uint8_t active = 0;
    take(&active, 1);
    s.active = active;
    if (!s.active) continue;
    uint64_t marked = 0;
    take(&s.box, sizeof s.box);
    take(&s.grid, sizeof s.grid);
    take(s.blocks, sizeof s.blocks);
    take(&marked, sizeof marked);
    s.block.resize(marked);
    s.bits.resize(marked);
    take(s.block.data(), marked * sizeof(int64_t));
    take(s.bits.data(), marked);
  }
  if (at != size) throw std::logic_error("MarksSummary: long bytes");
  return out;
}

WindowMarks::WindowMarks(const std::vector<double>& x, const std::vector<double>& horizon,
                         const std::vector<double>& half_cell, int dimension, const ReachFigures& body, int64_t body_n,
                         int64_t row_begin, int64_t row_end, double group_cells)
    : grids_(new Grids) {
  const size_t n = horizon.size();
  if (x.size() != 3 * n || half_cell.size() != n)
    throw std::invalid_argument("geometric_window: x0 3N, horizon and half_cell N");
  if (!(group_cells >= 0.0)) throw std::invalid_argument("geometric_window: a group extent of at least 0 cells");
  if (row_begin < 0 || row_begin > row_end || row_end > static_cast<int64_t>(n))
    throw std::invalid_argument("geometric_window: rows [begin, end) within [0, N]");
  ReachClasses rc = reach_classes(horizon, half_cell, dimension, body);
  if (row_begin < row_end) {
    ClassMarks* grids = grids_->g;
    GroupMarker marker(x, horizon, rc, grids);
    // Grid g holds the marks of the pairs whose coarser end's class is g: rows of class g
    // towards classes 0 .. g (bits 0 .. g), rows of finer classes towards class g (bit g).
    // Cells of a third of class g's largest reach, so about the 343 cells around a row's are
    // visited whatever its class and the candidates' (cells of half the reach, the 125
    // around, visited a third as many and left windows 4 to 9 % larger on the demo concrete
    // block's 4 ranks; a quarter, 729, about 4 % smaller at 1.6 times the time); the grid covers
    // the rows' box grown by the largest reach marked in it, cut to the box of classes 0 .. g
    // (only their particles are looked up in it); 1 B per cell, at most max(N, 65,536) cells
    // per grid. A marked cell's particle lies within the reach plus the cell's diagonal.
    double lo[3], hi[3];
    for (int d = 0; d < 3; ++d) lo[d] = hi[d] = x[3 * static_cast<size_t>(row_begin) + d];
    for (int64_t i = row_begin; i < row_end; ++i)
      for (int d = 0; d < 3; ++d) {
        lo[d] = std::min(lo[d], x[3 * i + d]);
        hi[d] = std::max(hi[d], x[3 * i + d]);
      }
    double marked_reach[kReachClasses] = {};
    for (int64_t i = row_begin; i < row_end; ++i) {
      const int k = rc.of[static_cast<size_t>(i)];
      for (int c = 0; c < kReachClasses; ++c)
        if (rc.present[c]) marked_reach[std::max(k, c)] = std::max(marked_reach[std::max(k, c)], marker.reach_to(i, c));
    }
    for (int g = 0; g < kReachClasses; ++g) {
      if (marked_reach[g] <= 0.0) continue;
      ClassMarks& m = grids[g];
      m.active = true;
      for (int d = 0; d < 3; ++d) {
        m.box.lo[d] = std::max(lo[d] - marked_reach[g], rc.up_to[g].lo[d]);
        m.box.hi[d] = std::min(hi[d] + marked_reach[g], rc.up_to[g].hi[d]);
        m.active = m.active && m.box.lo[d] <= m.box.hi[d];
      }
      if (!m.active) continue;
      double cell = std::max((rc.H[g] + rc.P[g]) / 3.0, 1e-300);
      for (;;) {
        m.grid = CellGrid::covering(m.box, cell);
        if (m.grid.cells() <= std::max<long long>(static_cast<long long>(body_n), 65536)) break;
        cell *= 1.25;
      }
      m.bits.assign(static_cast<size_t>(m.grid.cells()), 0);
    }
    RowGroup open[kReachClasses][2];  // [grid][0: rows of the grid's class, 1: rows of finer classes]
    auto add_to_group = [&](int64_t i, int g, bool own) {
      RowGroup& grp = open[g][own ? 0 : 1];
      const double* xi = &x[3 * i];
      const double limit = group_cells * grids[g].grid.cell[0];
      if (!grp.rows.empty())
        for (int d = 0; d < 3; ++d)
          if (std::max(grp.hi[d], xi[d]) - std::min(grp.lo[d], xi[d]) > limit) {
            marker.mark(grp, g, own);
            break;
          }
      if (grp.rows.empty())
        for (int d = 0; d < 3; ++d) grp.lo[d] = grp.hi[d] = xi[d];
      for (int d = 0; d < 3; ++d) grp.lo[d] = std::min(grp.lo[d], xi[d]), grp.hi[d] = std::max(grp.hi[d], xi[d]);
      grp.rows.push_back(i);
    };
    for (int64_t i = row_begin; i < row_end; ++i) {
      const int k = rc.of[static_cast<size_t>(i)];
      for (int g = k; g < kReachClasses; ++g)
        if (grids[g].active && (g == k || rc.present[g])) add_to_group(i, g, g == k);
    }
    for (int g = 0; g < kReachClasses; ++g)
      if (grids[g].active) marker.mark(open[g][0], g, true), marker.mark(open[g][1], g, false);
  }
  of_.swap(rc.of);
}

GeometricWindow geometric_window(const std::vector<double>& x, const std::vector<double>& horizon,
                                 const std::vector<double>& half_cell, int dimension, int64_t row_begin,
                                 int64_t row_end, double group_cells) {
  const size_t n = horizon.size();
  if (x.size() != 3 * n || half_cell.size() != n)
    throw std::invalid_argument("geometric_window: x0 3N, horizon and half_cell N");
  if (row_begin < 0 || row_begin > row_end || row_end > static_cast<int64_t>(n))
    throw std::invalid_argument("geometric_window: rows [begin, end) within [0, N]");
  GeometricWindow w;
  if (row_begin == row_end) return w;
  ReachFigures body(reach_bounds(horizon, half_cell, dimension));
  body.add(x, horizon, half_cell, dimension);
  const WindowMarks marks(x, horizon, half_cell, dimension, body, static_cast<int64_t>(n), row_begin, row_end, group_cells);
  auto near = [&](size_t j) { return marks.near(&x[3 * j], marks.class_of(static_cast<int64_t>(j))); };
  for (int64_t j = 0; j < row_begin; ++j)
    if (near(static_cast<size_t>(j))) w.index.push_back(static_cast<int32_t>(j));
  w.row_begin = static_cast<int64_t>(w.index.size());
  for (int64_t j = row_begin; j < row_end; ++j) w.index.push_back(static_cast<int32_t>(j));
  w.row_end = static_cast<int64_t>(w.index.size());
  for (size_t j = static_cast<size_t>(row_end); j < n; ++j)
    if (near(j)) w.index.push_back(static_cast<int32_t>(j));
  return w;
}

std::vector<int64_t> family_sizes(const std::vector<double>& x, const std::vector<double>& horizon,
                                  const std::vector<double>& half_cell, int dimension, PartialVolume kind) {
  return family_sizes(x, horizon, half_cell, dimension, kind, 0, static_cast<int64_t>(horizon.size()));
}

std::vector<int64_t> family_sizes(const std::vector<double>& x, const std::vector<double>& horizon,
                                  const std::vector<double>& half_cell, int dimension, PartialVolume kind,
                                  int64_t row_begin, int64_t row_end) {
  const size_t n = horizon.size();
  if (x.size() != 3 * n || half_cell.size() != n) throw std::invalid_argument("family_sizes: x0 3N, horizon and half_cell N");
  if (row_begin < 0 || row_begin > row_end || row_end > static_cast<int64_t>(n))
    throw std::invalid_argument("family_sizes: rows [begin, end) within [0, N]");
  const size_t b = static_cast<size_t>(row_begin), e = static_cast<size_t>(row_end);
  std::vector<int64_t> count(e - b, 0);
  if (b == e) return count;
  // The set-up's pad (setup.cpp): a neighbour's outermost sample may reach into the horizon.
  auto pad = [&](size_t i) { return partial_volume_reach(half_cell[i], dimension); };
  double max_pad = 0.0, min_horizon = horizon[0], max_horizon = horizon[0];
  for (size_t i = 0; i < n; ++i) {
    max_pad = std::max(max_pad, pad(i));
    min_horizon = std::min(min_horizon, horizon[i]);
    max_horizon = std::max(max_horizon, horizon[i]);
  }
  // Cells as build_families sizes them; each particle scans the largest reach, since a pair
  // belongs to the family when either end's search finds the other (no transpose kept).
  const double max_reach = max_horizon + max_pad;
  const double cell = std::max({min_horizon + max_pad, max_reach / 8.0, 1e-300});
  const CellList cells = sort_into_cells(CellGrid::covering(bounding_box(x), cell), x);
  const CellGrid& grid = cells.grid;
  const long long ring = static_cast<long long>(std::ceil(max_reach / cell));
  // The rows counted: [b, e); every particle is still a partner (the cells hold them all).
#pragma omp parallel for schedule(dynamic, 256)
  for (size_t i = b; i < e; ++i) {
    long long ci[3];
    for (int d = 0; d < 3; ++d) ci[d] = grid.coordinate(d, x[3 * i + d]);
    int64_t kept = 0;
    for (long long az = std::max(0LL, ci[2] - ring); az <= std::min(grid.count[2] - 1, ci[2] + ring); ++az)
      for (long long ay = std::max(0LL, ci[1] - ring); ay <= std::min(grid.count[1] - 1, ci[1] + ring); ++ay)
        for (long long ax = std::max(0LL, ci[0] - ring); ax <= std::min(grid.count[0] - 1, ci[0] + ring); ++ax) {
          const long long c = grid.index(ax, ay, az);
          for (int64_t m = cells.start[c]; m < cells.start[c + 1]; ++m) {
            const size_t j = static_cast<size_t>(cells.members[m]);
            if (j == i) continue;
            // build_families' test from each end, in its arithmetic (the same r2 both ways).
            const double p = std::max(pad(i), pad(j));
            const double reach_i = horizon[i] + p, reach_j = horizon[j] + p;
            double r2 = 0.0;
            for (int d = 0; d < 3; ++d) {
              const double e = x[3 * j + d] - x[3 * i + d];
              r2 += e * e;
            }
            if (!(r2 <= reach_i * reach_i || r2 <= reach_j * reach_j)) continue;
            // The set-up's keep test (setup.cpp, its first pass over the candidates).
            const double xv[3] = {x[3 * j] - x[3 * i], x[3 * j + 1] - x[3 * i + 1], x[3 * j + 2] - x[3 * i + 2]};
            const double xm[3] = {-xv[0], -xv[1], -xv[2]};
            if (partial_volume_positive(kind, xv, horizon[i], half_cell[j], dimension) ||
                partial_volume_positive(kind, xm, horizon[j], half_cell[i], dimension))
              ++kept;
          }
        }
    count[i - b] = kept;
  }
  return count;
}

Halo build_halo(const Partition& part, int rank, const std::vector<int64_t>& offsets,
                const std::vector<int32_t>& neighbor, const std::vector<int32_t>* window) {
  Halo h;
  h.rank = rank;
  const int64_t b = part.begin[rank], e = part.begin[rank + 1];
  // A window system's row i is at local row i + shift (its rows are one local range).
  const int64_t shift =
      window ? (std::lower_bound(window->begin(), window->end(), static_cast<int32_t>(b)) - window->begin()) - b : 0;
  std::vector<std::pair<int, int32_t>> sends;  // (destination rank, owned particle)
  for (int64_t i = b; i < e; ++i)
    for (int64_t k = offsets[i + shift]; k < offsets[i + shift + 1]; ++k) {
      const int32_t j = window ? (*window)[static_cast<size_t>(neighbor[k])] : neighbor[k];
      if (j >= b && j < e) continue;
      h.ghosts.push_back(j);
      sends.emplace_back(part.owner(j), static_cast<int32_t>(i));  // families are symmetric: j's rank reads i
    }
  std::sort(h.ghosts.begin(), h.ghosts.end());
  h.ghosts.erase(std::unique(h.ghosts.begin(), h.ghosts.end()), h.ghosts.end());
  for (size_t g = 0; g < h.ghosts.size(); ++g) {
    const int src = part.owner(h.ghosts[g]);
    if (h.recv_ranks.empty() || h.recv_ranks.back() != src) {
      h.recv_ranks.push_back(src);
      h.recv_begin.push_back(static_cast<int64_t>(g));
    }
  }
  h.recv_begin.push_back(static_cast<int64_t>(h.ghosts.size()));
  std::sort(sends.begin(), sends.end());
  sends.erase(std::unique(sends.begin(), sends.end()), sends.end());
  for (const auto& [dst, i] : sends) {
    if (h.send_ranks.empty() || h.send_ranks.back() != dst) {
      h.send_ranks.push_back(dst);
      h.send_lists.emplace_back();
    }
    h.send_lists.back().push_back(i);
  }
  return h;
}

namespace {

// The figures from what each rank owns, computes (bond entries), receives (ghosts) and
// exchanges with (neighbour ranks): shared by the built-families and the lattice routes.
DecompositionStats summarise(const Partition& part, const std::vector<int64_t>& bonds, const std::vector<int64_t>& ghosts,
                             const std::vector<int>& neighbours, double bytes_per_ghost) {
  DecompositionStats s;
  s.ranks = part.ranks();
  s.min_owned = s.max_owned = part.owned(0);
  double bonds_sum = 0.0, bonds_max = 0.0, ratio_sum = 0.0, bytes_sum = 0.0;
  for (int r = 0; r < s.ranks; ++r) {
    const int64_t owned = part.owned(r);
    s.min_owned = std::min(s.min_owned, owned);
    s.max_owned = std::max(s.max_owned, owned);
    bonds_sum += static_cast<double>(bonds[r]);
    bonds_max = std::max(bonds_max, static_cast<double>(bonds[r]));
    const double ratio = owned > 0 ? static_cast<double>(ghosts[r]) / static_cast<double>(owned) : 0.0;
    ratio_sum += ratio;
    s.max_ghost_ratio = std::max(s.max_ghost_ratio, ratio);
    const double bytes = static_cast<double>(ghosts[r]) * bytes_per_ghost;
    bytes_sum += bytes;
    s.max_halo_bytes = std::max(s.max_halo_bytes, bytes);
    s.max_neighbour_ranks = std::max(s.max_neighbour_ranks, neighbours[r]);
  }
  s.max_over_mean_bonds = bonds_sum > 0 ? bonds_max / (bonds_sum / s.ranks) : 1.0;
  s.mean_ghost_ratio = ratio_sum / s.ranks;
  s.mean_halo_bytes = bytes_sum / s.ranks;
  return s;
}

}  // namespace

DecompositionStats decomposition_stats(const Partition& part, const std::vector<int64_t>& offsets,
                                       const std::vector<int32_t>& neighbor, double bytes_per_ghost) {
  const int ranks = part.ranks();
  std::vector<int64_t> bonds(ranks), ghosts(ranks);
  std::vector<int> neighbours(ranks);
  for (int r = 0; r < ranks; ++r) {
    const Halo h = build_halo(part, r, offsets, neighbor);
    bonds[r] = offsets[part.begin[r + 1]] - offsets[part.begin[r]];
    ghosts[r] = static_cast<int64_t>(h.ghosts.size());
    neighbours[r] = static_cast<int>(std::max(h.recv_ranks.size(), h.send_ranks.size()));
  }
  return summarise(part, bonds, ghosts, neighbours, bytes_per_ghost);
}

namespace {

uint64_t compact_bits(uint64_t v) {  // the inverse of morton_spread
  v &= 0x1249249249249249ull;
  v = (v | v >> 2) & 0x10c30c30c30c30c3ull;
  v = (v | v >> 4) & 0x100f00f00f00f00full;
  v = (v | v >> 8) & 0x1f0000ff0000ffull;
  v = (v | v >> 16) & 0x1f00000000ffffull;
  v = (v | v >> 32) & 0x1fffff;
  return v;
}

uint64_t morton_key(int64_t x, int64_t y, int64_t z) {
  return morton_spread(static_cast<uint64_t>(x)) | morton_spread(static_cast<uint64_t>(y)) << 1 |
         morton_spread(static_cast<uint64_t>(z)) << 2;
}

}  // namespace

std::vector<std::array<int, 3>> lattice_family_stencil(double horizon_factor, PartialVolume kind) {
  // Every offset the horizon plus a cell's half diagonal (< 1 spacing) can reach.
  const int reach = static_cast<int>(std::ceil(horizon_factor)) + 1;
  std::vector<std::array<int, 3>> stencil;
  for (int a = -reach; a <= reach; ++a)
    for (int b = -reach; b <= reach; ++b)
      for (int c = -reach; c <= reach; ++c) {
        const double xi[3] = {double(a), double(b), double(c)};  // lattice units: half a cell is 0.5
        if ((a || b || c) && partial_volume_positive(kind, xi, horizon_factor, 0.5, 3)) stencil.push_back({a, b, c});
      }
  return stencil;
}

std::vector<DecompositionStats> lattice_decomposition_stats(const std::array<int64_t, 3>& n,
                                                            const std::vector<std::array<int, 3>>& stencil,
                                                            const std::vector<int>& ranks_list, double bytes_per_ghost,
                                                            int64_t sample, double particle_weight) {
  for (int d = 0; d < 3; ++d)
    if (n[d] < 1 || n[d] > (int64_t{1} << 21)) throw std::invalid_argument("lattice: 1 to 2^21 points per side");
  const int64_t total = n[0] * n[1] * n[2];
  // The points in Morton order: every key of the enclosing power-of-two cube whose
  // coordinates fall inside the box, in key order (no sort needed).
  int64_t side = 1;
  while (side < std::max({n[0], n[1], n[2]})) side *= 2;
  std::vector<uint64_t> keys;
  keys.reserve(static_cast<size_t>(total));
  const uint64_t cube = static_cast<uint64_t>(side) * side * side;
  for (uint64_t key = 0; key < cube; ++key) {
    const int64_t x = compact_bits(key), y = compact_bits(key >> 1), z = compact_bits(key >> 2);
    if (x < n[0] && y < n[1] && z < n[2]) keys.push_back(key);
  }
  auto family = [&](uint64_t key) {  // the stencil clipped to the box
    const int64_t x = compact_bits(key), y = compact_bits(key >> 1), z = compact_bits(key >> 2);
    int64_t count = 0;
    for (const auto& o : stencil) {
      const int64_t a = x + o[0], b = y + o[1], c = z + o[2];
      count += a >= 0 && a < n[0] && b >= 0 && b < n[1] && c >= 0 && c < n[2];
    }
    return count;
  };
  // Prefix sums of bond entries (exact integers) in that order.
  std::vector<int64_t> bonds(static_cast<size_t>(total) + 1, 0);
  {
    std::vector<int64_t> fam(static_cast<size_t>(total));
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < total; ++i) fam[i] = family(keys[i]);
    for (int64_t i = 0; i < total; ++i) bonds[i + 1] = bonds[i] + fam[i];
  }
  std::vector<DecompositionStats> out;
  for (const int ranks : ranks_list) {
    if (ranks < 1 || ranks > total) throw std::invalid_argument("lattice: 1 to one rank per particle");
    // MortonRangePartitioner's cuts on the same weights (bonds + particle_weight each).
    const Partition part = cut_equal_work(total, ranks, [&](int64_t i) {
      return static_cast<double>(bonds[i]) + particle_weight * static_cast<double>(i);
    });
    std::vector<uint64_t> first_key(static_cast<size_t>(ranks));
    for (int r = 0; r < ranks; ++r) first_key[r] = keys[part.begin[r]];
    auto owner_of = [&](uint64_t key) {
      return static_cast<int>(std::upper_bound(first_key.begin(), first_key.end(), key) - first_key.begin()) - 1;
    };
    // Ghosts: a particle is a ghost on every other rank that owns one of its partners.
    const int threads = omp_get_max_threads();
    std::vector<std::vector<int64_t>> ghosts(threads, std::vector<int64_t>(ranks, 0));
    std::vector<std::set<std::pair<int, int>>> links(threads);
#pragma omp parallel
    {
      const int t = omp_get_thread_num();
      std::vector<int> seen;
#pragma omp for schedule(dynamic, 4096)
      for (int64_t i = 0; i < total; i += sample) {
        const uint64_t key = keys[i];
        const int own = owner_of(key);
        const int64_t x = compact_bits(key), y = compact_bits(key >> 1), z = compact_bits(key >> 2);
        seen.clear();
        for (const auto& o : stencil) {
          const int64_t a = x + o[0], b = y + o[1], c = z + o[2];
          if (a < 0 || a >= n[0] || b < 0 || b >= n[1] || c < 0 || c >= n[2]) continue;
          const uint64_t k2 = morton_key(a, b, c);
          // Partners in the own range are the common case: skip the search.
          if (k2 >= first_key[own] && (own + 1 == ranks || k2 < first_key[own + 1])) continue;
          const int r = owner_of(k2);
          if (std::find(seen.begin(), seen.end(), r) == seen.end()) seen.push_back(r);
        }
        for (const int r : seen) {
          ghosts[t][r] += sample;
          links[t].emplace(std::min(r, own), std::max(r, own));
        }
      }
    }
    std::vector<int> neighbours(static_cast<size_t>(ranks), 0);
    std::set<std::pair<int, int>> all_links;
    for (const auto& l : links) all_links.insert(l.begin(), l.end());
    for (const auto& [a, b] : all_links) {
      ++neighbours[a];
      ++neighbours[b];
    }
    std::vector<int64_t> rank_bonds(ranks), rank_ghosts(ranks, 0);
    for (int r = 0; r < ranks; ++r) {
      rank_bonds[r] = bonds[part.begin[r + 1]] - bonds[part.begin[r]];
      for (int t = 0; t < threads; ++t) rank_ghosts[r] += ghosts[t][r];
    }
    const DecompositionStats s = summarise(part, rank_bonds, rank_ghosts, neighbours, bytes_per_ghost);
    out.push_back(s);
  }
  return out;
}

}  // namespace breccia::solver
