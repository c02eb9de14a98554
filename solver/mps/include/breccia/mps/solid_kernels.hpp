#pragma once
// Per-particle and per-bond bodies of the stress-based MPS solid (solid.hpp), written once
// as BRECCIA_HD inline functions over raw arrays and small plain structs, so the OpenMP
// loops in solid.cpp and a CUDA launcher call the same code.
//
// Notation (total Lagrangian, reference bonds r_k = X_j - X_i, c_k = w_k / |r_k|^2, V the
// particle volumes):
//   L_i   = sum_k V_j c_k r_k (x) r_k                     (moment matrix of the stencil)
//   H_i   = [sum_k V_j c_k (u_j - u_i) (x) r_k] L_i^-1     (displacement gradient, F = I + H)
// On a regular lattice (equal volumes, full stencil) L_i = V (n0/d) I and H_i is exactly
// the MPS gradient (d/n0) sum_k (u_j - u_i) (x) r_k w_k/|r_k|^2 (Koshizuka & Oka 1996).
// L_i^-1 keeps it exact for linear fields at surfaces, where the MPS form is not, and the
// volume weights keep a uniform stress free of interior forces where particle volumes vary
// (with unweighted sums a graded arrangement, e.g. particles on circles, feels a spurious
// force of order p grad V / V).
#include <cmath>

#include "breccia/mps/kernels.hpp"
#include "breccia/mps/plasticity.hpp"

namespace breccia::mps {

// Row-major 3x3 matrix.
struct Mat3 {
  double a[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
  BRECCIA_HD double& operator()(int r, int c) { return a[3 * r + c]; }
  BRECCIA_HD double operator()(int r, int c) const { return a[3 * r + c]; }
};

BRECCIA_HD inline Mat3 identity3() {
  Mat3 m;
  m.a[0] = m.a[4] = m.a[8] = 1.0;
  return m;
}

BRECCIA_HD inline Mat3 mul(const Mat3& x, const Mat3& y) {
  Mat3 m;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) m(r, c) = x(r, 0) * y(0, c) + x(r, 1) * y(1, c) + x(r, 2) * y(2, c);
  return m;
}

BRECCIA_HD inline double det(const Mat3& m) {
  return m(0, 0) * (m(1, 1) * m(2, 2) - m(1, 2) * m(2, 1)) - m(0, 1) * (m(1, 0) * m(2, 2) - m(1, 2) * m(2, 0)) +
         m(0, 2) * (m(1, 0) * m(2, 1) - m(1, 1) * m(2, 0));
}

// Inverse by cofactors; the caller guarantees det != 0.
BRECCIA_HD inline Mat3 inverse(const Mat3& m) {
  const double inv_det = 1.0 / det(m);
  Mat3 r;
  r(0, 0) = (m(1, 1) * m(2, 2) - m(1, 2) * m(2, 1)) * inv_det;
  r(0, 1) = (m(0, 2) * m(2, 1) - m(0, 1) * m(2, 2)) * inv_det;
  r(0, 2) = (m(0, 1) * m(1, 2) - m(0, 2) * m(1, 1)) * inv_det;
  r(1, 0) = (m(1, 2) * m(2, 0) - m(1, 0) * m(2, 2)) * inv_det;
  r(1, 1) = (m(0, 0) * m(2, 2) - m(0, 2) * m(2, 0)) * inv_det;
  r(1, 2) = (m(0, 2) * m(1, 0) - m(0, 0) * m(1, 2)) * inv_det;
  r(2, 0) = (m(1, 0) * m(2, 1) - m(1, 1) * m(2, 0)) * inv_det;
  r(2, 1) = (m(0, 1) * m(2, 0) - m(0, 0) * m(2, 1)) * inv_det;
  r(2, 2) = (m(0, 0) * m(1, 1) - m(0, 1) * m(1, 0)) * inv_det;
  return r;
}

BRECCIA_HD inline Mat3 transpose(const Mat3& m) {
  Mat3 t;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) t(r, c) = m(c, r);
  return t;
}

