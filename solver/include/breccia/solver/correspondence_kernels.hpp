#pragma once
// Correspondence (non-ordinary state-based) peridynamics (Silling, Epton, Weckner, Xu &
// Askari 2007, section 18): a classical stress from a nonlocal deformation gradient, turned
// into a force state. Two passes per step, as LPS: (1) shape tensor, deformation gradient,
// stress; (2) forces, which need the neighbours' stresses. Derivations: docs/theory.md
// ("Correspondence model"). Per particle the 3x3 tensors are row-major; in 2D only the
// in-plane 2x2 block is used (zz of F is 1, of Q is 0).
#include <cmath>
#include <cstdint>

#include "breccia/solver/pd_kernels.hpp"

namespace breccia::solver {

// The ratio of the non-affine energy measure to the body's mechanical energy above which
// the run is stopped (docs/atlas.md, correspondence stability map). With a penalty of
// coefficient G >= 1 the ratio is bounded by 1/G by energy conservation, so a stabilised run
// cannot trip it; a smooth physical wave keeps it well below (measured <= 0.1 on the map).
inline constexpr double kMaxNonAffineRatio = 1.0;

struct CorrespondenceView {
  PdView p;             // the shared arrays; k_own / k_dual hold w = omega * beta (as LPS)
  int dimension = 3;
  // Per particle, 5 values: dimensional bulk modulus K_d, shear modulus mu, the equivalent PMB
  // micro-modulus c0 (the scale of the penalty), the unit penalty stiffness h = c0 / (2 delta),
  // and the stabilisation coefficient G (0: none).
  const double* moduli = nullptr;
  double* deformation = nullptr;  // 9N: F_i
  // 9N: A_i = P_i K_i^-1 - G h F_i (P: first Piola-Kirchhoff, svk_stress). The force state is then
  // T_i<xi> = w (A_i xi + G h Y): the penalty's F_i xi folded into one tensor per particle.
  double* force_tensor = nullptr;
  double* nonaffine = nullptr;    // N: (h/2) sum_j w |Y - F xi|^2 V_j, the G = 1 penalty energy density
  // model.stress_damage_limit: a particle whose family has lost more than this share of its own
  // volume carries no stress (F = I, the penalty alone); above 1: never.
  double damage_limit = 2.0;
};

inline constexpr int kCorrModuli = 5;

// Inverse of the d x d block of a row-major 3x3 matrix; false if (nearly) singular, i.e.
// the family does not span the space (fewer than d non-collinear bonds).
BRECCIA_HD bool invert_block(const double* m, int d, double* inv) {
  for (int k = 0; k < 9; ++k) inv[k] = 0.0;
  if (d == 2) {
    const double det = m[0] * m[4] - m[1] * m[3];
    const double scale = m[0] * m[4] + m[1] * m[1] + m[3] * m[3];
    if (!(std::fabs(det) > 1e-12 * scale)) return false;
    inv[0] = m[4] / det;
    inv[1] = -m[1] / det;
    inv[3] = -m[3] / det;
    inv[4] = m[0] / det;
    return true;
  }
  const double c00 = m[4] * m[8] - m[5] * m[7], c01 = m[5] * m[6] - m[3] * m[8], c02 = m[3] * m[7] - m[4] * m[6];
  const double det = m[0] * c00 + m[1] * c01 + m[2] * c02;
  const double scale = m[0] * m[4] * m[8];
  if (!(std::fabs(det) > 1e-12 * std::fabs(scale))) return false;
  const double r = 1.0 / det;
  inv[0] = c00 * r;
  inv[1] = (m[2] * m[7] - m[1] * m[8]) * r;
  inv[2] = (m[1] * m[5] - m[2] * m[4]) * r;
  inv[3] = c01 * r;
  inv[4] = (m[0] * m[8] - m[2] * m[6]) * r;
  inv[5] = (m[2] * m[3] - m[0] * m[5]) * r;
  inv[6] = c02 * r;
  inv[7] = (m[1] * m[6] - m[0] * m[7]) * r;
  inv[8] = (m[0] * m[4] - m[1] * m[3]) * r;
  return true;
}

// Reference and deformed bond vectors j - i; the deformed one from the current positions x
// when the launcher filled them (one gathered array), else x0 + u.
BRECCIA_HD void bond_vectors(const PdView& p, int64_t i, int64_t j, double* xi, double* Y) {
  for (int a = 0; a < 3; ++a) {
    xi[a] = p.x0[3 * j + a] - p.x0[3 * i + a];
    Y[a] = p.x ? p.x[3 * j + a] - p.x[3 * i + a] : xi[a] + p.u[3 * j + a] - p.u[3 * i + a];
  }
}

// St Venant-Kirchhoff in d dimensions (Holzapfel 2000, section 6.5; docs/theory.md): the
// Green-Lagrange strain E = (F^T F - I) / 2, formed as sym(H) + H^T H / 2 with H = F - I so
// that a small strain loses nothing to cancellation against I; the second Piola-Kirchhoff
// stress S = K_d tr(E) I + 2 mu dev(E) (K_d: 3D bulk, plane stress/strain 2D bulk, as LPS);
// the first Piola-Kirchhoff stress P = F S = dW/dF, which the force state takes (Silling et al.
// 2007, section 18: T = w P K^-1 xi). Returns the energy density
// W = K_d tr(E)^2 / 2 + mu dev(E):dev(E). E is zero under any rigid rotation (F = R), so a
// turned or spinning body carries no stress; at small strain E -> sym(F) - I and P -> Hooke's
// sigma. (The small strain sym(F) - I used before read a turn of 30 degrees as a compression
// of 1 - cos 30 = 13 % in its plane.)
BRECCIA_HD double svk_stress(const double* F, int d, double bulk, double shear, double* P) {
  double H[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0}, E[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0}, S[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
  for (int a = 0; a < d; ++a)
    for (int b = 0; b < d; ++b) H[3 * a + b] = F[3 * a + b] - (a == b ? 1.0 : 0.0);
  double tr = 0.0;
  for (int a = 0; a < d; ++a)
    for (int b = 0; b < d; ++b) {
      double hh = 0.0;
      for (int c = 0; c < d; ++c) hh += H[3 * c + a] * H[3 * c + b];
      E[3 * a + b] = 0.5 * (H[3 * a + b] + H[3 * b + a]) + 0.5 * hh;
    }
  for (int a = 0; a < d; ++a) tr += E[4 * a];
  double dev2 = 0.0;
  for (int a = 0; a < d; ++a)
    for (int b = 0; b < d; ++b) {
      const double dev = E[3 * a + b] - (a == b ? tr / d : 0.0);
      dev2 += dev * dev;
      S[3 * a + b] = 2.0 * shear * dev + (a == b ? bulk * tr : 0.0);
    }
  for (int k = 0; k < 9; ++k) P[k] = 0.0;
  for (int a = 0; a < d; ++a)
    for (int b = 0; b < d; ++b) {
      double v = 0.0;
      for (int c = 0; c < d; ++c) v += F[3 * a + c] * S[3 * c + b];
      P[3 * a + b] = v;
    }
  return 0.5 * bulk * tr * tr + shear * dev2;
}

// F = N K^-1 from a family's moments (its d x d block), and K^-1; false, F untouched, where K
// does not span the space (all bonds broken or collinear): the callers' F = I stands.
template <int d>
BRECCIA_HD bool family_deformation(const double* K, const double* N, double* F, double* Kinv) {
  if (!invert_block(K, d, Kinv)) return false;
  for (int a = 0; a < d; ++a)
    for (int b = 0; b < d; ++b) {
      double s = 0.0;
      for (int e = 0; e < d; ++e) s += N[3 * a + e] * Kinv[3 * e + b];
      F[3 * a + b] = s;
    }
  return true;
}

// The deformation gradient of a family from its moments, F = N K^-1 (I where K does not span
// the space), and the family's energy density at it: St Venant-Kirchhoff's W(F) plus G times
// the penalty's (h/2) sum_j w |Y - F xi|^2 V_j, written with the moments as
// (h/2) (S - 2 F:N + F K : F), S = sum_j w |Y|^2 V_j, so that no second pass over the bonds is
// needed. (The difference of two such sums, the energy a break releases, is what it is used
// for: the moments' rounding, ~1e-16 of S, is ~1e-10 of the elastic energy at a strain of 1e-3.)
template <int d>
BRECCIA_HD double correspondence_family_energy(const double* K, const double* N, double S, const double* mod,
                                               bool stress_off) {
  double F[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, Kinv[9], P[9];
  const double W = !stress_off && family_deformation<d>(K, N, F, Kinv) ? svk_stress(F, d, mod[0], mod[1], P) : 0.0;
  double fn = 0.0, fkf = 0.0;
  for (int a = 0; a < d; ++a)
    for (int b = 0; b < d; ++b) {
      fn += F[3 * a + b] * N[3 * a + b];
      double fk = 0.0;
      for (int e = 0; e < d; ++e) fk += F[3 * a + e] * K[3 * e + b];
      fkf += fk * F[3 * a + b];
    }
  return W + mod[4] * 0.5 * mod[3] * (S - 2.0 * fn + fkf);
}

// Pass 1 for particle i: break over-stretched bonds (critical stretch, as PMB/LPS), then
// K_i = sum_j w xi (x) xi V_j, F_i = (sum_j w Y (x) xi V_j) K_i^-1 over i's intact own bonds,
// the stress and A_i = P K_i^-1 - G h F_i. Writes damage, energy density (elastic part) and the
// energy released by bonds broken here: the drop of the particle's energy density (elastic and
// penalty) times V_i at the current positions, its family's moments with the bonds that broke
// against without them, so the energy balance books what the break took out of the body. (A
// bond's own half belongs to i's energy alone; its dual half to j's, which j's pass breaks and
// books from its own entry. Before 2026-12-07 the break booked what the equivalent PMB
// half-bond holds at its critical stretch, not the correspondence energy: on the DCB the
// balance was 9.7 % of the work off, docs/theory.md.)
template <int d>
BRECCIA_HD void correspondence_deformation_pass(const CorrespondenceView& c, int64_t i) {
  const PdView& p = c.p;
  const double* mod = c.moduli + kCorrModuli * i;
  double K[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0}, N[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
  // The own halves broken in this pass: their share of the moments (and S = sum w |Y|^2 V_j,
  // over the intact ones in S), for the energy they release.
  double dK[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0}, dN[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
  double S = 0.0, dS = 0.0;
  bool own_broke = false;
  double smax = 0.0, intact_vol = 0.0;
  const bool limited = c.damage_limit < 1.0;
  const double total_vol = p.diagnostics || limited ? family_volume(p, i) : 0.0;
  double broken_vol = 0.0;  // own volume of the halves broken in this pass
  for (int64_t k = p.offsets[i]; k < p.offsets[i + 1]; ++k) {
    uint8_t st = p.state[k];
    if (!st) continue;
    const int64_t j = p.neighbor[k];
    double xi[3], Y[3];
    bond_vectors(p, i, j, xi, Y);
    const double len = std::sqrt(Y[0] * Y[0] + Y[1] * Y[1] + Y[2] * Y[2]);
    const double stretch = (len - p.xi_len[k]) / p.xi_len[k];
    const double wv = p.k_own[k] * p.volume[j];
    if (p.fracture) {
      const uint8_t after = break_bonds(p, k, stretch, 0.0);
      if (after != st) {
        if ((st & ~after) & kOwnIntact) {
          own_broke = true;
          if (limited) broken_vol += own_volume(p, k);
          for (int a = 0; a < d; ++a) {
            dS += wv * Y[a] * Y[a];
            for (int b = 0; b < d; ++b) {
              dK[3 * a + b] += wv * xi[a] * xi[b];
              dN[3 * a + b] += wv * Y[a] * xi[b];
            }
          }
        }
        st = after;
        p.state[k] = st;
      }
    }
    if (!(st & kOwnIntact)) continue;
    intact_vol += own_volume(p, k);
    if (stretch > smax) smax = stretch;
    for (int a = 0; a < d; ++a) {
      if (p.fracture) S += wv * Y[a] * Y[a];
      for (int b = 0; b < d; ++b) {
        K[3 * a + b] += wv * xi[a] * xi[b];
        N[3 * a + b] += wv * Y[a] * xi[b];
      }
    }
  }
  // Past the damage limit (damage: the share of the family's own volume lost) the particle
  // carries no stress; crossing it is a break like any other, booked below.
  const bool stress_off = limited && total_vol > 0.0 && 1.0 - intact_vol / total_vol > c.damage_limit;
  const bool stress_off_before =
      limited && total_vol > 0.0 && 1.0 - (intact_vol + broken_vol) / total_vol > c.damage_limit;
  double released = 0.0;
  if (own_broke) {
    double K0[9], N0[9];
    for (int q = 0; q < 9; ++q) {
      K0[q] = K[q] + dK[q];
      N0[q] = N[q] + dN[q];
    }
    released = p.volume[i] * (correspondence_family_energy<d>(K0, N0, S + dS, mod, stress_off_before) -
                              correspondence_family_energy<d>(K, N, S, mod, stress_off));
  }
  double* F = c.deformation + 9 * i;
  double* Q = c.force_tensor + 9 * i;  // becomes A_i
  double Kinv[9];
  double W = 0.0;
  for (int k = 0; k < 9; ++k) {
    F[k] = (k % 4 == 0) ? 1.0 : 0.0;
    Q[k] = (k % 4 == 0 && k / 4 < d) ? -mod[4] * mod[3] : 0.0;  // A = -G h F with F = I
  }
  // A family that no longer spans the space (all bonds broken or collinear), or past the
  // damage limit, carries no stress.
  if (!stress_off && family_deformation<d>(K, N, F, Kinv)) {
    double P[9];
    W = svk_stress(F, d, mod[0], mod[1], P);
    for (int a = 0; a < d; ++a)
      for (int b = 0; b < d; ++b) {
        double s = 0.0;
        for (int e = 0; e < d; ++e) s += P[3 * a + e] * Kinv[3 * e + b];
        Q[3 * a + b] = s - mod[4] * mod[3] * F[3 * a + b];
      }
  }
  p.dissipated[i] = released;
  if (p.diagnostics) {
    p.energy_density[i] = W;
    p.damage[i] = total_vol > 0.0 ? 1.0 - intact_vol / total_vol : 0.0;
    if (p.max_stretch) p.max_stretch[i] = smax;
  }
}

// The dimension as a template argument so that the small tensor loops unroll.
BRECCIA_HD void correspondence_deformation_kernel(const CorrespondenceView& c, int64_t i) {
  if (c.dimension == 2) correspondence_deformation_pass<2>(c, i);
  else correspondence_deformation_pass<3>(c, i);
}

// Pass 2 for particle i: f_i = sum_j (T_i<xi> - T_j<-xi>) V_j with
// T_i<xi> = w_ij (P_i K_i^-1 xi + G_i h_i z_i) = w_ij (A_i xi + G_i h_i Y), with
// z_i = Y - F_i xi the non-affine part of the bond's deformation (zero under any affine
// field), and the same from j's side. The penalty's energy
// (G h / 2) sum_j w |z|^2 V_j has dW/dF = 0 (sum_j w z (x) xi V_j = 0 by the definition of F),
// so the force is exactly its derivative and velocity Verlet conserves the total.
template <int d>
BRECCIA_HD void correspondence_force_pass(const CorrespondenceView& c, int64_t i) {
  const PdView& p = c.p;
  const double* Fi = c.deformation + 9 * i;
  const double* Ai = c.force_tensor + 9 * i;
  const double gh_i = c.moduli[kCorrModuli * i + 4] * c.moduli[kCorrModuli * i + 3];
  double f[3] = {0, 0, 0}, z2_sum = 0.0;
  for (int64_t k = p.offsets[i]; k < p.offsets[i + 1]; ++k) {
    const uint8_t st = p.state[k];
    if (!st) continue;
    const int64_t j = p.neighbor[k];
    double xi[3], Y[3];
    bond_vectors(p, i, j, xi, Y);
    const double vj = p.volume[j];
    const double* Aj = c.force_tensor + 9 * j;
    const double gh_j = c.moduli[kCorrModuli * j + 4] * c.moduli[kCorrModuli * j + 3];
    // Own half from i's horizon, dual half from j's: w (A xi + G h Y) for each intact one.
    const double w_own = (st & kOwnIntact) ? p.k_own[k] * vj : 0.0;
    const double w_dual = (st & kDualIntact) ? p.k_dual[k] * vj : 0.0;
    for (int a = 0; a < d; ++a) {
      double ai = 0.0, aj = 0.0;
      for (int b = 0; b < d; ++b) {
        ai += Ai[3 * a + b] * xi[b];
        aj += Aj[3 * a + b] * xi[b];
      }
      f[a] += w_own * (ai + gh_i * Y[a]) + w_dual * (aj + gh_j * Y[a]);
    }
    if (p.diagnostics && w_own > 0.0) {
      double z2 = 0.0;
      for (int a = 0; a < d; ++a) {
        double fx = 0.0;
        for (int b = 0; b < d; ++b) fx += Fi[3 * a + b] * xi[b];
        z2 += (Y[a] - fx) * (Y[a] - fx);
      }
      z2_sum += w_own * z2;
    }
  }
  for (int a = 0; a < 3; ++a) p.force[3 * i + a] = f[a];
  if (p.diagnostics) {
    const double h = c.moduli[kCorrModuli * i + 3], G = c.moduli[kCorrModuli * i + 4];
    c.nonaffine[i] = 0.5 * h * z2_sum;
    p.energy_density[i] += G * c.nonaffine[i];
  }
}

BRECCIA_HD void correspondence_force_kernel(const CorrespondenceView& c, int64_t i) {
  if (c.dimension == 2) correspondence_force_pass<2>(c, i);
  else correspondence_force_pass<3>(c, i);
}

}  // namespace breccia::solver
