#pragma once
// Disjoint sets with path compression (halving) and union by rank: near-constant
// amortised time per operation (Tarjan 1975), so 10^7 bonds cost well under a second.
// The one union-find of every stage: post-processing's fragments and crack faces, and MPS's
// fragment labels (solver/mps/src/fracture.cpp).
#include <cstdint>
#include <numeric>
#include <vector>

namespace breccia {

class UnionFind {
public:
  explicit UnionFind(size_t n) : parent_(n), rank_(n, 0) {
    std::iota(parent_.begin(), parent_.end(), int32_t{0});
  }
  size_t size() const { return parent_.size(); }

  int32_t find(int32_t x) {
    while (parent_[x] != x) {
      parent_[x] = parent_[parent_[x]];
      x = parent_[x];
    }
    return x;
  }

  // Returns true when a and b were in different sets.
  bool unite(int32_t a, int32_t b) {
    a = find(a);
    b = find(b);
    if (a == b) return false;
    if (rank_[a] < rank_[b]) std::swap(a, b);
    parent_[b] = a;
    if (rank_[a] == rank_[b]) ++rank_[a];
    return true;
  }

  // Dense labels 0..count-1, numbered in order of each set's first member.
  std::vector<int32_t> labels(int32_t* count = nullptr) {
    std::vector<int32_t> label(parent_.size(), -1), of_root(parent_.size(), -1);
    int32_t next = 0;
    for (size_t i = 0; i < parent_.size(); ++i) {
      const int32_t r = find(static_cast<int32_t>(i));
      if (of_root[r] < 0) of_root[r] = next++;
      label[i] = of_root[r];
    }
    if (count) *count = next;
    return label;
  }

private:
  std::vector<int32_t> parent_;
  std::vector<uint8_t> rank_;
};

}  // namespace breccia
