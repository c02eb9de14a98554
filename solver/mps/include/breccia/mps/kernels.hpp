#pragma once
// MPS particle-interaction operators (Koshizuka & Oka 1996), total Lagrangian: every
// bond carries its reference vector r_ij = r_j - r_i and weight w(|r_ij|), so the
// operators below act on the reference configuration ([MPS harmonics] eqs 1-3, docs/references.md).
//
// Physics written once: plain inline functions over raw arrays (structure of arrays,
// CSR bonds), no containers, so the OpenMP loops here and the CUDA launcher call
// the same bodies (solver/cuda/src/mps_cuda.cu). BRECCIA_HD marks them for host and device.
#include <cmath>

#if defined(__CUDACC__)
#ifndef BRECCIA_HD
#define BRECCIA_HD __host__ __device__
#endif
#else
#ifndef BRECCIA_HD
#define BRECCIA_HD
#endif
#endif
// On a per-particle body: inline everything it calls (GCC/Clang host code), so that the
// temporaries of the 3x3 algebra stay in registers and the entries a plane-strain form never
// reads are not computed at all. Nothing for the device compiler, which inlines by itself.
#if !defined(__CUDACC__) && defined(__GNUC__)
#define BRECCIA_FLATTEN __attribute__((flatten))
#else
#define BRECCIA_FLATTEN
#endif

