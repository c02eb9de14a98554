#pragma once
// Domain decomposition of the PD solver (the distributed-runs work, docs/parallel.md when it
// lands): which rank owns which particles, and which particles of other ranks each rank must
// receive (ghosts) and send every step. PD particles never migrate, so ownership is fixed in
// the reference configuration, and the ghosts are exactly the off-rank bond partners of the
// CSR families: no geometric halo width to guess, so dual horizon and graded meshes are exact.
//
// Particles are held in Morton order (setup.cpp), so contiguous ranges of that order are
// compact in space. `MortonRangePartitioner` cuts it into ranges of equal work (bond entries
// plus a per-particle share); other partitioners (RCB, a graph partitioner) fit the same
// interface.
#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "breccia/common/cell_list.hpp"
#include "breccia/solver/pd_physics.hpp"

namespace breccia::solver {

// Rank r owns the internal indices [begin[r], begin[r + 1]).
struct Partition {
  std::vector<int64_t> begin;  // ranks + 1 offsets, non-decreasing, begin[0] = 0, begin[ranks] = n
  int ranks() const { return static_cast<int>(begin.size()) - 1; }
  int64_t owned(int r) const { return begin[r + 1] - begin[r]; }
  int owner(int64_t i) const;  // binary search
};

class Partitioner {
public:
  virtual ~Partitioner() = default;
  virtual std::string name() const = 0;
  // offsets: the CSR row offsets (n + 1) of the bond families in internal order.
  virtual Partition partition(const std::vector<int64_t>& offsets, int ranks) const = 0;
};

// Contiguous ranges of the internal (Morton) order with equal work: each particle weighs its
// family size plus `particle_weight` bond entries' worth of per-particle work (kick, drift,
// loads, outputs), so a graded mesh with very unequal families still balances the bond loop.
// Throws std::invalid_argument unless 1 <= ranks <= n (at most one rank per particle): the
// partitioners' refusal, which a rank that cuts nothing checks too (cut_partition).
void require_ranks_fit(int64_t n, int ranks);

class MortonRangePartitioner final : public Partitioner {
public:
  explicit MortonRangePartitioner(double particle_weight = 4.0) : particle_weight_(particle_weight) {}
  std::string name() const override { return "morton-ranges"; }
  Partition partition(const std::vector<int64_t>& offsets, int ranks) const override;
  // partition's cuts without the whole offsets: a rank holding the row lengths `sizes` of
  // rows [first, first + sizes.size()) (a slice of the order; `entries_before` the entries
  // of the rows before it, the body's n rows hold body_entries) finds the cuts whose targets
  // fall in its slice: cut[r] for those r in [1, ranks), -1 for the others (ranks entries).
  // Every target falls in exactly one non-empty slice; from_slice_cuts makes the ranges of
  // the ranks' cuts merged, partition's exactly (the same rule, the same ties).
  std::vector<int64_t> slice_cuts(const std::vector<int64_t>& sizes, int64_t first, int64_t entries_before,
                                  int64_t body_n, int64_t body_entries, int ranks) const;
  static Partition from_slice_cuts(const std::vector<int64_t>& cut, int64_t n, int ranks);

private:
  double particle_weight_;
};

// The row lengths of the families setup_system builds (its offsets' differences, bond
// entries per particle), counted without storing a single bond: the pairs build_families
// finds (common's families.hpp: |xi| <= max(horizon) + max(pad), pad = half cell x sqrt(d))
// that the set-up keeps (a positive partial volume from either end under `kind`). Arrays in
// the set-up's internal order: x0 (3N), horizon and half_cell (N). With them the partition
// above can be cut before any family exists: the first pass of a set-up that builds each
// rank's families alone. Memory: the cell list (about 12 B per particle) and the counts.
std::vector<int64_t> family_sizes(const std::vector<double>& x0, const std::vector<double>& horizon,
                                  const std::vector<double>& half_cell, int dimension, PartialVolume kind);
// The same for rows [row_begin, row_end) only (row_end - row_begin counts, the first of row
// row_begin), every particle still a partner: the same integers as the whole count's slice,
// so the ranks of a distributed set-up each count a slice and concatenate them
// (plan_distributed_rows, on the slice's geometric_window, below: the arrays then hold the
// window's particles only). The cell list holds every particle given. Throws
// std::invalid_argument for a range outside [0, N].
std::vector<int64_t> family_sizes(const std::vector<double>& x0, const std::vector<double>& horizon,
                                  const std::vector<double>& half_cell, int dimension, PartialVolume kind,
                                  int64_t row_begin, int64_t row_end);

// The particles a rank's rows [row_begin, row_end) may read before any family exists: the
// rows, then the geometric halo, every other particle j within the pair's reach of some row
// i. build_families pairs i and j when |xi| <= max(h_i, h_j) + max(pad_i, pad_j) (pad:
// partial_volume_reach of the half cell; the dual horizon's partner reaches with its own
// horizon), and family_sizes counts the same pairs. The halo follows each particle's own
// reach: the particles fall in reach classes (h + pad in geometric bins from the smallest, at
// most 8; class c's largest horizon H_c and pad P_c), and each row i marks, for each class c,
// the cells within max(h_i, H_c) + max(pad_i, P_c), times 1 + 1e-6 against rounding, of its
// position (cells of a third of the reach of the pair's coarser class, one grid per class,
// 1 B per cell: a bit per class). j of class c is in the halo when its cell is marked for c.
// So a row in a fine region holds the fine particles within a fine reach and the coarse ones
// within theirs, not the whole body's largest reach: on a graded mesh the window is the rows
// plus a shell about as thick as the local reach (its slack: a cell's diagonal and a class's
// bin; docs/parallel.md, Memory, What to take next, item 2 b). A superset of the rows'
// family ghosts, known from positions alone. Arrays as family_sizes takes them (set-up
// internal order). `index` is ascending (the halo below the rows, the rows, the halo above),
// so a local index orders as the global one: a row built on the window and mapped back
// through `index` is sorted as the whole build's. An empty range has an empty window.
// The cells are marked for groups of nearby rows (consecutive rows within 3 cells on each
// axis), each cell about a group decided once from the group's box and only the doubtful
// ones row by row: the marks of each row alone at a quarter to a third of their cost. O(N +
// the cells within reach of each group's box, per grid it marks, + the doubtful cells' row
// tests) time; memory the window and the grids (each cut to the rows' box grown by its
// reach, at most max(N, 65,536) cells); throws std::invalid_argument for a range outside
// [0, N] or a negative group size. `group_cells`: the groups' extent in cells (0: each row
// alone, the marking the groups must reproduce exactly; the tests compare the two).
inline constexpr double kWindowGroupCells = 3.0;
// geometric_window's reach classes from two folds over the particles, which a distributed
// set-up's ranks take over their slices of the internal order and combine in rank order
// (fold: std::min and std::max, so the same doubles as over the whole body): the smallest
// and largest reach h + pad, then, with the classes' bounds from those, each class's largest
// horizon and pad, presence and box.
inline constexpr int kReachClasses = 8;
struct ReachBounds {
  double rmin = std::numeric_limits<double>::infinity(), rmax = 0.0;
  void fold(const ReachBounds& b);
};
ReachBounds reach_bounds(const std::vector<double>& horizon, const std::vector<double>& half_cell, int dimension);
struct ReachFigures {
  ReachFigures() = default;
  explicit ReachFigures(const ReachBounds& body);
  int class_of(double reach) const;  // reach: h + pad
  void add(const std::vector<double>& x, const std::vector<double>& horizon, const std::vector<double>& half_cell,
           int dimension);
  void fold(const ReachFigures& b);
  double bound[kReachClasses - 1] = {};
  double H[kReachClasses] = {}, P[kReachClasses] = {};
  bool present[kReachClasses] = {};
  BoundingBox box[kReachClasses];  // each class's own particles' box
};

// The marks geometric_window makes for rows [row_begin, row_end) of the arrays (x0 3N,
// horizon and half_cell N) under the body's classes (`body`; its count `body_n` caps each
// grid's cells as geometric_window's): near(x, c) is whether a particle of class c at x is
// in the rows' window, the test geometric_window makes of every other particle; summary():
// what the other ranks choose their candidates by. So a rank holding a slice of the internal
// order forms its rows' window from the particles the other ranks send it (form_window,
// distributed_setup.hpp), the same window as geometric_window over the body.
// A summary of a WindowMarks' grids for the other ranks of a distributed set-up: each grid's
// box and cells, and per block of kMarksBlock^3 cells the union of its cells' bits (the
// blocks with a bit alone, about the window's volume: 9 B per 512 cells). A particle near
// the rows (WindowMarks::near) is in a block with its class's bit (may_be_near): the ranks
// choose the particles they send a rank by it, a superset of its window, and the rank keeps
// those near its rows. Bytes: its form for a concatenation.
inline constexpr long long kMarksBlock = 8;
struct MarksSummary {
  struct Grid {
    bool active = false;
    BoundingBox box{};
    CellGrid grid;
    long long blocks[3] = {0, 0, 0};
    std::vector<int64_t> block;  // the blocks with a bit, ascending
    std::vector<uint8_t> bits;   // theirs
  };
  Grid g[kReachClasses];
  bool may_be_near(const double* x, int c) const;
  std::vector<char> bytes() const;
  static MarksSummary from_bytes(const char* p, size_t size);
};

class WindowMarks {
 public:
  MarksSummary summary() const;
  WindowMarks(const std::vector<double>& x0, const std::vector<double>& horizon, const std::vector<double>& half_cell,
              int dimension, const ReachFigures& body, int64_t body_n, int64_t row_begin, int64_t row_end,
              double group_cells = kWindowGroupCells);
  ~WindowMarks();
  WindowMarks(const WindowMarks&) = delete;
  WindowMarks& operator=(const WindowMarks&) = delete;
  int class_of(int64_t i) const;  // of particle i of the arrays
  bool near(const double* x, int c) const;

