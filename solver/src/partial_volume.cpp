#include <cmath>
#include <cstdint>
#include <cstring>

#include "breccia/solver/partial_volume_lattice.hpp"
#include "breccia/solver/pd_physics.hpp"

namespace breccia::solver {

// The count of j's cell's n^d sample points inside i's horizon, each point's squared distance
// summed as (px^2 + py^2) + pz^2 (2D: pz = xi_z, one z sample). The set-up asks it for every
// candidate entry (80 million on the full concrete case), so it is written for speed, each
// step exact:
// - the early accept and reject by the cell's half diagonal (the definition's own, with a
//   margin of a sixth of it over the samples' reach);
// - the samples' box: the sample with the smallest square on each axis is a sample, and so is
//   the one with the largest, and floating-point addition is monotonic, so when the first is
//   outside every sample is and when the second is inside every sample is;
// - else every sample point is tested, without a branch (count_every_sample; the per-row
//   shortcuts it replaced mispredicted a branch a row). Settling whole slabs of 36 samples
//   first by the same monotonicity (2.6 of 6 slabs left on average) was measured too: no
//   faster, the branches' mispredictions eating the comparisons saved (docs/performance-log.md);
// - a count asked before by this thread for an offset within a grid step (2^-30 horizons)
//   is looked up where every sample is farther than that from the sphere, where such counts
//   recur (a lattice); where they do not (a graded mesh) the memo steps aside.
namespace {

// The full quadrature's counts, kept per thread by their offset x_j - x_i rounded to a grid
// of 2^-30 horizons (and the exact horizon, cell and dimension): on a lattice the same few
// hundred offsets between cells recur in every row, each in a few roundings of x_j - x_i
// (3.0 million distinct bit patterns at 41^3). A count is stored only where every sample
// point's squared distance is farther from the horizon's square than any offset within a
// grid step (and the arithmetic's rounding) can move it: then each sample is inside or
// outside for every offset of the key, and a count looked up is the count the quadrature
// would compute, exactly. Samples on or within that margin of the sphere (a lattice whose
// horizon is a whole number of half-cells) are counted every time. A slot holds the last key
// hashed to it (0 in `count_plus_one`: empty; thread_local and zero-initialised, so no guard
// per call and no initial image of its 400 KB in the binary's thread-local data).
//
// On a graded mesh offsets rarely recur: there the hash, the compare and the slot's store cost
// 6-10% of the bond-coefficient phase for nothing (full concrete case, paired runs,
// docs/performance-log.md). So the memo watches its hits over windows of kWindow full counts, and
// after a window with under one hit in eight it stands aside for kRest windows, then
// tries again; each trial window that fails again doubles the rest (plus one), up to kRestMost
// windows, and a window with hits sets it back to kRest. A graded case then pays for a
// sixteenth of its first 4,096 x 16 counts' lookups and under one in 256 of the rest (the
// fixed rest's sixteenth was 0.2 CPU s of slot misses on the full concrete case's 71 million
// candidates, docs/performance-log.md); a lattice that follows a graded stretch waits at most
// kRestMost windows (a million counts). A key's
// first count only marks its slot (kSeen): the margin check, 216 scalar distances, a quarter
// of the graded mesh's count time when every first count paid it (docs/performance-log.md), is
// done at a key's second count, when keys recur. The counts are the same either way: the
// memo only decides whether a count is computed or looked up.
struct CountMemo {
  static constexpr int kBits = 13;
  static constexpr int kWindow = 4096, kRest = 15, kRestMost = 255;
  struct Slot {
    int64_t offset[3];       // x_j - x_i in grid steps (kGridStep horizons)
    uint64_t exact[2];       // the horizon's and the half cell's bits
    int dimension;
    int count_plus_one;      // 0: empty; kSeen: counted once, not kept; kNear: a sample near the sphere
  };
  static constexpr int kSeen = -1, kNear = -2;
  Slot slot[1 << kBits] = {};
  int calls = 0, hits = 0, resting = 0;  // in the current window; windows left to stand aside
  int failed_trials = 0;                  // trial windows without hits since the last with hits