// Plane strain (2D): every matrix of the solid is block-diagonal, its in-plane 2x2 block and
// its zz entry, the entries (0,2), (1,2), (2,0), (2,1) exactly zero (no z bonds, no z
// displacement, L^-1 with a zero z row and column, no out-of-plane shear stress). The *_plane
// forms below skip only the products that have such a zero factor and keep the others in
// the order of the full forms above, so every nonzero entry is the full form's to the last
// bit (adding an exact zero changes no nonzero sum); only the sign of an entry that is zero
// anyway can differ. dimension 3 takes the full forms.
BRECCIA_HD inline Mat3 mul_plane(const Mat3& x, const Mat3& y) {
  Mat3 m;
  for (int r = 0; r < 2; ++r)
    for (int c = 0; c < 2; ++c) m(r, c) = x(r, 0) * y(0, c) + x(r, 1) * y(1, c);
  m(2, 2) = x(2, 2) * y(2, 2);
  return m;
}

BRECCIA_HD inline Mat3 mul(const Mat3& x, const Mat3& y, int dimension) {
  return dimension == 2 ? mul_plane(x, y) : mul(x, y);
}

BRECCIA_HD inline double det(const Mat3& m, int dimension) {
  if (dimension != 2) return det(m);
  return m(0, 0) * (m(1, 1) * m(2, 2)) - m(0, 1) * (m(1, 0) * m(2, 2));
}

BRECCIA_HD inline Mat3 inverse(const Mat3& m, int dimension) {
  if (dimension != 2) return inverse(m);
  const double inv_det = 1.0 / det(m, 2);
  Mat3 r;
  r(0, 0) = (m(1, 1) * m(2, 2)) * inv_det;
  r(0, 1) = (-(m(0, 1) * m(2, 2))) * inv_det;
  r(1, 0) = (-(m(1, 0) * m(2, 2))) * inv_det;
  r(1, 1) = (m(0, 0) * m(2, 2)) * inv_det;
  r(2, 2) = (m(0, 0) * m(1, 1) - m(0, 1) * m(1, 0)) * inv_det;
  return r;
}

BRECCIA_HD inline Mat3 to_matrix(const SymTensor& s) {
  Mat3 m;
  m(0, 0) = s.xx;
  m(1, 1) = s.yy;
  m(2, 2) = s.zz;
  m(0, 1) = m(1, 0) = s.xy;
  m(1, 2) = m(2, 1) = s.yz;
  m(0, 2) = m(2, 0) = s.zx;
  return m;
}

BRECCIA_HD inline SymTensor symmetric_part(const Mat3& m) {
  return {m(0, 0), m(1, 1), m(2, 2), 0.5 * (m(0, 1) + m(1, 0)), 0.5 * (m(1, 2) + m(2, 1)), 0.5 * (m(0, 2) + m(2, 0))};
}

BRECCIA_HD inline double contract(const SymTensor& s, const SymTensor& e) {
  return s.xx * e.xx + s.yy * e.yy + s.zz * e.zz + 2.0 * (s.xy * e.xy + s.yz * e.yz + s.zx * e.zx);
}

