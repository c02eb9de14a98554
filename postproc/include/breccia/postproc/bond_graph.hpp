#pragma once
// The intact bond graph of one output: the run's bonds (results.h5 /bonds, each pair once
// from its lower index) minus the bonds broken by fracture (one bit per bond and output)
// minus the pre-cracks. The older pair-list form (RemovedBonds) serves pre-cracks and tests.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "breccia/common/families.hpp"

namespace breccia::postproc {

// A set of bonds that answers "is (i, j) in it" (crack faces ask this of every face).
class BondSet {
public:
  virtual ~BondSet() = default;
  virtual bool contains(int64_t i, int64_t j) const = 0;
  // The same for candidate face f of particles (i, j); a set may answer it from a per-face
  // cache (BondBits), saving a search per face and output.
  virtual bool contains_face(size_t /*f*/, int64_t i, int64_t j) const { return contains(i, j); }
};

// Removed bonds as a CSR keyed by the lower index: partners of i are the j > i removed,
// sorted, so "is (i, j) removed" is a short binary search.
class RemovedBonds : public BondSet {
public:
  RemovedBonds() = default;
  // pairs: 2B (i, j) in any order; n: particle count. Out-of-range indices are ignored by
  // the caller's validation (see validate_pairs).
  RemovedBonds(std::span<const int64_t> pairs, size_t n);
  bool contains(int64_t i, int64_t j) const override;
  std::span<const int32_t> partners_above(size_t i) const {
    return {partners_.data() + offsets_[i], partners_.data() + offsets_[i + 1]};
  }
  size_t size() const { return partners_.size(); }

private:
  std::vector<int64_t> offsets_;
  std::vector<int32_t> partners_;
};

// Bit b of a per-bond bit array: byte b / 8, bit b % 8, least significant first.
inline bool bond_bit(std::span<const uint8_t> bits, int64_t b) { return (bits[b >> 3] >> (b & 7)) & 1; }
size_t count_bits(std::span<const uint8_t> bits);

// Position of bond (i, j) in a half list (Families holding only partners j > i, as
// results.h5 /bonds stores them), or -1 when the pair is not a bond.
int64_t bond_index(const Families& half, int64_t i, int64_t j);

// The bonds of a half list whose bit is set: the bonds broken by fracture at one output.
// face_bond (optional): bond_index of each candidate face's pair, computed once per run.
// Holds references: `half`, `bits` and `face_bond` must outlive it.
class BondBits : public BondSet {
public:
  BondBits(const Families& half, std::span<const uint8_t> bits, std::span<const int64_t> face_bond = {})
      : half_(&half), bits_(bits), face_bond_(face_bond) {}
  bool contains(int64_t i, int64_t j) const override {
    const int64_t b = bond_index(*half_, i, j);
    return b >= 0 && bond_bit(bits_, b);
  }
  bool contains_face(size_t f, int64_t i, int64_t j) const override {
    if (face_bond_.empty()) return contains(i, j);
    return face_bond_[f] >= 0 && bond_bit(bits_, face_bond_[f]);
  }

private:
  const Families* half_;
  std::span<const uint8_t> bits_;
  std::span<const int64_t> face_bond_;
};

// Throws InputError naming file/dataset when an index is out of [0, n) or i == j.
void validate_pairs(std::span<const int64_t> pairs, size_t n, const std::string& file,
                    const std::string& dataset);

// Component label of every particle over bonds of `families` that are in neither removed set.
std::vector<int32_t> intact_components(const Families& families, const RemovedBonds& broken,
                                       const RemovedBonds& precracks, int32_t* component_count);

// The same over a half list: bonds b with bond_bit(graph, b) set (all when `graph` is
// empty), bond_bit(broken, b) clear and not in `precracks`.
std::vector<int32_t> intact_components(const Families& half, std::span<const uint8_t> graph,
                                       std::span<const uint8_t> broken, const RemovedBonds& precracks,
                                       int32_t* component_count);

}  // namespace breccia::postproc