  // Whether this full count consults the memo; the window's bookkeeping.
  bool in_use() {
    if (++calls == kWindow) {
      if (resting > 0) {
        --resting;
      } else if (hits < kWindow / 8) {
        // kRest, 2 kRest + 1, ...: (kRest + 1) 2^failed - 1 windows, at most kRestMost.
        resting = failed_trials < 4 ? ((kRest + 1) << failed_trials) - 1 : kRestMost;
        failed_trials += failed_trials < 4;
      } else {
        failed_trials = 0;
      }
      calls = hits = 0;
    }
    return resting == 0;
  }
};
constexpr double kGridStep = 0x1p-30;  // of the horizon
constinit thread_local CountMemo count_memo;

// Each axis's squared sample coordinates of j's cell at offset xi; 2D's single z "sample" is
// the point's own z, and its unused lanes +inf (s + inf is never inside).
void sample_squares(const double xi[3], double half_cell_j, int dimension, double sq[3][kPartialVolumeSamples]) {
  constexpr int n = kPartialVolumeSamples;
  const double h = 2.0 * half_cell_j / n;
  for (int axis = 0; axis < 3; ++axis)
    for (int a = 0; a < n; ++a) {
      const double p = xi[axis] - half_cell_j + (a + 0.5) * h;
      sq[axis][a] = p * p;
    }
  if (dimension != 3) {
    sq[2][0] = xi[2] * xi[2];
    for (int c = 1; c < n; ++c) sq[2][c] = INFINITY;
  }
}

// The smallest distance of a sample's squared distance, summed as the count sums it, from r2.
double sample_margin(const double sq[3][kPartialVolumeSamples], double r2, int dimension) {
  constexpr int n = kPartialVolumeSamples;
  const int nz = dimension == 3 ? n : 1;
  double margin = INFINITY;
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b) {
      const double row = sq[0][a] + sq[1][b];
      for (int c = 0; c < nz; ++c) {
        const double gap = std::fabs((row + sq[2][c]) - r2);
        margin = gap < margin ? gap : margin;
      }
    }
  return margin;
}

// How far another offset within `step` per axis of xi (and the arithmetic's rounding) can move
// a sample's squared distance: a sample coordinate p moves by at most step (1.01: the rounding
// of the offset's own arithmetic), its square by step (2 |p| + step), |p| <= |xi| + half cell;
// 1e-12 r^2 is far above the few ulp of r^2 that rounding the coordinates and sums adds.
double sample_shift_bound(const double xi[3], double half_cell_j, double step, double r2) {
  return 1.01 * step * (2.0 * (std::fabs(xi[0]) + std::fabs(xi[1]) + std::fabs(xi[2]) + 3.0 * half_cell_j) + 3.03 * step) +
         1e-12 * r2;
}

// Every sample tested, without a branch: each row's sum (x^2 + y^2) against the 6 z squares,
// each comparison giving -1 or 0 per lane (GCC/Clang vector extension). Two bodies, the same
// sums and comparisons (the same count, bit for bit), the loader picking one for the CPU
// (GCC's function multiversioning): the portable one (SSE2 on x86-64, NEON on ARM, scalar
// elsewhere) the z squares in pairs, and with AVX2 four and two, which compares a row in
// two instructions instead of three, with no register copies (VEX's three operands): 45
// against 53 ns per candidate entry of the mid-size concrete case (docs/performance-log.md).
// 2D: one z sample, the other z lanes +inf (s + inf is never inside).
__attribute__((target("default"))) int count_every_sample(const double sq[3][kPartialVolumeSamples], double r2) {
  constexpr int n = kPartialVolumeSamples;
  static_assert(n % 2 == 0, "the z samples are taken in pairs");
  typedef double Pair __attribute__((vector_size(16)));
  typedef long long Mask __attribute__((vector_size(16)));
  Pair z[n / 2];
  for (int c = 0; c < n / 2; ++c) z[c] = Pair{sq[2][2 * c], sq[2][2 * c + 1]};
  const Pair limit = {r2, r2};
  Mask inside = {0, 0};
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b) {
      const double row = sq[0][a] + sq[1][b];
      const Pair s = {row, row};
      for (int c = 0; c < n / 2; ++c) inside -= (s + z[c] <= limit);  // true is -1
    }
  return static_cast<int>(inside[0] + inside[1]);
}