namespace breccia::mps {

// Non-owning view of the CSR bond list: bonds of particle i are [offset[i], offset[i+1]).
struct BondsView {
  const long long* offset = nullptr;
  const int* neighbour = nullptr;
  const double* rx = nullptr;  // reference bond vector r_j - r_i, m
  const double* ry = nullptr;
  const double* rz = nullptr;
  const double* weight = nullptr;  // w(|r_ij|), dimensionless
};

// Non-owning view of a vector field stored as three arrays.
struct VectorField {
  const double* x = nullptr;
  const double* y = nullptr;
  const double* z = nullptr;
};

// Operator coefficients fixed by the reference lattice.
struct OperatorScales {
  double gradient = 0.0;   // d / n0                  (eqs 1, 2)
  double laplacian = 0.0;  // 2 d / (lambda n0)       (eq 3)
};

// Koshizuka weight w = re/r - 1 for 0 < r < re, else 0.
BRECCIA_HD inline double koshizuka_weight(double r, double radius_re) {
  return (r > 0.0 && r < radius_re) ? radius_re / r - 1.0 : 0.0;
}

// The sum of the gradient and of its adjoint below, written once: (d/n0) sum_j
// (phi_j -/+ phi_i) r_ij / |r_ij|^2 w_ij, with phi_j - phi_i (kAdjoint false) or phi_j + phi_i.
template <bool kAdjoint>
BRECCIA_HD inline void gradient_sum_at(long long i, BondsView b, const double* phi, double scale, double out[3]) {
  double gx = 0.0, gy = 0.0, gz = 0.0;
  for (long long k = b.offset[i]; k < b.offset[i + 1]; ++k) {
    const double r2 = b.rx[k] * b.rx[k] + b.ry[k] * b.ry[k] + b.rz[k] * b.rz[k];
    const double c = (kAdjoint ? phi[b.neighbour[k]] + phi[i] : phi[b.neighbour[k]] - phi[i]) * b.weight[k] / r2;
    gx += c * b.rx[k];
    gy += c * b.ry[k];
    gz += c * b.rz[k];
  }
  out[0] = scale * gx;
  out[1] = scale * gy;
  out[2] = scale * gz;
}

// <grad phi>_i = (d/n0) sum_j (phi_j - phi_i) r_ij / |r_ij|^2 w_ij          (eq 1)
BRECCIA_HD inline void gradient_at(long long i, BondsView b, const double* phi, double scale,
                                   double out[3]) {
  gradient_sum_at<false>(i, b, phi, scale, out);
}

// The same gradient with (phi_j + phi_i) instead of (phi_j - phi_i): minus the adjoint of
// the divergence below. In the interior sum_j r_ij w/r^2 = 0 (point symmetry) and the two
// forms agree; at a free surface this form is the one that makes grad(div u) derive from
// the energy (1/2) sum_i (div u)_i^2, so the elastic force conserves energy.
BRECCIA_HD inline void gradient_adjoint_at(long long i, BondsView b, const double* phi, double scale,
                                           double out[3]) {
  gradient_sum_at<true>(i, b, phi, scale, out);
}

// <div u>_i = (d/n0) sum_j (u_j - u_i) . r_ij / |r_ij|^2 w_ij                (eq 2)
BRECCIA_HD inline double divergence_at(long long i, BondsView b, VectorField u, double scale) {
  double acc = 0.0;
  for (long long k = b.offset[i]; k < b.offset[i + 1]; ++k) {
    const long long j = b.neighbour[k];
    const double r2 = b.rx[k] * b.rx[k] + b.ry[k] * b.ry[k] + b.rz[k] * b.rz[k];
    acc += ((u.x[j] - u.x[i]) * b.rx[k] + (u.y[j] - u.y[i]) * b.ry[k] + (u.z[j] - u.z[i]) * b.rz[k]) *
           b.weight[k] / r2;
  }
  return scale * acc;
}

// <lap u>_i = (2d/(lambda n0)) sum_j (u_j - u_i) w_ij, per component          (eq 3)
BRECCIA_HD inline void laplacian_at(long long i, BondsView b, VectorField u, double scale,
                                    double out[3]) {
  double lx = 0.0, ly = 0.0, lz = 0.0;
  for (long long k = b.offset[i]; k < b.offset[i + 1]; ++k) {
    const long long j = b.neighbour[k];
    lx += (u.x[j] - u.x[i]) * b.weight[k];
    ly += (u.y[j] - u.y[i]) * b.weight[k];
    lz += (u.z[j] - u.z[i]) * b.weight[k];
  }
  out[0] = scale * lx;
  out[1] = scale * ly;
  out[2] = scale * lz;
}

// Scalar Laplacian, same normalisation.
BRECCIA_HD inline double laplacian_scalar_at(long long i, BondsView b, const double* phi, double scale) {
  double acc = 0.0;
  for (long long k = b.offset[i]; k < b.offset[i + 1]; ++k)
    acc += (phi[b.neighbour[k]] - phi[i]) * b.weight[k];
  return scale * acc;
}

// Elastic acceleration of one particle:
//   a_i = graddiv_per_rho * <grad(div u)>_i + laplacian_per_rho * <lap u>_i
// Navier (isotropic): graddiv = (lambda + mu)/rho, laplacian = mu/rho.
// Paper eq. (6) (rotation-free): graddiv = C13/rho, laplacian = 2 C55/rho.
// grad(div u) is the composition of eq. (2) then the adjoint gradient of eq. (1) applied
// to the precomputed divergence field `div`.
struct ElasticCoefficients {
  double graddiv_per_rho = 0.0;    // m^2/s^2
  double laplacian_per_rho = 0.0;  // m^2/s^2
};

BRECCIA_HD inline void elastic_acceleration_at(long long i, BondsView b, VectorField u, const double* div,
                                               OperatorScales s, ElasticCoefficients c, double out[3]) {
  // One pass over the bonds for both terms (the same as gradient_adjoint_at(div) and
  // laplacian_at(u), fused: the bond data is read once).
  double gx = 0.0, gy = 0.0, gz = 0.0, lx = 0.0, ly = 0.0, lz = 0.0;
  const double di = div[i];
  for (long long k = b.offset[i]; k < b.offset[i + 1]; ++k) {
    const long long j = b.neighbour[k];
    const double w = b.weight[k];
    const double r2 = b.rx[k] * b.rx[k] + b.ry[k] * b.ry[k] + b.rz[k] * b.rz[k];
    const double g = (div[j] + di) * w / r2;
    gx += g * b.rx[k];
    gy += g * b.ry[k];
    gz += g * b.rz[k];
    lx += (u.x[j] - u.x[i]) * w;
    ly += (u.y[j] - u.y[i]) * w;
    lz += (u.z[j] - u.z[i]) * w;
  }
  const double cg = c.graddiv_per_rho * s.gradient, cl = c.laplacian_per_rho * s.laplacian;
  out[0] = cg * gx + cl * lx;
  out[1] = cg * gy + cl * ly;
  out[2] = cg * gz + cl * lz;
}

// Strain-like energy density of particle i for the same operator (J/m^3 times 1/rho):
// (graddiv/2) (div u)_i^2 + (laplacian/4) (2d/(lambda n0)) sum_j w |u_j - u_i|^2.
// Summed over particles times rho V it is the potential whose negative gradient is the
// force above, hence the discrete energy that symplectic integrators conserve.
BRECCIA_HD inline double elastic_energy_per_rho_at(long long i, BondsView b, VectorField u, const double* div,
                                                   OperatorScales s, ElasticCoefficients c) {
  double pair = 0.0;
  for (long long k = b.offset[i]; k < b.offset[i + 1]; ++k) {
    const long long j = b.neighbour[k];
    const double dx = u.x[j] - u.x[i], dy = u.y[j] - u.y[i], dz = u.z[j] - u.z[i];
    pair += (dx * dx + dy * dy + dz * dz) * b.weight[k];
  }
  return 0.5 * c.graddiv_per_rho * div[i] * div[i] + 0.25 * c.laplacian_per_rho * s.laplacian * pair;
}

// Time integration of one particle component (the CPU loops and the CUDA launcher call these,
// so both round alike). Symplectic Euler, the paper's eqs (7)-(8): v^{k+1} = v^k + dt a(u^k),
// u^{k+1} = u^k + dt v^{k+1}.
BRECCIA_HD inline void symplectic_euler_at(double& u, double& v, double a, double dt) {
  v += dt * a;
  u += dt * v;
}

// Velocity Verlet, first half: half kick with a(u^k), then the drift with the half-step velocity.
BRECCIA_HD inline void verlet_kick_drift_at(double& u, double& v, double a, double half_dt, double dt) {
  v += half_dt * a;
  u += dt * v;
}

// Velocity Verlet, second half kick with a(u^{k+1}).
BRECCIA_HD inline void verlet_kick_at(double& v, double a, double half_dt) { v += half_dt * a; }

}  // namespace breccia::mps
