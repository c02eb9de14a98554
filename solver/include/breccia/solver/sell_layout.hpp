#pragma once
// SELL-C-sigma: the bond entries of a CSR (one row per particle, in the row's order) stored so
// that the k-th entries of the C particles of a slice lie next to each other. A device thread
// per slice lane (one particle) then reads, at each step of its row, the neighbour of the
// C - 1 threads beside it: a warp's load of xi_len is one 256-byte line instead of 32 lines
// (docs/cuda.md, "SELL-C-sigma"). Within windows of sigma particles the rows are sorted by
// length (longest first, ties in index order), so the rows of a slice have similar lengths and
// little padding is needed; a slice is as wide as its longest row.
//
// Nothing is renumbered: a lane names its particle (`particle`), an entry keeps its
// neighbour's original index, and each row's entries keep their CSR order, so a kernel walking
// a lane's entries sums them in the order the CSR loop does (bit-for-bit agreement).
#include <cstdint>
#include <stdexcept>
#include <vector>

#include "breccia/solver/hd.hpp"

namespace breccia::solver {

// What a kernel reads of the layout (raw pointers, host or device memory).
struct SellView {
  int64_t lanes = 0;   // slices x chunk (0: no layout)
  int chunk = 0;       // C, particles per slice
  const int64_t* slice_offset = nullptr;  // slices + 1: first entry of each slice
  const int32_t* particle = nullptr;      // per lane: its particle, -1 for the lanes after the last
  const int32_t* row_length = nullptr;    // per lane: entries of its row (0 for an empty lane)
  const int64_t* csr_entry = nullptr;     // per padded entry: its CSR index, -1 for padding
  // The CSR's bond state, kept current by the SELL passes (a break is written to both), so
  // that whatever reads the CSR (loads, diagnostics, measures, downloads) sees every break.
  uint8_t* csr_state = nullptr;
  // Entry `k` of lane `lane` (k < row_length[lane]).
  BRECCIA_HD int64_t entry(int64_t lane, int64_t k) const {
    const int64_t slice = lane / chunk;
    return slice_offset[slice] + k * chunk + (lane - slice * chunk);
  }
};

// The layout built on the host (sell_layout.cpp).
struct SellLayout {
  int chunk = 32;
  int sigma = 1;
  int64_t particles = 0;
  int64_t slices = 0;
  std::vector<int64_t> slice_offset;  // slices + 1
  std::vector<int32_t> particle;      // slices x chunk
  std::vector<int32_t> row_length;    // slices x chunk
  std::vector<int64_t> csr_entry;     // slice_offset.back()
  int64_t lanes() const { return slices * chunk; }
  int64_t padded_entries() const { return slice_offset.empty() ? 0 : slice_offset.back(); }
  int64_t width(int64_t slice) const { return (slice_offset[slice + 1] - slice_offset[slice]) / chunk; }
  // The CSR's per-entry array in the layout's order; `pad` fills the padding.
  template <class T>
  std::vector<T> gather(const std::vector<T>& csr, T pad) const {
    std::vector<T> out(csr_entry.size(), pad);
    for (size_t e = 0; e < csr_entry.size(); ++e)
      if (csr_entry[e] >= 0) out[e] = csr[static_cast<size_t>(csr_entry[e])];
    return out;
  }
  // The neighbours in the layout's order; a padding entry names its lane's own particle (or
  // particle 0 in an empty lane), so that a loop that does read it stays inside the arrays.
  std::vector<int32_t> gather_neighbors(const std::vector<int32_t>& csr) const {
    std::vector<int32_t> out = gather(csr, int32_t{0});
    for (int64_t lane = 0; lane < lanes(); ++lane) {
      const int64_t slice = lane / chunk;
      for (int64_t k = row_length[lane]; k < width(slice); ++k)
        out[slice_offset[slice] + k * chunk + (lane - slice * chunk)] = particle[lane] < 0 ? 0 : particle[lane];
    }
    return out;
  }
  // Entry values back into the CSR's order (padding dropped).
  template <class T>
  void scatter(const std::vector<T>& sell, std::vector<T>& csr) const {
    for (size_t e = 0; e < csr_entry.size(); ++e)
      if (csr_entry[e] >= 0) csr[static_cast<size_t>(csr_entry[e])] = sell[e];
  }
  // Padded entries per real entry (1 = no padding).
  double padding_factor() const;
  SellView view(uint8_t* csr_state) const {
    return {lanes(), chunk, slice_offset.data(), particle.data(), row_length.data(), csr_entry.data(), csr_state};
  }
};

// The per-entry arrays of the layout's passes (sell_kernels.hpp SellEntriesT) in the layout's
// order, from the CSR's; padding: the lane's particle as neighbour, length 1, moduli and
// critical stretches 0, state 0 (broken: a loop that reads it adds +0). The dual halves and
// the damage weights (vol_own, or the own counts own_count where the system holds those:
// pd_system.hpp; padding 0) only where given (variable horizons; empty otherwise).
template <class Real>
struct SellBondArrays {
  std::vector<int32_t> neighbor;
  std::vector<Real> xi_len, k_own;
  std::vector<float> s0_own;
  std::vector<uint8_t> state;
  std::vector<Real> k_dual;
  std::vector<float> s0_dual;
  std::vector<Real> vol_own;
  std::vector<uint8_t> own_count;
};
template <class Real>
SellBondArrays<Real> gather_sell_bonds(const SellLayout& layout, const std::vector<int32_t>& neighbor,
                                       const std::vector<Real>& xi_len, const std::vector<Real>& k_own,
                                       const std::vector<float>& s0_own, const std::vector<uint8_t>& state,
                                       const std::vector<Real>& k_dual = {}, const std::vector<float>& s0_dual = {},
                                       const std::vector<Real>& vol_own = {},
                                       const std::vector<uint8_t>& own_count = {}) {
  return {layout.gather_neighbors(neighbor),
          layout.gather(xi_len, Real(1)),
          layout.gather(k_own, Real(0)),
          layout.gather(s0_own, 0.0f),
          layout.gather(state, uint8_t{0}),
          k_dual.empty() ? std::vector<Real>{} : layout.gather(k_dual, Real(0)),
          s0_dual.empty() ? std::vector<float>{} : layout.gather(s0_dual, 0.0f),
          vol_own.empty() ? std::vector<Real>{} : layout.gather(vol_own, Real(0)),
          own_count.empty() ? std::vector<uint8_t>{} : layout.gather(own_count, uint8_t{0})};
}

// Builds SELL-C-sigma from CSR row offsets (n + 1 values). `chunk` >= 1; `sigma` 1 (no
// sorting) or a multiple of `chunk`. Throws std::invalid_argument naming the bad argument.
SellLayout build_sell_layout(const std::vector<int64_t>& offsets, int chunk = 32, int sigma = 256);

}  // namespace breccia::solver