__attribute__((target("avx2"))) int count_every_sample(const double sq[3][kPartialVolumeSamples], double r2) {
  static_assert(kPartialVolumeSamples == 6, "four z squares and two");
  constexpr int n = kPartialVolumeSamples;
  typedef double Pair __attribute__((vector_size(16)));
  typedef long long Mask __attribute__((vector_size(16)));
  typedef double Quad __attribute__((vector_size(32)));
  typedef long long QuadMask __attribute__((vector_size(32)));
  const Quad z4 = {sq[2][0], sq[2][1], sq[2][2], sq[2][3]};
  const Pair z2 = {sq[2][4], sq[2][5]};
  const Quad limit4 = {r2, r2, r2, r2};
  const Pair limit2 = {r2, r2};
  QuadMask inside4 = {0, 0, 0, 0};
  Mask inside2 = {0, 0};
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b) {
      const double row = sq[0][a] + sq[1][b];
      const Quad s4 = {row, row, row, row};
      const Pair s2 = {row, row};
      inside4 -= (s4 + z4 <= limit4);
      inside2 -= (s2 + z2 <= limit2);
    }
  return static_cast<int>((inside4[0] + inside4[1]) + (inside4[2] + inside4[3]) + (inside2[0] + inside2[1]));
}

}  // namespace

namespace {
double offset_length(const double xi[3]) { return std::sqrt(xi[0] * xi[0] + xi[1] * xi[1] + xi[2] * xi[2]); }

// The count at offset xi of length len (offset_length(xi)).
int samples_inside_at(const double xi[3], double len, double horizon, double half_cell_j, int dimension) {
  constexpr int n = kPartialVolumeSamples;
  const double reach = partial_volume_half_diagonal(half_cell_j, dimension);
  if (len + reach <= horizon) return partial_volume_sample_total(dimension);
  if (len - reach >= horizon) return 0;
  const int nz = dimension == 3 ? n : 1;
  double sq[3][n];
  sample_squares(xi, half_cell_j, dimension, sq);
  double lo[3], hi[3];
  for (int axis = 0; axis < 3; ++axis) {
    const int count = axis == 2 ? nz : n;
    lo[axis] = hi[axis] = sq[axis][0];
    for (int a = 1; a < count; ++a) {
      lo[axis] = sq[axis][a] < lo[axis] ? sq[axis][a] : lo[axis];
      hi[axis] = sq[axis][a] > hi[axis] ? sq[axis][a] : hi[axis];
    }
  }
  const double r2 = horizon * horizon;
  if ((lo[0] + lo[1]) + lo[2] > r2) return 0;
  if ((hi[0] + hi[1]) + hi[2] <= r2) return partial_volume_sample_total(dimension);
  const bool memo = count_memo.in_use();
  const double step = kGridStep * horizon;
  int64_t offset[3];
  uint64_t exact[2];
  CountMemo::Slot* slot = nullptr;
  bool seen = false;  // the slot holds this key
  if (memo) {
    // Rounded to the nearest step by the 1.5 * 2^52 shift (exact for |v| < 2^51; |xi| / step
    // is below 2^32): no division, no library call per count.
    const double per_step = 1.0 / step, shift = 0x1.8p52;
    for (int axis = 0; axis < 3; ++axis) offset[axis] = static_cast<int64_t>((xi[axis] * per_step + shift) - shift);
    std::memcpy(&exact[0], &horizon, sizeof(double));
    std::memcpy(&exact[1], &half_cell_j, sizeof(double));
    // Each word mixed into the high bits (the slot's index); a plain xor-multiply chain maps
    // offsets that differ in sign alone to one slot.
    uint64_t hash = static_cast<uint64_t>(dimension);
    auto mix = [&hash](uint64_t k) {
      hash = (hash ^ k) * 0x9E3779B97F4A7C15ull;
      hash ^= hash >> 29;
    };
    for (int64_t k : offset) mix(static_cast<uint64_t>(k));
    for (uint64_t k : exact) mix(k);
    slot = &count_memo.slot[hash >> (64 - CountMemo::kBits)];
    seen = slot->count_plus_one != 0 && slot->dimension == dimension && std::memcmp(slot->offset, offset, sizeof offset) == 0 &&
           std::memcmp(slot->exact, exact, sizeof exact) == 0;
    if (seen && slot->count_plus_one > 0) {
      ++count_memo.hits;
      return slot->count_plus_one - 1;
    }
  }
  const int count = count_every_sample(sq, r2);
  if (memo && !seen) {  // the key's first count here: marked only
    std::memcpy(slot->offset, offset, sizeof offset);
    std::memcpy(slot->exact, exact, sizeof exact);
    slot->dimension = dimension;
    slot->count_plus_one = CountMemo::kSeen;
  } else if (memo && slot->count_plus_one == CountMemo::kSeen) {
    // The key recurs. Every sample's distance from the sphere, in the sums just compared,
    // against how far another offset of the key moves it: two offsets of one key differ by at
    // most a grid step per axis. A key that fails is not checked again (kNear).
    slot->count_plus_one = sample_margin(sq, r2, dimension) > sample_shift_bound(xi, half_cell_j, step, r2)
                               ? count + 1
                               : CountMemo::kNear;
  }
  return count;
}
}  // namespace

