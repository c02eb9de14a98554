#pragma once
// Contact physics of the stress-based MPS solid (contact.hpp), written once as BRECCIA_HD
// functions over plain values, so the OpenMP loops in contact.cpp and a CUDA launcher call
// the same bodies. Every normal force derives from a penalty potential k g^2 / 2 (g the
// penetration), so frictionless contact conserves energy up to the time-integration error;
// friction is a tangential spring with a Coulomb slip limit (coulomb_tangential_force).
#include <cmath>

#include "breccia/mps/kernels.hpp"

namespace breccia::mps {

// Two particles of different bodies (or not bonded) closer than the contact distance d
// repel along the line of their centres: energy k (d - r)^2 / 2, force on i
// k (d - r) (x_i - x_j)/r. A central pair force conserves linear and angular momentum and
// is the exact gradient of the energy. dx = x_i - x_j (current). Returns the energy of the
// pair (0 when apart) and adds the force on i to f.
BRECCIA_HD inline double particle_pair_contact(const double dx[3], double distance, double stiffness, double f[3]) {
  const double r = std::sqrt(dx[0] * dx[0] + dx[1] * dx[1] + dx[2] * dx[2]);
  if (!(r < distance) || r <= 0.0) return 0.0;
  const double g = distance - r;
  for (int a = 0; a < 3; ++a) f[a] += stiffness * g * dx[a] / r;
  return 0.5 * stiffness * g * g;
}

// Signed penetration of point (px, py) into a closed 2D polygon (vertices x[k], y[k],
// k < count, either orientation): the distance to the nearest boundary point when inside,
// 0 outside. normal: the unit direction from the point to that boundary point (pointing
// out of the polygon), along which the penalty force k g pushes the particle. The distance
// to the boundary is continuous across the polygon, so the energy k g^2/2 is a potential
// (also for concave polygons, where only its gradient jumps on the medial axis).
BRECCIA_HD inline double polygon_penetration(const double* x, const double* y, int count, double px, double py,
                                             double normal[2]) {
  bool inside = false;
  double best = 1e300, nx = 0.0, ny = 0.0;
  for (int k = 0, m = count - 1; k < count; m = k++) {
    // Crossing number (ray to +x) for inside/outside.
    if ((y[k] > py) != (y[m] > py)) {
      const double xc = x[m] + (py - y[m]) * (x[k] - x[m]) / (y[k] - y[m]);
      if (px < xc) inside = !inside;
    }
    // Nearest point on edge m -> k.
    const double ex = x[k] - x[m], ey = y[k] - y[m];
    double t = ((px - x[m]) * ex + (py - y[m]) * ey) / (ex * ex + ey * ey);
    t = t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t);
    const double qx = x[m] + t * ex - px, qy = y[m] + t * ey - py;
    const double d2 = qx * qx + qy * qy;
    if (d2 < best) {
      best = d2;
      nx = qx;
      ny = qy;
    }
  }
  if (!inside) return 0.0;
  const double d = std::sqrt(best);
  if (d <= 0.0) return 0.0;
  normal[0] = nx / d;
  normal[1] = ny / d;
  return d;
}

// Coulomb friction of one particle on a rigid surface, regularised as a tangential spring
// with a slip limit (as the crack model of seed 000, and Cundall & Strack's DEM contact):
// the spring elongation s follows the relative tangential motion, F_t = -k_t s; while
// sticking, |F_t| <= mu_s N; beyond it the contact slips, |F_t| = mu_k N and s is shortened
// to mu_k N / k_t (the slip, the rest of the elongation, dissipates mu_k N times its
// length); a slipping contact sticks again when the spring force falls below mu_k N (the
// relative motion stopped or reversed).
struct FrictionState {
  double s[3] = {0.0, 0.0, 0.0};  // tangential spring elongation, m
  int slipping = 0;
};

// n: unit contact normal; v_rel: velocity of the particle relative to the surface; N >= 0
// the normal force. Updates the state and adds the tangential force to f. Returns the
// energy dissipated by slip in this step (J).
BRECCIA_HD inline double coulomb_tangential_force(FrictionState& st, const double n[3], const double v_rel[3],
                                                  double dt, double normal_force, double k_t, double mu_s,
                                                  double mu_k, double f[3]) {
  // Keep the spring in the current tangent plane (the surface or the particle may turn),
  // with its length preserved, then stretch it by the tangential relative motion.
  const double len0 = std::sqrt(st.s[0] * st.s[0] + st.s[1] * st.s[1] + st.s[2] * st.s[2]);
  const double sn = st.s[0] * n[0] + st.s[1] * n[1] + st.s[2] * n[2];
  for (int a = 0; a < 3; ++a) st.s[a] -= sn * n[a];
  const double len1 = std::sqrt(st.s[0] * st.s[0] + st.s[1] * st.s[1] + st.s[2] * st.s[2]);
  if (len1 > 0.0)
    for (int a = 0; a < 3; ++a) st.s[a] *= len0 / len1;
  const double vn = v_rel[0] * n[0] + v_rel[1] * n[1] + v_rel[2] * n[2];
  for (int a = 0; a < 3; ++a) st.s[a] += (v_rel[a] - vn * n[a]) * dt;
  const double len = std::sqrt(st.s[0] * st.s[0] + st.s[1] * st.s[1] + st.s[2] * st.s[2]);
  const double trial = k_t * len;
  double dissipated = 0.0;
  const double limit_static = mu_s * normal_force, limit_kinetic = mu_k * normal_force;
  if (st.slipping ? trial > limit_kinetic : trial > limit_static) {
    st.slipping = 1;
    const double keep = limit_kinetic / k_t;  // spring length carrying mu_k N
    // Work of the friction force mu_k N over the slip len - keep (backward Euler: the
    // spring energy is then the rest of the work of the relative motion).
    dissipated = limit_kinetic * (len - keep);
    for (int a = 0; a < 3; ++a) st.s[a] *= keep / len;
  } else {
    st.slipping = 0;
  }
  for (int a = 0; a < 3; ++a) f[a] -= k_t * st.s[a];
  return dissipated;
}

}  // namespace breccia::mps
