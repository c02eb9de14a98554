#pragma once
// The bond passes between output steps (no diagnostics, brittle bonds) over the SELL-C-sigma
// layout of sell_layout.hpp: one call per slice lane, i.e. per particle, walking that particle's
// entries in its CSR row's order. Two paths, each its own launch: the fast passes of one
// constant horizon (pmb_fast_entry, lps_fast_entry and their breaks, in pd_kernels.hpp's
// ordered_fast_loop) and the dual-horizon pass (variable horizons: pd_kernels.hpp's
// general_force_row, the CSR's general loop itself); LPS's first pass (lps_dilatation_entry)
// serves both. The physics is read through a view whose per-entry arrays are the layout's, and
// every sum runs in the CSR loop's order, so the results are the CSR passes' bit for bit
// (padding is never visited: a lane stops at its row's length).
#include <cstdint>

#include "breccia/solver/pd_kernels.hpp"
#include "breccia/solver/sell_layout.hpp"

namespace breccia::solver {

// The per-entry arrays the layout's passes read, in the layout's order (padding: state 0, the
// neighbour the lane's own particle, lengths 1, moduli, volumes and stretches 0). The dual
// halves and the damage weights only with variable horizons (null with one constant horizon,
// where the fast passes read one half and the diagnostic passes run on the CSR).
template <class Real>
struct SellEntriesT {
  const int32_t* neighbor = nullptr;
  const Real* xi_len = nullptr;
  const Real* k_own = nullptr;
  const float* s0_own = nullptr;
  uint8_t* state = nullptr;
  const Real* k_dual = nullptr;
  const float* s0_dual = nullptr;
  const Real* vol_own = nullptr;
  const uint8_t* own_count = nullptr;  // the damage weights as own counts (pd_kernels.hpp own_volume)
};

// `p` with its per-entry arrays replaced by the layout's; the arrays the layout's passes never
// read (offsets, damage weights, softening) are cleared, so that a path that did read them
// would fault rather than read the CSR's order.
template <class Real>
BRECCIA_HD PdViewT<Real> sell_entry_view(PdViewT<Real> p, const SellEntriesT<Real>& e) {
  p.offsets = nullptr;
  p.neighbor = e.neighbor;
  p.xi_len = e.xi_len;
  p.k_own = e.k_own;
  p.k_dual = e.k_dual;
  p.vol_own = e.vol_own;
  p.own_count = e.own_count;
  p.s0_own = e.s0_own;
  p.s0_dual = e.s0_dual;
  p.state = e.state;
  p.s_onset = nullptr;
  p.bond_damage = nullptr;
  return p;
}

// Does this force pass take the fast paths the layout carries? The condition under which
// force_kernel runs pmb_fast_force_loop or lps_fast_force_loop (the portable double build's
// scalar PMB loop gives the same bits, pd_kernels.hpp), and for LPS the dilatation pass's
// brittle loop.
template <class Real>
BRECCIA_HD bool sell_fast_pass(const PdViewT<Real>& p) {
  if (!p.symmetric_halves || !has_bond_vectors(p) || p.diagnostics || !fast_bond_loop(p)) return false;
  return p.model == static_cast<int>(PdModel::PMB) || (p.model == static_cast<int>(PdModel::LPS) && p.lps_a);
}

// Does this force pass take the dual-horizon pass the layout carries? Where force_kernel runs
// general_force_loop (variable horizons), with brittle bonds (a softening entry's damage and
// onset are per-entry state the layout does not hold); gathered bond vectors for LPS's first
// pass; the layout's dual halves (gathered where the set-up found variable horizons).
// Diagnostic passes too where the layout holds the damage weights (`e.vol_own`, or the own
// counts `e.own_count` with which own_volume forms them from the lane's neighbour). The
// compressive enhancement's s_min is per particle, so it runs here too.
template <class Real>
BRECCIA_HD bool sell_general_pass(const PdViewT<Real>& p, const SellEntriesT<Real>& e) {
  if (p.bond_damage || !has_bond_vectors(p) || !takes_general_loop(p) || !e.k_dual || !e.s0_dual) return false;
  if (p.diagnostics && !e.vol_own && !e.own_count) return false;
  return p.model == static_cast<int>(PdModel::PMB) || p.model == static_cast<int>(PdModel::LPS);
}

// The q-th entry of a lane, and the break hook that keeps the CSR's state current: the entry's
// new state (0 in the fast passes; one half cleared in the dual-horizon pass) copied over.
struct SellLaneEntries {
  const SellView* s;
  int64_t lane;
  BRECCIA_HD int64_t operator()(int64_t q) const { return s->entry(lane, q); }
};
struct SellCsrBreak {
  const SellView* s;
  const uint8_t* state;  // the layout's
  BRECCIA_HD void operator()(int64_t k) const { s->csr_state[s->csr_entry[k]] = state[k]; }
};

// The fast force passes of one slice lane (`e`: sell_entry_view), one function per model so
// that each launch carries one path (registers sized for it alone).
template <class Real>
BRECCIA_HD void sell_pmb_force_lane(const PdViewT<Real>& e, const SellView& s, int64_t lane) {
  const int32_t i = s.particle[lane];
  if (i < 0) return;
  ordered_fast_loop<PmbReleased<Real>>(e, i, s.row_length[lane], PmbFastPath<Real>{BondOriginT<Real>(e, i)},
                                       SellLaneEntries{&s, lane}, SellCsrBreak{&s, e.state});
}
template <class Real>
BRECCIA_HD void sell_lps_force_lane(const PdViewT<Real>& e, const SellView& s, int64_t lane) {
  const int32_t i = s.particle[lane];
  if (i < 0) return;
  ordered_fast_loop<double>(e, i, s.row_length[lane], LpsFastPath<Real>{BondOriginT<Real>(e, i), e.lps_a[i], e.lps_b[i]},
                            SellLaneEntries{&s, lane}, SellCsrBreak{&s, e.state});
}
// PMB or LPS as `e.model` says (the host's callers).
template <class Real>
BRECCIA_HD void sell_fast_force_lane(const PdViewT<Real>& e, const SellView& s, int64_t lane) {
  if (e.model == static_cast<int>(PdModel::PMB)) sell_pmb_force_lane(e, s, lane);
  else sell_lps_force_lane(e, s, lane);
}

// The dual-horizon force pass of one slice lane (sell_general_pass): the CSR's general loop
// over the lane's entries, each half-bond break copied to the CSR's state; kDiagnostics on
// output and history steps (energy density, damage, max stretch), as general_force_loop.
template <bool kDiagnostics, class Real>
BRECCIA_HD void sell_general_force_lane(const PdViewT<Real>& e, const SellView& s, int64_t lane) {
  const int32_t i = s.particle[lane];
  if (i < 0) return;
  general_force_row<kDiagnostics>(e, i, s.row_length[lane], SellLaneEntries{&s, lane}, SellCsrBreak{&s, e.state});
}

// LPS's first pass for one slice lane: the brittle terms of lps_dilatation_entry summed in
// row order (a broken entry adds +0, which leaves the sum as the CSR loop's that skips it).
template <class Real>
BRECCIA_HD void sell_lps_dilatation_lane(const PdViewT<Real>& e, const SellView& s, int64_t lane) {
  const int32_t i = s.particle[lane];
  if (i < 0) return;
  const BondOriginT<Real> origin(e, i);
  Real sum = Real(0);
  const int64_t count = s.row_length[lane];
  for (int64_t q = 0; q < count; ++q) sum += lps_dilatation_entry(e, origin, s.entry(lane, q));
  lps_store_dilatation(e, i, sum);
}

// The layout's state from the CSR's, for one lane: after a pass that broke bonds in the CSR
// order (a diagnostic pass: output and history steps).
BRECCIA_HD void sell_state_from_csr(const SellView& s, uint8_t* state, int64_t lane) {
  const int64_t count = s.row_length[lane];
  for (int64_t q = 0; q < count; ++q) {
    const int64_t k = s.entry(lane, q);
    state[k] = s.csr_state[s.csr_entry[k]];
  }
}

// Launchable functors (step.hpp's pd_force_pass), one index per slice lane; one per path.
template <class Real>
struct SellDilatation {
  PdViewT<Real> e;
  SellView s;
  BRECCIA_HD void operator()(int64_t lane) const { sell_lps_dilatation_lane(e, s, lane); }
};
template <class Real>
struct SellPmbForces {
  static constexpr int kMinBlocksPerSm = 2;  // CUDA launch bounds (cuda_launch.cuh)
  PdViewT<Real> e;
  SellView s;
  BRECCIA_HD void operator()(int64_t lane) const { sell_pmb_force_lane(e, s, lane); }
};
template <class Real>
struct SellLpsForces {
  static constexpr int kMinBlocksPerSm = 2;  // CUDA launch bounds (cuda_launch.cuh)
  PdViewT<Real> e;
  SellView s;
  BRECCIA_HD void operator()(int64_t lane) const { sell_lps_force_lane(e, s, lane); }
};
template <class Real, bool kDiagnostics>
struct SellGeneralForces {
  static constexpr int kMinBlocksPerSm = 2;  // CUDA launch bounds (cuda_launch.cuh)
  PdViewT<Real> e;
  SellView s;
  BRECCIA_HD void operator()(int64_t lane) const { sell_general_force_lane<kDiagnostics>(e, s, lane); }
};
struct SellStateFromCsr {
  SellView s;
  uint8_t* state;
  BRECCIA_HD void operator()(int64_t lane) const { sell_state_from_csr(s, state, lane); }
};

}  // namespace breccia::solver
