#pragma once
// The partial-volume sample counts of a uniform lattice (one spacing, one horizon) by its
// integer offsets: host only, solver/src/partial_volume.cpp.
#include <cmath>
#include <cstdint>
#include <vector>

namespace breccia::solver {

// On a lattice of spacing 2 half_cell every candidate offset x_j - x_i is an integer offset
// times the spacing, to the rounding of the positions' differences. The set-up asks for the
// count of every candidate entry and of its reverse (12.6 million calls each at 41^3, each a
// square root, the sample box and a hash of the offset, docs/performance-log.md): here each integer
// offset's count is computed once, at the offset itself, and kept only where no sample lies
// within reach of the sphere for any offset within kLatticeTolerance spacings of it (the same
// margin argument as the rounded-offset memo's, partial_volume.cpp). count(xi) returns the
// kept count when xi lies within that tolerance of a kept offset, and otherwise asks
// partial_volume_samples_inside: either way the count partial_volume_samples_inside(xi,
// horizon, half_cell, dimension) gives, bit for bit.
class LatticeSampleCounts {
 public:
  static constexpr double kLatticeTolerance = 0x1p-24;  // of the spacing, per axis
  LatticeSampleCounts(double horizon, double half_cell, int dimension);
  // The counts of j's cell in i's horizon at xi = x_j - x_i (`own`) and of i's cell in j's
  // horizon at -xi (`reverse`, the reverse entry's own count): both looked up by one
  // rounding, since -xi lies as near -o as xi lies near o.
  void counts(const double xi[3], int& own, int& reverse) const {
    // The nearest lattice offset, by the 1.5 * 2^52 shift (exact for |v| < 2^51).
    const double shift = 0x1.8p52;
    int o[3] = {0, 0, 0};
    bool near = dimension_ == 3 || xi[2] == 0.0;
    for (int axis = 0; axis < (dimension_ == 3 ? 3 : 2); ++axis) {
      const double r = (xi[axis] * per_spacing_ + shift) - shift;
      near = near && std::fabs(r) <= reach_ && std::fabs(xi[axis] - r * spacing_) <= tolerance_;
      o[axis] = near ? static_cast<int>(r) : 0;
    }
    own = near ? count_[index(o[0], o[1], o[2])] : -1;
    reverse = near ? count_[index(-o[0], -o[1], -o[2])] : -1;
    if (own < 0) own = counted(xi);
    if (reverse < 0) {
      const double xm[3] = {-xi[0], -xi[1], -xi[2]};
      reverse = counted(xm);
    }
  }

 private:
  int counted(const double xi[3]) const;  // partial_volume_samples_inside
  size_t index(int a, int b, int c) const {
    const size_t side = static_cast<size_t>(2 * reach_ + 1);
    return (static_cast<size_t>(c + (dimension_ == 3 ? reach_ : 0)) * side + static_cast<size_t>(b + reach_)) * side +
           static_cast<size_t>(a + reach_);
  }
  double horizon_, half_cell_, spacing_, per_spacing_, tolerance_ = 0.0;
  int dimension_, reach_ = 0;
  std::vector<int16_t> count_;  // -1: not kept (a sample near the sphere), asked per call
};

}  // namespace breccia::solver
