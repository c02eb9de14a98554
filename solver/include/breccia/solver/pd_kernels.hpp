#pragma once
// Per-particle kernels over raw views: the loop bodies both backends run. A backend only
// decides how `for i in [0, n)` is launched (OpenMP here, CUDA in solver/cuda/).
#include <cmath>
#include <cstdint>

#include "breccia/solver/pd_physics.hpp"

namespace breccia::solver {

// Everything a kernel reads or writes, as raw pointers (structure of arrays).
struct PdView {
  int64_t n = 0;
  int model = 0;  // PdModel
  bool fracture = true;
  // Damage, energy density and max stretch are only needed on output/history steps.
  bool diagnostics = true;
  // One constant horizon: both halves of every entry are equal (k_own == k_dual,
  // s0_own == s0_dual, both bits set together), so the kernel reads one of each.
  bool symmetric_halves = false;
  const double* x0 = nullptr;   // 3N reference positions
  const double* x = nullptr;    // 3N current positions x0 + u (optional: fast PMB path)
  double* u = nullptr;          // 3N displacement
  double* v = nullptr;          // 3N velocity
  double* a = nullptr;          // 3N acceleration
  double* force = nullptr;      // 3N internal force density [N/m3]
  const double* body = nullptr; // 3N external force density [N/m3]
  const double* volume = nullptr;
  const double* density = nullptr;
  const uint8_t* fixed_dof = nullptr;  // N, bit d set: component d is prescribed
  // bonds, CSR over full families
  const int64_t* offsets = nullptr;
  const int32_t* neighbor = nullptr;
  const double* xi_len = nullptr;
  const double* k_own = nullptr;   // PMB: c_half*omega*beta*V_j; LPS: omega*beta (own horizon)
  const double* k_dual = nullptr;  // same for the neighbour's horizon
  const double* vol_own = nullptr; // beta*V_j in the own horizon (damage weights)
  const float* s0_own = nullptr;   // critical stretch of each half-bond
  const float* s0_dual = nullptr;
  uint8_t* state = nullptr;        // kOwnIntact | kDualIntact
  // LPS per particle
  const LpsCoefficients* lps = nullptr;
  const double* weighted_volume = nullptr;  // m_i
  double* dilatation = nullptr;             // theta_i
  // Optional per-particle LPS factors for the fast path: t_i = omega (A_i |xi| + B_i e),
  // A_i = theta_i (c_b - c_s/d) / m_i, B_i = c_s / m_i (filled by the dilatation pass).
  double* lps_a = nullptr;
  double* lps_b = nullptr;
  // per-particle outputs
  double* energy_density = nullptr;   // W_i [J/m3]
  double* dissipated = nullptr;       // energy released by bonds broken this step, per particle [J]
  double* damage = nullptr;
  double* max_stretch = nullptr;      // optional
};

// LPS first pass: theta_i = d/m_i * sum_j omega beta |xi| e V_j over intact own bonds.
BRECCIA_HD void lps_dilatation_kernel(const PdView& p, int64_t i) {
  double sum = 0.0;
  for (int64_t k = p.offsets[i]; k < p.offsets[i + 1]; ++k) {
    if (!(p.state[k] & kOwnIntact)) continue;
    const int64_t j = p.neighbor[k];
    double length;
    if (p.x) {
      const double dx = p.x[3 * j] - p.x[3 * i], dy = p.x[3 * j + 1] - p.x[3 * i + 1], dz = p.x[3 * j + 2] - p.x[3 * i + 2];
      length = std::sqrt(dx * dx + dy * dy + dz * dz);
    } else {
      length = bond_geometry(p.x0, p.u, i, j, p.xi_len[k]).length;
    }
    sum += p.k_own[k] * p.xi_len[k] * (length - p.xi_len[k]) * p.volume[j];
  }
  const double theta = p.lps[i].dilatation_factor * sum / p.weighted_volume[i];
  p.dilatation[i] = theta;
  if (p.lps_a) {
    const LpsCoefficients& c = p.lps[i];
    p.lps_a[i] = theta * (c.bulk_term - c.shear_term / c.dilatation_factor) / p.weighted_volume[i];
    p.lps_b[i] = c.shear_term / p.weighted_volume[i];
  }
}

// LPS with one constant horizon: the pair's force state is omega ((A_i + A_j)|xi| +
// (B_i + B_j) e), the same algebra as lps_force_state summed over both ends.
BRECCIA_HD void lps_symmetric_force_kernel(const PdView& p, int64_t i) {
  const double* x = p.x;
  const double xi0 = x[3 * i], yi0 = x[3 * i + 1], zi0 = x[3 * i + 2];
  const double a_i = p.lps_a[i], b_i = p.lps_b[i];
  const double theta_i = p.dilatation[i], d = p.lps[i].dilatation_factor;
  double fx = 0.0, fy = 0.0, fz = 0.0, released = 0.0, dev_sum = 0.0, smax = 0.0;
  double intact_vol = 0.0, total_vol = 0.0;
  const int64_t end = p.offsets[i + 1];
  for (int64_t k = p.offsets[i]; k < end; ++k) {
    if (p.diagnostics) total_vol += p.vol_own[k];
    if (!p.state[k]) continue;
    const int64_t j = p.neighbor[k];
    const double dx = x[3 * j] - xi0, dy = x[3 * j + 1] - yi0, dz = x[3 * j + 2] - zi0;
    const double len = std::sqrt(dx * dx + dy * dy + dz * dz);
    const double xi = p.xi_len[k];
    const double e = len - xi;
    const double omega = p.k_own[k];
    if (p.fracture && e > p.s0_own[k] * xi) {
      const double dev = p.s0_own[k] * xi - theta_i * xi / d;  // at the critical extension
      released += 0.5 * b_i * omega * dev * dev * p.volume[j] * p.volume[i];
      p.state[k] = 0;
      continue;
    }
    const double t = omega * ((a_i + p.lps_a[j]) * xi + (b_i + p.lps_b[j]) * e);
    const double f = t * p.volume[j] / len;
    fx += f * dx;
    fy += f * dy;
    fz += f * dz;
    if (p.diagnostics) {
      const double dev = e - theta_i * xi / d;
      dev_sum += omega * dev * dev * p.volume[j];
      intact_vol += p.vol_own[k];
      if (e / xi > smax) smax = e / xi;
    }
  }
  p.force[3 * i] = fx;
  p.force[3 * i + 1] = fy;
  p.force[3 * i + 2] = fz;
  p.dissipated[i] = released;
  if (p.diagnostics) {
    p.energy_density[i] = lps_bulk_energy(p.lps[i], theta_i) + 0.5 * b_i * dev_sum;
    p.damage[i] = total_vol > 0.0 ? 1.0 - intact_vol / total_vol : 0.0;
    if (p.max_stretch) p.max_stretch[i] = smax;
  }
}

// Has entry k lost a half-bond that existed? (With variable horizons a half may never
// have existed: j outside i's horizon, or i outside j's.)
BRECCIA_HD bool entry_broken(const PdView& p, int64_t k) {
  const uint8_t st = p.state[k];
  const bool own_lost = p.vol_own[k] > 0.0 && !(st & kOwnIntact);
  const bool dual_lost = p.k_dual[k] > 0.0 && !(st & kDualIntact);
  return own_lost || dual_lost;
}

// Break the half-bonds of entry k whose stretch passed their critical value. Each entry is
// written only by its owner i; (i,j) and (j,i) see the same stretch, so they agree.
BRECCIA_HD uint8_t break_bonds(const PdView& p, int64_t k, double stretch) {
  uint8_t st = p.state[k];
  if ((st & kOwnIntact) && stretch > p.s0_own[k]) st &= static_cast<uint8_t>(~kOwnIntact);
  if ((st & kDualIntact) && stretch > p.s0_dual[k]) st &= static_cast<uint8_t>(~kDualIntact);
  return st;
}

// PMB with one constant horizon, the common production case: reads one modulus and one
// critical stretch per entry; the diagnostics (energy, damage) are compiled out of the
// loop between output steps.
template <bool kDiagnostics>
BRECCIA_HD void pmb_symmetric_force_loop(const PdView& p, int64_t i) {
  const double* x = p.x;
  const double xi0 = x[3 * i], yi0 = x[3 * i + 1], zi0 = x[3 * i + 2];
  double fx = 0.0, fy = 0.0, fz = 0.0, w = 0.0, released = 0.0, smax = 0.0;
  double intact_vol = 0.0, total_vol = 0.0;
  const int64_t end = p.offsets[i + 1];
  for (int64_t k = p.offsets[i]; k < end; ++k) {
    if (kDiagnostics) total_vol += p.vol_own[k];
    if (!p.state[k]) continue;
    const int64_t j = p.neighbor[k];
    const double dx = x[3 * j] - xi0, dy = x[3 * j + 1] - yi0, dz = x[3 * j + 2] - zi0;
    const double len = std::sqrt(dx * dx + dy * dy + dz * dz);
    const double xi = p.xi_len[k];
    const double extension = len - xi;
    const double k2 = 2.0 * p.k_own[k];  // own + dual halves
    if (p.fracture && extension > p.s0_own[k] * xi) {
      // Dissipated: what the bond holds at its critical stretch. It broke somewhere inside
      // this step, so its force never worked against the stretch beyond s0.
      const double s0 = p.s0_own[k];
      released += p.volume[i] * 0.25 * k2 * s0 * s0 * xi;
      p.state[k] = 0;
      continue;
    }
    const double f = k2 * extension / (xi * len);  // c s / |xi + eta|
    fx += f * dx;
    fy += f * dy;
    fz += f * dz;
    if (kDiagnostics) {
      const double stretch = extension / xi;
      w += 0.25 * k2 * stretch * stretch * xi;
      intact_vol += p.vol_own[k];
      if (stretch > smax) smax = stretch;
    }
  }
  p.force[3 * i] = fx;
  p.force[3 * i + 1] = fy;
  p.force[3 * i + 2] = fz;
  p.dissipated[i] = released;
  if (kDiagnostics) {
    p.energy_density[i] = w;
    p.damage[i] = total_vol > 0.0 ? 1.0 - intact_vol / total_vol : 0.0;
    if (p.max_stretch) p.max_stretch[i] = smax;
  }
}

BRECCIA_HD void pmb_symmetric_force_kernel(const PdView& p, int64_t i) {
  if (p.diagnostics) pmb_symmetric_force_loop<true>(p, i);
  else pmb_symmetric_force_loop<false>(p, i);
}

// Internal force density, strain-energy density, damage and breaking for particle i.
BRECCIA_HD void force_kernel(const PdView& p, int64_t i) {
  if (p.symmetric_halves && p.x && p.model == static_cast<int>(PdModel::PMB)) {
    pmb_symmetric_force_kernel(p, i);
    return;
  }
  if (p.symmetric_halves && p.lps_a && p.x) {
    lps_symmetric_force_kernel(p, i);
    return;
  }
  double fx = 0.0, fy = 0.0, fz = 0.0, w = 0.0, released = 0.0, smax = 0.0;
  double intact_vol = 0.0, total_vol = 0.0;
  const bool lps = p.model == static_cast<int>(PdModel::LPS);
  double m_i = 0.0, theta_i = 0.0, dev_sum = 0.0;
  if (lps) {
    m_i = p.weighted_volume[i];
    theta_i = p.dilatation[i];
  }
  for (int64_t k = p.offsets[i]; k < p.offsets[i + 1]; ++k) {
    total_vol += p.vol_own[k];
    uint8_t st = p.state[k];
    if (!st) continue;
    const int64_t j = p.neighbor[k];
    const double xi = p.xi_len[k];
    const BondGeometry g = bond_geometry(p.x0, p.u, i, j, xi);
    if (g.stretch > smax) smax = g.stretch;
    if (p.fracture) {
      const uint8_t after = break_bonds(p, k, g.stretch);
      if (after != st) {
        // Energy the broken halves held (PMB pair potential; LPS deviatoric pair part).
        // What the broken halves hold at their critical stretch (see the symmetric kernel).
        const uint8_t lost = static_cast<uint8_t>(st & ~after);
        if (lps) {
          const double e = p.s0_own[k] * xi;
          const double dev_i = e - theta_i * xi / p.lps[i].dilatation_factor;
          if (lost & kOwnIntact)
            released += 0.5 * (p.lps[i].shear_term / m_i) * p.k_own[k] * dev_i * dev_i * p.volume[j] * p.volume[i];
        } else {
          if (lost & kOwnIntact)
            released += p.volume[i] * pmb_energy_density(p.k_own[k], 0.0, kOwnIntact, p.s0_own[k], xi);
          if (lost & kDualIntact)
            released += p.volume[i] * pmb_energy_density(0.0, p.k_dual[k], kDualIntact, p.s0_dual[k], xi);
        }
        st = after;
        p.state[k] = st;
      }
    }
    if (st & kOwnIntact) intact_vol += p.vol_own[k];
    if (!st) continue;
    double scalar;  // force density along the deformed bond direction
    if (lps) {
      const double e = g.length - xi;
      const int64_t jj = j;
      double t = 0.0;
      if (st & kOwnIntact) {
        t += lps_force_state(p.lps[i], m_i, theta_i, p.k_own[k], xi, e);
        const double dev = e - theta_i * xi / p.lps[i].dilatation_factor;
        dev_sum += p.k_own[k] * dev * dev * p.volume[j];
      }
      if (st & kDualIntact)
        t += lps_force_state(p.lps[jj], p.weighted_volume[jj], p.dilatation[jj], p.k_dual[k], xi, e);
      scalar = t * p.volume[j];
    } else {
      scalar = pmb_force_scalar(p.k_own[k], p.k_dual[k], st, g.stretch);
      w += pmb_energy_density(p.k_own[k], p.k_dual[k], st, g.stretch, xi);
    }
    const double inv_len = 1.0 / g.length;
    fx += scalar * g.dx * inv_len;
    fy += scalar * g.dy * inv_len;
    fz += scalar * g.dz * inv_len;
  }
  if (lps) w = lps_bulk_energy(p.lps[i], theta_i) + 0.5 * (p.lps[i].shear_term / m_i) * dev_sum;
  p.force[3 * i] = fx;
  p.force[3 * i + 1] = fy;
  p.force[3 * i + 2] = fz;
  p.energy_density[i] = w;
  p.dissipated[i] = released;
  p.damage[i] = total_vol > 0.0 ? 1.0 - intact_vol / total_vol : 0.0;
  if (p.max_stretch) p.max_stretch[i] = smax;
}

// a = (f_int + b) / rho, then the second half kick of velocity Verlet.
BRECCIA_HD void acceleration_kernel(const PdView& p, int64_t i, double half_dt) {
  const double inv_rho = 1.0 / p.density[i];
  for (int d = 0; d < 3; ++d) {
    const int64_t c = 3 * i + d;
    p.a[c] = (p.force[c] + p.body[c]) * inv_rho;
    if (!(p.fixed_dof[i] & (1u << d))) p.v[c] += half_dt * p.a[c];
  }
}

// First half kick and drift for free components (prescribed ones are set by the caller).
BRECCIA_HD void kick_drift_kernel(const PdView& p, int64_t i, double half_dt, double dt) {
  for (int d = 0; d < 3; ++d) {
    const int64_t c = 3 * i + d;
    if (p.fixed_dof[i] & (1u << d)) continue;
    p.v[c] += half_dt * p.a[c];
    p.u[c] += dt * p.v[c];
  }
}

}  // namespace breccia::solver