int partial_volume_samples_inside(const double xi[3], double horizon, double half_cell_j, int dimension) {
  return samples_inside_at(xi, offset_length(xi), horizon, half_cell_j, dimension);
}

void partial_volume_pair_samples_inside(const double xi[3], double horizon_i, double half_cell_j, double horizon_j,
                                        double half_cell_i, int dimension, int& own, int& reverse) {
  // -xi's length is xi's, bit for bit: (-a)(-a) = a a exactly.
  const double len = offset_length(xi);
  const double xm[3] = {-xi[0], -xi[1], -xi[2]};
  own = samples_inside_at(xi, len, horizon_i, half_cell_j, dimension);
  reverse = samples_inside_at(xm, len, horizon_j, half_cell_i, dimension);
}

LatticeSampleCounts::LatticeSampleCounts(double horizon, double half_cell, int dimension)
    : horizon_(horizon),
      half_cell_(half_cell),
      spacing_(2.0 * half_cell),
      per_spacing_(1.0 / spacing_),
      dimension_(dimension) {
  // Offsets beyond horizon + reach have no sample inside; one more for the rounding.
  reach_ = static_cast<int>(std::ceil((horizon + partial_volume_half_diagonal(half_cell, dimension)) / spacing_)) + 1;
  const int side = 2 * reach_ + 1;
  tolerance_ = kLatticeTolerance * spacing_;
  const double r2 = horizon * horizon;
  count_.assign(static_cast<size_t>(side) * side * (dimension == 3 ? side : 1), -1);
  for (int c = (dimension == 3 ? -reach_ : 0); c <= (dimension == 3 ? reach_ : 0); ++c)
    for (int b = -reach_; b <= reach_; ++b)
      for (int a = -reach_; a <= reach_; ++a) {
        // The lattice offset as counts() rebuilds it, and whether every offset within the
        // tolerance of it has the same samples inside (then the same count, exactly).
        const double xi[3] = {a * spacing_, b * spacing_, c * spacing_};
        double sq[3][kPartialVolumeSamples];
        sample_squares(xi, half_cell, dimension, sq);
        if (!(sample_margin(sq, r2, dimension) > sample_shift_bound(xi, half_cell, tolerance_, r2))) continue;
        count_[index(a, b, c)] = static_cast<int16_t>(partial_volume_samples_inside(xi, horizon, half_cell, dimension));
      }
}

int LatticeSampleCounts::counted(const double xi[3]) const {
  return partial_volume_samples_inside(xi, horizon_, half_cell_, dimension_);
}

}  // namespace breccia::solver
