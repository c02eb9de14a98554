#pragma once
// The fast bond passes (one constant horizon, brittle bonds, no diagnostics) over the SELL-C-sigma
// layout of sell_layout.hpp: one call per slice lane, i.e. per particle, walking that particle's
// entries in its CSR row's order. The per-entry physics is pd_kernels.hpp's (pmb_fast_entry,
// lps_fast_entry, lps_dilatation_entry and their breaks) read through a view whose per-entry
// arrays are the layout's, and the loop is pd_kernels.hpp's ordered_fast_loop: every sum runs
// in the CSR loop's order, so the results are the CSR passes' bit for bit (padding is never
// visited: a lane stops at its row's length).
#include <cstdint>

#include "breccia/solver/pd_kernels.hpp"
#include "breccia/solver/sell_layout.hpp"

namespace breccia::solver {

// The per-entry arrays the fast passes read, in the layout's order (padding: state 0, the
// neighbour the lane's own particle, lengths 1, moduli and stretches 0).
template <class Real>
struct SellEntriesT {
  const int32_t* neighbor = nullptr;
  const Real* xi_len = nullptr;
  const Real* k_own = nullptr;
  const float* s0_own = nullptr;
  uint8_t* state = nullptr;
};

// `p` with its per-entry arrays replaced by the layout's; the arrays the fast passes never
// read (offsets, the dual halves, damage weights, softening) are cleared, so that a path that
// did read them would fault rather than read the CSR's order.
template <class Real>
BRECCIA_HD PdViewT<Real> sell_entry_view(PdViewT<Real> p, const SellEntriesT<Real>& e) {
  p.offsets = nullptr;
  p.neighbor = e.neighbor;
  p.xi_len = e.xi_len;
  p.k_own = e.k_own;
  p.k_dual = nullptr;
  p.vol_own = nullptr;
  p.s0_own = e.s0_own;
  p.s0_dual = nullptr;
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

// The q-th entry of a lane, and the break hook that keeps the CSR's state current.
struct SellLaneEntries {
  const SellView* s;
  int64_t lane;
  BRECCIA_HD int64_t operator()(int64_t q) const { return s->entry(lane, q); }
};
struct SellCsrBreak {
  const SellView* s;
  BRECCIA_HD void operator()(int64_t k) const { s->csr_state[s->csr_entry[k]] = 0; }
};

// The force pass of one slice lane (`e`: sell_entry_view). PMB or LPS as `e.model` says.
template <class Real>
BRECCIA_HD void sell_fast_force_lane(const PdViewT<Real>& e, const SellView& s, int64_t lane) {
  const int32_t i = s.particle[lane];
  if (i < 0) return;
  const BondOriginT<Real> origin(e, i);
  const int64_t count = s.row_length[lane];
  if (e.model == static_cast<int>(PdModel::PMB))
    ordered_fast_loop<PmbReleased<Real>>(e, i, count, PmbFastPath<Real>{origin}, SellLaneEntries{&s, lane},
                                         SellCsrBreak{&s});
  else
    ordered_fast_loop<double>(e, i, count, LpsFastPath<Real>{origin, e.lps_a[i], e.lps_b[i]},
                              SellLaneEntries{&s, lane}, SellCsrBreak{&s});
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

// Launchable functors (step.hpp's pd_force_pass), one index per slice lane.
template <class Real>
struct SellDilatation {
  PdViewT<Real> e;
  SellView s;
  BRECCIA_HD void operator()(int64_t lane) const { sell_lps_dilatation_lane(e, s, lane); }
};
template <class Real>
struct SellBondForces {
  PdViewT<Real> e;
  SellView s;
  BRECCIA_HD void operator()(int64_t lane) const { sell_fast_force_lane(e, s, lane); }
};
struct SellStateFromCsr {
  SellView s;
  uint8_t* state;
  BRECCIA_HD void operator()(int64_t lane) const { sell_state_from_csr(s, state, lane); }
};

}  // namespace breccia::solver