 private:
  struct Grids;
  Grids* grids_;
  std::vector<uint8_t> of_;
};

struct GeometricWindow {
  std::vector<int32_t> index;          // global indices, ascending
  int64_t row_begin = 0, row_end = 0;  // the rows' local range in index
  size_t halo() const { return index.size() - static_cast<size_t>(row_end - row_begin); }
};
GeometricWindow geometric_window(const std::vector<double>& x0, const std::vector<double>& horizon,
                                 const std::vector<double>& half_cell, int dimension, int64_t row_begin,
                                 int64_t row_end, double group_cells = kWindowGroupCells);

// What one rank exchanges each step. Ghosts are sorted by internal index; since ranks own
// contiguous ranges, the ghosts from one source rank are one contiguous run of `ghosts`.
struct Halo {
  int rank = 0;
  std::vector<int32_t> ghosts;                    // off-rank particles this rank's families read
  std::vector<int> recv_ranks;                    // source ranks, ascending
  std::vector<int64_t> recv_begin;                // recv_ranks.size() + 1 offsets into ghosts
  std::vector<int> send_ranks;                    // destination ranks, ascending
  std::vector<std::vector<int32_t>> send_lists;   // per destination: owned particles it reads, ascending
};

// The halo of `rank`: ghosts from its own rows, sends from the rows of the other ranks that
// reach into it (the families are symmetric: j in i's family iff i in j's, so the sends are
// also read off this rank's rows).
// `window` (a window system's local -> internal indices, ascending; PdSystem::window_global):
// offsets and neighbor are that system's (local rows and partners). Null: the whole body's.
Halo build_halo(const Partition& part, int rank, const std::vector<int64_t>& offsets,
                const std::vector<int32_t>& neighbor, const std::vector<int32_t>* window = nullptr);

// Figures of a decomposition for docs/performance.md: load balance of the bond loop, ghosts
// per owned particle, bytes exchanged per step.
struct DecompositionStats {
  int ranks = 0;
  int64_t min_owned = 0, max_owned = 0;
  double max_over_mean_bonds = 0.0;   // load imbalance of the bond loop (1 = perfect)
  double mean_ghost_ratio = 0.0;      // ghosts / owned, mean over ranks
  double max_ghost_ratio = 0.0;
  double max_halo_bytes = 0.0;        // per step, largest rank, received
  double mean_halo_bytes = 0.0;
  int max_neighbour_ranks = 0;        // most ranks one rank exchanges with
};
// bytes_per_ghost: what one ghost carries per step (PMB: displacement, 24 B; LPS adds the
// dilatation and the fast path's two factors between its passes, 24 B more).
DecompositionStats decomposition_stats(const Partition& part, const std::vector<int64_t>& offsets,
                                       const std::vector<int32_t>& neighbor, double bytes_per_ghost);

// The family of a point of a 3D box lattice far from its faces, as offsets in lattice units:
// the neighbours the set-up keeps (setup.cpp) at a horizon of `horizon_factor` spacings
// under the partial-volume rule `kind`. A point near a face has this stencil clipped to the
// box. For the figures below, which need no families built.
std::vector<std::array<int, 3>> lattice_family_stencil(double horizon_factor, PartialVolume kind);

// The same figures for a box lattice of n[0] x n[1] x n[2] points whose every point's
// family is `stencil` (offsets in lattice units) clipped to the box, without building the
// families: for lattices too large to set up on one process (10^8 particles and more).
// The order is the Morton order of the lattice indices, cut as MortonRangePartitioner cuts
// (equal bond entries + particle_weight per particle); bond balance is exact; ghosts are
// counted from every `sample`-th particle of that order and scaled (1: exact; the tests
// compare sample 1 with build_halo), and so are the neighbour-rank counts (a lower bound
// when sampled).
std::vector<DecompositionStats> lattice_decomposition_stats(const std::array<int64_t, 3>& n,
                                                            const std::vector<std::array<int, 3>>& stencil,
                                                            const std::vector<int>& ranks, double bytes_per_ghost,
                                                            int64_t sample = 1, double particle_weight = 4.0);

}  // namespace breccia::solver
