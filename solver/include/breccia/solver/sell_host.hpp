#pragma once
// The host's form of the SELL-C-sigma fast force pass: a slice's C lanes side by side, the
// k-th entry of every lane at once. The k-th entries of a slice are C consecutive values, so
// the per-entry loads are unit-stride across lanes, the loop the compiler runs several lanes
// at once (only x[j] is gathered). Each lane still sums its own entries in its row's order;
// a lane past its row reads padding (state 0: it adds +0 and never breaks), and adding +0
// leaves a sum that started at +0 unchanged, so the results are sell_fast_force_lane's (and
// the CSR passes') bit for bit. Not used by a backend yet (docs/cuda.md, "SELL-C-sigma").
#include <cstdint>

#include "breccia/solver/sell_kernels.hpp"

namespace breccia::solver {

// The fast force pass of slice `slice` (`e`: sell_entry_view). C is the layout's chunk.
template <int C, class Real>
void sell_fast_force_slice_host(const PdViewT<Real>& e, const SellView& s, int64_t slice) {
  const bool pmb = e.model == static_cast<int>(PdModel::PMB);
  using Released = double;  // float's PMB loop sums in float: converted per break below
  int32_t particle[C];
  BondOriginT<Real> origin[C];
  Real a_i[C], b_i[C];
  // Each lane's force sums: four for PMB, entry k of the row to sum k mod 4 (RowForceSums),
  // one for LPS (sum 0).
  Real fx[4][C], fy[4][C], fz[4][C];
  PmbReleased<Real> released_pmb[C];
  Released released_lps[C];
  for (int l = 0; l < C; ++l) {
    const int32_t i = s.particle[slice * C + l];
    particle[l] = i;
    origin[l] = BondOriginT<Real>(e, i < 0 ? 0 : i);  // an empty lane reads particle 0's padding
    a_i[l] = pmb || i < 0 ? Real(0) : e.lps_a[i];
    b_i[l] = pmb || i < 0 ? Real(0) : e.lps_b[i];
    for (int r = 0; r < 4; ++r) fx[r][l] = fy[r][l] = fz[r][l] = Real(0);
    released_pmb[l] = PmbReleased<Real>(0);
    released_lps[l] = 0.0;
  }
  const PdViewT<Real> v = e;  // a local copy: its pointers stay in registers (two_stage_force_loop)
  const int64_t first = s.slice_offset[slice], width = (s.slice_offset[slice + 1] - first) / C;
  for (int64_t k = 0; k < width; ++k) {
    const int64_t base = first + k * C;
    bool breaks[C];
    int breaking = 0;
    if (pmb) {
      const int r = static_cast<int>(k & 3);
BRECCIA_SIMD_COUNT(breaking)
      for (int l = 0; l < C; ++l) {
        Real cx, cy, cz;
        breaks[l] = pmb_fast_entry(v, origin[l], base + l, cx, cy, cz);
        fx[r][l] += cx;
        fy[r][l] += cy;
        fz[r][l] += cz;
        breaking += breaks[l] ? 1 : 0;
      }
    } else {
BRECCIA_SIMD_COUNT(breaking)
      for (int l = 0; l < C; ++l) {
        Real cx, cy, cz;
        breaks[l] = lps_fast_entry(v, origin[l], base + l, a_i[l], b_i[l], cx, cy, cz);
        fx[0][l] += cx;
        fy[0][l] += cy;
        fz[0][l] += cz;
        breaking += breaks[l] ? 1 : 0;
      }
    }
    if (breaking)  // rare; each lane's released energy in its row's order
      for (int l = 0; l < C; ++l) {
        if (!breaks[l]) continue;
        const int64_t entry = base + l;
        if (pmb) released_pmb[l] += static_cast<PmbReleased<Real>>(pmb_fast_break(e, particle[l], entry));
        else released_lps[l] += lps_fast_break(e, particle[l], entry);
        s.csr_state[s.csr_entry[entry]] = 0;
      }
  }
  for (int l = 0; l < C; ++l) {
    const int32_t i = particle[l];
    if (i < 0) continue;
    const auto total = [&](const Real (&f)[4][C]) {
      return pmb ? RowForceSums<Real, true>::total({f[0][l], f[1][l], f[2][l], f[3][l]}) : f[0][l];
    };
    e.force[3 * i] = total(fx);
    e.force[3 * i + 1] = total(fy);
    e.force[3 * i + 2] = total(fz);
    e.dissipated[i] = pmb ? double(released_pmb[l]) : released_lps[l];
  }
}

}  // namespace breccia::solver
