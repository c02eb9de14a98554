#pragma once
// The intact bond graph of one output: the reference families (rebuilt from positions and
// horizons, they are not stored) minus the bonds broken by fracture minus the pre-cracks.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "breccia/solver/family.hpp"

namespace breccia::postproc {

// Removed bonds as a CSR keyed by the lower index: partners of i are the j > i removed,
// sorted, so "is (i, j) removed" is a short binary search.
class RemovedBonds {
public:
  RemovedBonds() = default;
  // pairs: 2B (i, j) in any order; n: particle count. Out-of-range indices are ignored by
  // the caller's validation (see validate_pairs).
  RemovedBonds(std::span<const int64_t> pairs, size_t n);
  bool contains(int64_t i, int64_t j) const;
  std::span<const int32_t> partners_above(size_t i) const {
    return {partners_.data() + offsets_[i], partners_.data() + offsets_[i + 1]};
  }
  size_t size() const { return partners_.size(); }

private:
  std::vector<int64_t> offsets_;
  std::vector<int32_t> partners_;
};

// Throws InputError naming file/dataset when an index is out of [0, n) or i == j.
void validate_pairs(std::span<const int64_t> pairs, size_t n, const std::string& file,
                    const std::string& dataset);

// Component label of every particle over bonds of `families` that are in neither removed set.
std::vector<int32_t> intact_components(const solver::Families& families, const RemovedBonds& broken,
                                       const RemovedBonds& precracks, int32_t* component_count);

}  // namespace breccia::postproc