// c_k = V_j w_k / |r_k|^2 of bond k (V: the stencil volumes), or coefficient[k] where the
// caller keeps these products (Solid::bond_coefficient_, computed once per stencil from the
// same expression, so the values are the same to the last bit; nullptr: computed here).
BRECCIA_HD inline double bond_coefficient(BondsView b, long long k, const double* volume_m3, const double* coefficient) {
  if (coefficient) return coefficient[k];
  const double r[3] = {b.rx[k], b.ry[k], b.rz[k]};
  return volume_m3[b.neighbour[k]] * b.weight[k] / (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
}

// L_i^-1 for particle i. In 2D the z row and column stay zero (no z bonds). A stencil too
// one-sided to invert (fewer than d independent bond directions) falls back to the plain
// MPS scale d/(n0 V_i).
BRECCIA_HD inline Mat3 inverse_moment_matrix_at(long long i, BondsView b, const double* volume_m3, int dimension,
                                                double mps_scale) {
  Mat3 moment;
  mps_scale /= volume_m3[i];
  for (long long k = b.offset[i]; k < b.offset[i + 1]; ++k) {
    const double r[3] = {b.rx[k], b.ry[k], b.rz[k]};
    const double c = volume_m3[b.neighbour[k]] * b.weight[k] / (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    for (int p = 0; p < 3; ++p)
      for (int q = 0; q < 3; ++q) moment(p, q) += c * r[p] * r[q];
  }
  if (dimension == 2) moment(2, 2) = 1.0;
  // Relative to the full-stencil value (n0/d)^d: below 1e-3 the inverse amplifies noise.
  const double full = 1.0 / mps_scale;
  const double det_full = dimension == 2 ? full * full : full * full * full;
  Mat3 inv;
  if (std::fabs(det(moment)) < 1e-3 * det_full) {
    inv = identity3();
    for (double& v : inv.a) v *= mps_scale;
  } else {
    inv = inverse(moment);
  }
  if (dimension == 2) inv(2, 2) = 0.0;
  return inv;
}

// H_i = [sum_k V_j c_k (u_j - u_i) (x) r_k] L_i^-1 (see the header comment). dimension 2:
// the in-plane block only (the z row and column are zero); coefficient: bond_coefficient's.
BRECCIA_HD inline Mat3 displacement_gradient_at(long long i, BondsView b, VectorField u, const double* volume_m3,
                                                const Mat3& moment_inverse, int dimension = 3,
                                                const double* coefficient = nullptr) {
  Mat3 sum;
  if (dimension == 2) {  // the same sums in registers (c du_p r_q in the same order)
    double s00 = 0.0, s01 = 0.0, s10 = 0.0, s11 = 0.0;
    for (long long k = b.offset[i]; k < b.offset[i + 1]; ++k) {
      const long long j = b.neighbour[k];
      const double c = bond_coefficient(b, k, volume_m3, coefficient);
      const double cu0 = c * (u.x[j] - u.x[i]), cu1 = c * (u.y[j] - u.y[i]);
      s00 += cu0 * b.rx[k];
      s01 += cu0 * b.ry[k];
      s10 += cu1 * b.rx[k];
      s11 += cu1 * b.ry[k];
    }
    sum(0, 0) = s00;
    sum(0, 1) = s01;
    sum(1, 0) = s10;
    sum(1, 1) = s11;
    return mul_plane(sum, moment_inverse);
  }
  for (long long k = b.offset[i]; k < b.offset[i + 1]; ++k) {
    const long long j = b.neighbour[k];
    const double r[3] = {b.rx[k], b.ry[k], b.rz[k]};
    const double c = bond_coefficient(b, k, volume_m3, coefficient);
    const double du[3] = {u.x[j] - u.x[i], u.y[j] - u.y[i], u.z[j] - u.z[i]};
    for (int p = 0; p < 3; ++p)
      for (int q = 0; q < 3; ++q) sum(p, q) += c * du[p] * r[q];
  }
  return mul(sum, moment_inverse);
}

// F = I + H from the displacement gradient H (in 2D, F_zz = 1).
BRECCIA_HD inline Mat3 deformation_gradient(const Mat3& h) {
  Mat3 f = h;
  f(0, 0) += 1.0;
  f(1, 1) += 1.0;
  f(2, 2) += 1.0;
  return f;
}

// The elastic law of a solid without plasticity. NeoHookean: the stress from F itself
// (neo_hookean_stress), so the internal forces derive from a stored energy and an elastic
// vibration conserves it; Rate: Hooke increments on the rotated stress (update_stress), which
// plasticity and updated-Lagrangian stencils need (their F does not hold the whole history).
enum class ElasticLaw { NeoHookean, Rate };

// Material law of the solid: isotropic elasticity (Lame lambda, mu) plus optional J2 plasticity.
struct SolidLaw {
  double lame_lambda_pa = 0.0;
  double shear_modulus_pa = 0.0;
  // Used only where plastic is false on total-Lagrangian stencils (Solid takes Rate otherwise).
  ElasticLaw elastic = ElasticLaw::NeoHookean;
  bool plastic = false;
  VonMisesHardening hardening;
  // Material (stiffness-proportional, Rayleigh beta) damping: a Kelvin-Voigt viscous stress
  // sigma_v = beta C : d(eps)/dt added to the stress in the force (viscous_stress_of).
  // 0: none. A damping ratio zeta at a frequency f gives beta = zeta / (pi f).
  double viscous_time_s = 0.0;
};

// The stable step of the central-difference (symplectic Euler) scheme with a viscous term:
// a mode of frequency omega with damping ratio zeta is stable for
// omega dt <= 2 (sqrt(1 + zeta^2) - zeta) (Belytschko, Liu & Moran 2000, sec. 6.3, recalled),
// against 2 without damping. Stiffness-proportional damping gives the highest mode the most,
// zeta_max = beta omega_max / 2, with omega_max = 2 c_L / length for the shortest length the
// lattice resolves (the bound of a 1D chain; the step's safety factor keeps the MPS stencil's
// margin). Returns the factor on the undamped step, 1 without damping.
BRECCIA_HD inline double damped_step_factor(double viscous_time_s, double p_wave_speed_m_s, double length_m) {
  if (!(viscous_time_s > 0.0)) return 1.0;
  const double zeta_max = viscous_time_s * p_wave_speed_m_s / length_m;  // beta (2 c / l) / 2
  return std::sqrt(1.0 + zeta_max * zeta_max) - zeta_max;
}

// a + b, component by component (the elastic and viscous stresses in the force).
BRECCIA_HD inline SymTensor add_stresses(const SymTensor& a, const SymTensor& b) {
  return {a.xx + b.xx, a.yy + b.yy, a.zz + b.zz, a.xy + b.xy, a.yz + b.yz, a.zx + b.zx};
}

// The viscous stress of a step over which the strain grew by strain_increment in dt:
// beta C : (strain_increment / dt).
BRECCIA_HD inline SymTensor viscous_stress_of(const SolidLaw& law, const SymTensor& strain_increment, double dt) {
  SymTensor v;
  add_hooke_increment(v, strain_increment, law.lame_lambda_pa, law.shear_modulus_pa);
  const double s = law.viscous_time_s / dt;
  v.xx *= s;
  v.yy *= s;
  v.zz *= s;
  v.xy *= s;
  v.yz *= s;
  v.zx *= s;
  return v;
}

// Compressible neo-Hookean energy per reference volume and its Cauchy stress (Bonet & Wood
// 2008, sec. 6.4.3):
//   psi = mu/2 (tr C - 3) - mu ln J + lambda/2 (ln J)^2,
//   sigma = [mu (B - I) + lambda ln J I] / J,   B = F F^T, J = det F,
// so P = J sigma F^-T = mu (F - F^-T) + lambda ln J F^-T = d psi / dF. Linearised it is Hooke's
// law with the same lambda and mu; unlike St Venant-Kirchhoff it stiffens as J -> 0 (no
// collapse under strong compression, which the impact cases reach). In 2D (plane strain)
// F_zz = 1 and the formulas are the 3D ones (sigma_zz = lambda ln J / J, in-plane J).
BRECCIA_HD inline double neo_hookean_energy_density(const SolidLaw& law, const Mat3& f, int dimension) {
  const double j = det(f, dimension);
  double tr_c = 0.0;  // tr(F^T F); in 2D the in-plane block and F_zz = 1
  if (dimension == 2) {
    tr_c = f(0, 0) * f(0, 0) + f(0, 1) * f(0, 1) + f(1, 0) * f(1, 0) + f(1, 1) * f(1, 1) + 1.0;
  } else {
    for (int k = 0; k < 9; ++k) tr_c += f.a[k] * f.a[k];
  }
  const double log_j = std::log(j);
  return 0.5 * law.shear_modulus_pa * (tr_c - 3.0) - law.shear_modulus_pa * log_j +
         0.5 * law.lame_lambda_pa * log_j * log_j;
}

BRECCIA_HD inline SymTensor neo_hookean_stress(const SolidLaw& law, const Mat3& f, int dimension) {
  const double j = det(f, dimension);
  const double mu = law.shear_modulus_pa, volumetric = law.lame_lambda_pa * std::log(j);
  // B = F F^T by components; in 2D the z row and column of F are (0, 0, 1).
  auto b = [&](int r, int c) { return f(r, 0) * f(c, 0) + f(r, 1) * f(c, 1) + f(r, 2) * f(c, 2); };
  SymTensor s;
  const double inv_j = 1.0 / j;
  s.xx = (mu * (b(0, 0) - 1.0) + volumetric) * inv_j;
  s.yy = (mu * (b(1, 1) - 1.0) + volumetric) * inv_j;
  s.xy = mu * b(0, 1) * inv_j;
  if (dimension == 2) {
    s.zz = volumetric * inv_j;  // F_zz = 1: B_zz = 1
    s.yz = s.zx = 0.0;
  } else {
    s.zz = (mu * (b(2, 2) - 1.0) + volumetric) * inv_j;
    s.yz = mu * b(1, 2) * inv_j;
    s.zx = mu * b(2, 0) * inv_j;
  }
  return s;
}

// One particle's stress update over a step, from the displacement gradients at the start
// (h_old, with f_old_inverse = (I + h_old)^-1) and the end (h_new) of the step. The
// incremental deformation gradient dF = F_new F_old^-1 = I + (H_new - H_old) F_old^-1
// splits into the strain increment sym(dF - I) and the spin increment W = skew(dF - I).
// The stress is first rotated with the Hughes-Winget operator Q = (I - W/2)^-1 (I + W/2)
// (an exactly orthogonal, second-order integration of the Jaumann rate: a rigid rotation
// only rotates the stress), then receives the Hooke increment (elastic trial) and, if
// plastic, the radial return (deviatoric_scale: q_returned / q_trial, 1 when elastic).
// Returns the stress work density of the step, (sigma_old + sigma_new)/2 : d eps (J/m^3),
// for the energy balance; the strain increment itself in *strain_increment_out if given.
// An elastic law written from F (law.elastic NeoHookean, not plastic) sets the stress from
// h_new alone and returns the change of the stored energy density, psi(F_new) - psi(F_old)
// (per reference volume), so the booked work is the stored energy exactly, step after step.
BRECCIA_HD inline double update_stress(const SolidLaw& law, const Mat3& h_old, const Mat3& f_old_inverse,
                                       const Mat3& h_new, int dimension, SymTensor& stress, double& eq_plastic_strain,
                                       double* deviatoric_scale = nullptr, SymTensor* strain_increment_out = nullptr) {
  Mat3 dh;
  for (int k = 0; k < 9; ++k) dh.a[k] = h_new.a[k] - h_old.a[k];
  const Mat3 g = mul(dh, f_old_inverse, dimension);
  const SymTensor strain_increment = symmetric_part(g);
  if (!law.plastic && law.elastic == ElasticLaw::NeoHookean) {
    const Mat3 f_new = deformation_gradient(h_new), f_old = deformation_gradient(h_old);
    stress = neo_hookean_stress(law, f_new, dimension);
    if (deviatoric_scale) *deviatoric_scale = 1.0;
    if (strain_increment_out) *strain_increment_out = strain_increment;
    return neo_hookean_energy_density(law, f_new, dimension) - neo_hookean_energy_density(law, f_old, dimension);
  }
  Mat3 half_spin;  // W/2
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) half_spin(r, c) = 0.25 * (g(r, c) - g(c, r));
  Mat3 minus = identity3(), plus = identity3();
  for (int k = 0; k < 9; ++k) {
    minus.a[k] -= half_spin.a[k];
    plus.a[k] += half_spin.a[k];
  }
  const Mat3 q = mul(inverse(minus, dimension), plus, dimension);
  SymTensor rotated = symmetric_part(mul(mul(q, to_matrix(stress), dimension), transpose(q), dimension));
  if (dimension == 2) rotated.yz = rotated.zx = 0.0;  // plane strain: no out-of-plane shear
  SymTensor next = rotated;
  add_hooke_increment(next, strain_increment, law.lame_lambda_pa, law.shear_modulus_pa);
  double scale = 1.0;
  if (law.plastic) {
    const double q_trial = von_mises_stress(next);
    if (radial_return(law.hardening, next, eq_plastic_strain) > 0.0) scale = von_mises_stress(next) / q_trial;
  }
  if (deviatoric_scale) *deviatoric_scale = scale;
  if (strain_increment_out) *strain_increment_out = strain_increment;
  SymTensor mid;
  mid.xx = 0.5 * (rotated.xx + next.xx);
  mid.yy = 0.5 * (rotated.yy + next.yy);
  mid.zz = 0.5 * (rotated.zz + next.zz);
  mid.xy = 0.5 * (rotated.xy + next.xy);
  mid.yz = 0.5 * (rotated.yz + next.yz);
  mid.zx = 0.5 * (rotated.zx + next.zx);
  stress = next;
  return contract(mid, strain_increment);
}

// Per-particle force matrices. With the Cauchy stress sigma, F = I + H, J = det F, the first
// Piola-Kirchhoff stress P = J sigma F^-T and K_hg the hourglass stiffness (below):
//   combined  C_i = P_i L_i^-1 - K_hg H_i
//   pressure  G_i = J_i F_i^-T L_i^-1   (the part of P L^-1 that multiplies -p)
// The bond force then needs only these two matrices per end (solid_force_at).
struct ForceMatrices {
  Mat3 combined, pressure;
  double hourglass_stiffness = 0.0;  // K_hg of this particle (Pa/m^3)
};

BRECCIA_HD inline ForceMatrices force_matrices(const SymTensor& stress, const Mat3& h, const Mat3& f_inverse,
                                               const Mat3& moment_inverse, double hourglass_stiffness,
                                               int dimension = 3) {
  const Mat3 f = deformation_gradient(h);
  const double j = det(f, dimension);
  const Mat3 g = mul(transpose(f_inverse), moment_inverse, dimension);
  const Mat3 piola = mul(to_matrix(stress), g, dimension);
  ForceMatrices out;
  out.hourglass_stiffness = hourglass_stiffness;
  for (int k = 0; k < 9; ++k) {
    out.combined.a[k] = j * piola.a[k] - hourglass_stiffness * h.a[k];
    out.pressure.a[k] = j * g.a[k];
  }
  return out;
}

// Internal force on particle i: minus the derivative of W = sum_i V_i psi(F_i) + E_hg with
// respect to u_i (the MPS divergence of stress in its energy-conjugate, symmetric form):
//   f_i = sum_k c_k V_i V_j [ (P_i L_i^-1 + P_j L_j^-1) r_k + hourglass_k ].
// On a regular lattice L^-1 = (d/(n0 V)) I and the stress part is
// V (d/n0) sum_k (sigma_i + sigma_j) r_k w_k/r_k^2, the adjoint MPS gradient of the stress
// (as in kernels.hpp). Each bond term is antisymmetric in i, j: momentum is conserved.
//
// Repulsive pressure (pressure_floor_pa != nullptr; Inagaki's stabilisation): as in the
// MPS pressure gradient of fluids, (d/n0) sum_j (p_j - p^_i) r w/r^2 with p^_i the lowest
// pressure in i's neighbourhood (Koshizuka & Oka 1996), the pressure of both ends of i's
// bonds is measured from p^_i, so (p - p^_i) >= 0 and the pressure part of every bond
// force on i pushes i away from j. The shift adds p^_i (G_i + G_j) r_k per bond, whose sum
// vanishes on a full, symmetric stencil (so the interior is unchanged to O(h)); the price
// is that the bond forces are no longer equal and opposite (momentum and energy are
// conserved only approximately) and that at a free surface the shift acts like a surface
// pressure p^_i (a body in tension is wrongly loaded there).
// Hourglass control (zero-energy modes of a particle-wise gradient): the energy
// E_hg = sum_i (K_i / 2) V_i sum_k V_j c_k |u_j - u_i - H_i r_k|^2, K_i = alpha mu_i d/(n0 V),
// penalises the part of each bond's displacement that the particle's gradient does not
// explain, so it vanishes for every linear field. H_i is the weighted least-squares fit of
// exactly these residuals, so dE_hg/dH_i = 0 and the force is the plain pair sum
//   V_i V_j [ (K_i + K_j)(u_j - u_i) - (K_i H_i + K_j H_j) r_k ]
// (the residual is Ganzenmueller's 2015 SPH hourglass measure). mu_i is the shear modulus,
// scaled in a plastic step by the radial return's deviatoric factor (the algorithmic shear
// stiffness), so the penalty does not stiffen plastic flow far beyond the material.
struct SolidForceInputs {
  BondsView bonds;
  VectorField u;
  const ForceMatrices* matrices = nullptr;
  const double* pressure_floor_pa = nullptr;  // nullptr: conservative form
  const double* volume_m3 = nullptr;
  const double* bond_coefficient = nullptr;   // bond_coefficient's (nullptr: computed per bond)
  int dimension = 3;                          // 2: the in-plane components only (out[2] = 0)
};

BRECCIA_HD inline void solid_force_at(long long i, const SolidForceInputs& in, double out[3]) {
  const BondsView& b = in.bonds;
  const Mat3& ci = in.matrices[i].combined;
  double f[3] = {0.0, 0.0, 0.0};
  for (long long k = b.offset[i]; k < b.offset[i + 1]; ++k) {
    const long long j = b.neighbour[k];
    const double r[3] = {b.rx[k], b.ry[k], b.rz[k]};
    const double c = bond_coefficient(b, k, in.volume_m3, in.bond_coefficient);
    const Mat3& cj = in.matrices[j].combined;
    const double hg = in.matrices[i].hourglass_stiffness + in.matrices[j].hourglass_stiffness;
    const double du[3] = {in.u.x[j] - in.u.x[i], in.u.y[j] - in.u.y[i], in.u.z[j] - in.u.z[i]};
    if (in.dimension == 2) {  // r[2] = 0 and the matrices' z column is zero: those terms are 0
      for (int p = 0; p < 2; ++p)
        f[p] += c * ((ci.a[3 * p] + cj.a[3 * p]) * r[0] + (ci.a[3 * p + 1] + cj.a[3 * p + 1]) * r[1] + hg * du[p]);
    } else {
      for (int p = 0; p < 3; ++p)
        f[p] += c * ((ci.a[3 * p] + cj.a[3 * p]) * r[0] + (ci.a[3 * p + 1] + cj.a[3 * p + 1]) * r[1] +
                     (ci.a[3 * p + 2] + cj.a[3 * p + 2]) * r[2] + hg * du[p]);
    }
    if (in.pressure_floor_pa) {
      const double p_ref = in.pressure_floor_pa[i];
      const Mat3& gi = in.matrices[i].pressure;
      const Mat3& gj = in.matrices[j].pressure;
      for (int p = 0; p < 3; ++p)
        f[p] += c * p_ref * ((gi.a[3 * p] + gj.a[3 * p]) * r[0] + (gi.a[3 * p + 1] + gj.a[3 * p + 1]) * r[1] +
                             (gi.a[3 * p + 2] + gj.a[3 * p + 2]) * r[2]);
    }
  }
  const double vi = in.volume_m3[i];
  out[0] = vi * f[0];
  out[1] = vi * f[1];
  out[2] = vi * f[2];
}

// Hourglass energy of particle i (J), the E_hg term above.
// dimension 2: the in-plane components (the z residual and the z terms are zero).
BRECCIA_HD inline double hourglass_energy_at(long long i, BondsView b, VectorField u, const double* volume_m3,
                                             const Mat3& h, double hourglass_stiffness, int dimension = 3,
                                             const double* coefficient = nullptr) {
  double sum = 0.0;
  for (long long k = b.offset[i]; k < b.offset[i + 1]; ++k) {
    const long long j = b.neighbour[k];
    const double r[3] = {b.rx[k], b.ry[k], b.rz[k]};
    const double c = bond_coefficient(b, k, volume_m3, coefficient);
    const double du[3] = {u.x[j] - u.x[i], u.y[j] - u.y[i], u.z[j] - u.z[i]};
    if (dimension == 2) {
      for (int p = 0; p < 2; ++p) {
        const double e = du[p] - (h(p, 0) * r[0] + h(p, 1) * r[1]);
        sum += c * e * e;
      }
      continue;
    }
    for (int p = 0; p < 3; ++p) {
      const double e = du[p] - (h(p, 0) * r[0] + h(p, 1) * r[1] + h(p, 2) * r[2]);
      sum += c * e * e;
    }
  }
  return 0.5 * hourglass_stiffness * volume_m3[i] * sum;
}

}  // namespace breccia::mps
