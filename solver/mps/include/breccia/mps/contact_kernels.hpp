#pragma once
// Contact physics of the stress-based MPS solid (contact.hpp), written once as BRECCIA_HD
// functions over plain values, so the OpenMP loops in contact.cpp and a CUDA launcher call
// the same bodies. Every normal force derives from a penalty potential k g^2 / 2 (g the
// penetration), so frictionless contact conserves energy up to the time-integration error
// (with the neighbour-distribution normal, up to the neglected change of the normal);
// friction is a tangential spring with a Coulomb slip limit (coulomb_tangential_force).
#include <cmath>

#include "breccia/mps/kernels.hpp"

namespace breccia::mps {

// Outward surface direction of particle i from its neighbour distribution ([Inagaki 2009]: "the
// contact normal is estimated from the neighbour relations, so the roughness of the
// particle arrangement does not matter"): the weighted mean of the unit directions from its
// intact neighbours to i in the current configuration, sum_j w_ij (x_i - x_j)/r_ij / sum_j
// w_ij. Not normalised on purpose: its length says how one-sided the neighbourhood is
// (re = 2.1 spacings, square lattice: 0 inside, 0.008 one row below a face, 0.42 on a flat
// face, 0.76 at a corner), which distribution_normal_geometry uses to tell faces from the
// inside. x: 3N current positions; bonds with weight 0 (cut) do not count, so crack faces
// get their own normal.
BRECCIA_HD inline void neighbour_distribution_direction(long long i, const BondsView& b, const double* x, double out[3]) {
  double sum[3] = {0.0, 0.0, 0.0}, weights = 0.0;
  for (long long k = b.offset[i]; k < b.offset[i + 1]; ++k) {
    const double w = b.weight[k];
    if (w == 0.0) continue;
    const long long j = b.neighbour[k];
    const double d[3] = {x[3 * i] - x[3 * j], x[3 * i + 1] - x[3 * j + 1], x[3 * i + 2] - x[3 * j + 2]};
    const double r = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    if (r <= 0.0) continue;
    for (int a = 0; a < 3; ++a) sum[a] += w * d[a] / r;
    weights += w;
  }
  for (int a = 0; a < 3; ++a) out[a] = weights > 0.0 ? sum[a] / weights : 0.0;
}

// Geometry of one contact pair: the unit normal n (direction of the force on i), the
// penetration along it g = d - (x_i - x_j) . n, the tangential offset t (the part of
// x_i - x_j across n) and the pair's weight w(|t|).
struct PairContactGeometry {
  double n[3] = {0.0, 0.0, 0.0};
  double gap = 0.0;         // penetration, > 0 in contact
  double t[3] = {0.0, 0.0, 0.0};
  double weight = 1.0;      // share of the pair in the contact, 0..1
  double dweight_dt = 0.0;  // d weight / d |t|
};

// Pair direction (contact.particles.normal: pair): two particles (of different bodies, or
// not bonded) closer than the contact distance d repel along the line of their centres,
// n = e = (x_i - x_j)/r, g = d - r, w = 1: energy k (d - r)^2 / 2, force on i k (d - r) e.
// A central pair force conserves linear and angular momentum and is the exact gradient of
// the energy; but between laterally offset particles of two flat faces it has a tangential
// part and its size depends on the offset: the faces ride over an egg-crate potential
// ("washboard"; a block over a slab whose particles sit over its gaps rests on pairs
// 30 deg off the normal, so Coulomb friction mu_k k (d - r) per pair is 1/cos 30 = 1.15
// times mu_k times the weight).
BRECCIA_HD inline PairContactGeometry pair_direction_geometry(const double dx[3], double distance) {
  PairContactGeometry c;
  const double r = std::sqrt(dx[0] * dx[0] + dx[1] * dx[1] + dx[2] * dx[2]);
  if (r <= 0.0) return c;
  for (int a = 0; a < 3; ++a) c.n[a] = dx[a] / r;
  c.gap = distance - r;
  return c;
}

BRECCIA_HD inline double contact_smoothstep(double x) {
  x = x < 0.0 ? 0.0 : (x > 1.0 ? 1.0 : x);
  return x * x * (3.0 - 2.0 * x);
}

// Neighbour-distribution normal (contact.particles.normal: neighbour_distribution).
// From the two particles' outward surface directions m_i, m_j
// (neighbour_distribution_direction), the face normal n_f = (m_j - m_i)/|m_j - m_i| (j's
// outward and i's inward normal). Between two faces that face each other the contact is
// planar: penetration along the normal, g = d - (x_i - x_j) . n, independent of the lateral
// offset t, and each pair counts with the hat weight w = 1 - |t|/window (window = spacing),
// so the weights of a particle's partners on a regular facing surface sum to one at any
// lateral position: the normal force does not depend on how the lattices are offset and
// has no tangential part - no washboard. Energy k w g^2 / 2 per pair, force its gradient
// with n held fixed (normal part k w g n, tangential part -k g^2/2 dw/d|t| t/|t|, which
// cancels between the partners of a regular surface).
// The face normal is used only where both particles are on faces that face each other; a
// corner (its m is 45 deg off the face it touches, so a planar penetration along a blend of
// the two would be off by up to h sin(22 deg)) or a particle inside a body (|m| near 0, its
// direction noise; a flat face has |m| = 0.42 at re = 2.1 spacings) meets the other body
// through the pair direction, exact for a point contact: n = normalize((1 - b) e + b n_f),
//   b = S((a - cos 10 deg)/(cos 3 deg - cos 10 deg)) S((min(|m_i|, |m_j|) - 0.1)/0.1),
// a = -m_i . m_j / (|m_i| |m_j|) the alignment of the two face normals, S the smoothstep.
// With b = 0 this is the pair direction exactly (t = 0, w = 1, g = d - r).
// Antisymmetric in i and j: the forces on i and j are equal and opposite (linear momentum
// exact); angular momentum is not exact (face-face forces are not central), nor is the
// energy where n turns (its own derivative is neglected; zero between flat faces).
BRECCIA_HD inline PairContactGeometry distribution_normal_geometry(const double dx[3], const double m_i[3],
                                                                  const double m_j[3], double distance,
                                                                  double window) {
  PairContactGeometry c = pair_direction_geometry(dx, distance);
  const double mi = std::sqrt(m_i[0] * m_i[0] + m_i[1] * m_i[1] + m_i[2] * m_i[2]);
  const double mj = std::sqrt(m_j[0] * m_j[0] + m_j[1] * m_j[1] + m_j[2] * m_j[2]);
  if (!(mi > 0.0) || !(mj > 0.0)) return c;
  const double align = -(m_i[0] * m_j[0] + m_i[1] * m_j[1] + m_i[2] * m_j[2]) / (mi * mj);
  const double cos3 = 0.99862953475457383, cos10 = 0.98480775301220802;
  const double blend = contact_smoothstep((align - cos10) / (cos3 - cos10)) *
                       contact_smoothstep(((mi < mj ? mi : mj) - 0.1) / 0.1);
  if (blend <= 0.0) return c;
  const double nf[3] = {m_j[0] - m_i[0], m_j[1] - m_i[1], m_j[2] - m_i[2]};
  const double lf = std::sqrt(nf[0] * nf[0] + nf[1] * nf[1] + nf[2] * nf[2]);
  double n[3];
  for (int a = 0; a < 3; ++a) n[a] = (1.0 - blend) * c.n[a] + blend * nf[a] / lf;
  const double ln = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  if (!(ln > 1e-12)) return c;
  for (int a = 0; a < 3; ++a) c.n[a] = n[a] / ln;
  const double along = dx[0] * c.n[0] + dx[1] * c.n[1] + dx[2] * c.n[2];
  c.gap = distance - along;
  for (int a = 0; a < 3; ++a) c.t[a] = dx[a] - along * c.n[a];
  const double tl = std::sqrt(c.t[0] * c.t[0] + c.t[1] * c.t[1] + c.t[2] * c.t[2]);
  c.weight = tl < window ? 1.0 - tl / window : 0.0;
  c.dweight_dt = tl < window ? -1.0 / window : 0.0;
  return c;
}

// Normal penalty of a pair with geometry c: adds the force on i (minus it acts on j) to f,
// returns the energy k w g^2 / 2 (0 when apart) and the normal force k w g in *normal_force.
BRECCIA_HD inline double pair_normal_force(const PairContactGeometry& c, double stiffness, double f[3],
                                           double* normal_force) {
  *normal_force = 0.0;
  if (!(c.gap > 0.0) || !(c.weight > 0.0)) return 0.0;
  *normal_force = stiffness * c.weight * c.gap;
  for (int a = 0; a < 3; ++a) f[a] += *normal_force * c.n[a];
  const double tl = std::sqrt(c.t[0] * c.t[0] + c.t[1] * c.t[1] + c.t[2] * c.t[2]);
  if (tl > 0.0 && c.dweight_dt != 0.0)
    for (int a = 0; a < 3; ++a) f[a] -= 0.5 * stiffness * c.gap * c.gap * c.dweight_dt * c.t[a] / tl;
  return 0.5 * stiffness * c.weight * c.gap * c.gap;
}

// Normal dashpot of a linear spring-dashpot contact with a stated coefficient of restitution
// e (0 < e <= 1). A mass m_eff on a spring k and a dashpot c, F = k g + c dg/dt while the
// penetration g > 0, is a damped oscillator; it leaves the contact (g back to 0) after half
// a damped period with the speed ratio e = exp(-pi zeta / sqrt(1 - zeta^2)), zeta =
// c / (2 sqrt(k m_eff)), independent of the impact speed (Schaefer, Dippel & Wolf 1996,
// docs/references.md). Inverted: zeta = -ln e / sqrt(pi^2 + ln^2 e); e = 1 gives 0 (no dashpot).
BRECCIA_HD inline double damping_ratio_of_restitution(double e) {
  if (!(e < 1.0)) return 0.0;
  const double pi = 3.14159265358979323846, l = std::log(e);
  return -l / std::sqrt(pi * pi + l * l);
}

// Signed penetration of point (px, py) into a closed 2D polygon (vertices x[k], y[k],
// k < count, either orientation): the distance to the nearest boundary point when inside,
// 0 outside. normal: the unit direction from the point to that boundary point (pointing
// out of the polygon), along which the penalty force k g pushes the particle. The distance
// to the boundary is continuous across the polygon, so the energy k g^2/2 is a potential
// (also for concave polygons, where only its gradient jumps on the medial axis).
BRECCIA_HD inline double polygon_penetration(const double* x, const double* y, int count, double px, double py,
                                             double normal[2]) {
  // Inside or outside first (crossing number, ray to +x): most points tested are outside, and
  // for those the nearest edge is not needed.
  bool inside = false;
  for (int k = 0, m = count - 1; k < count; m = k++) {
    if ((y[k] > py) != (y[m] > py)) {
      const double xc = x[m] + (py - y[m]) * (x[k] - x[m]) / (y[k] - y[m]);
      if (px < xc) inside = !inside;
    }
  }
  if (!inside) return 0.0;
  double best = 1e300, nx = 0.0, ny = 0.0;
  for (int k = 0, m = count - 1; k < count; m = k++) {
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
  const double d = std::sqrt(best);
  if (d <= 0.0) return 0.0;
  normal[0] = nx / d;
  normal[1] = ny / d;
  return d;
}

// Coulomb friction of one particle on a rigid surface, regularised as a tangential spring
// with a slip limit (as the crack model of [MPS harmonics], and Cundall & Strack's DEM contact):
// the spring elongation s follows the relative tangential motion, F_t = -k_t s; while
// sticking, |F_t| <= mu_s N; beyond it the contact slips, |F_t| = mu_k N and s is shortened
// to mu_k N / k_t; a slipping contact sticks again when the spring force falls below mu_k N
// (the relative motion stopped or reversed).
//
// Dissipation, booked so that the discrete energy balance closes. In the symplectic Euler
// step (a leapfrog with v^n the velocity of the half step before x^n) the force of step n,
// -k_t s_n, does the work -k_t s_n . (D_n + D_n+1)/2 on the particle, D_n = x^n - x^n-1 the
// relative displacement that stretches the spring at step n (v_rel dt); summed over the
// steps this is -sum_n k_t (s_n-1 + s_n) . D_n / 2, the trapezoidal work along the spring's
// path. The energy removed at step n is that work less the change of the spring's energy:
//   dissipated_n = k_t (s_n-1 + s_n) . D_n / 2 - k_t (|s_n|^2 - |s_n-1|^2) / 2,
// exactly 0 while sticking (s_n = s_n-1 + D_n) and mu_k N |D_n| in steady slip (s_n =
// s_n-1). It differs from mu_k N times the slip when the normal force changes within a step:
// a contact unloaded in one step (a corner lifting, a particle of a chattering face) sheds
// most of its spring's energy, which mu_k N (new, small) times the slip missed (an elastic
// block shaken on a frictional floor lost 7% of the ground's work that way).
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
  double stretch[3], previous[3];  // D_n (tangential) and s_n-1 (in the current tangent plane)
  for (int a = 0; a < 3; ++a) {
    stretch[a] = (v_rel[a] - vn * n[a]) * dt;
    previous[a] = st.s[a];
    st.s[a] += stretch[a];
  }
  const double len = std::sqrt(st.s[0] * st.s[0] + st.s[1] * st.s[1] + st.s[2] * st.s[2]);
  const double trial = k_t * len;
  const double limit_static = mu_s * normal_force, limit_kinetic = mu_k * normal_force;
  if (!(st.slipping ? trial > limit_kinetic : trial > limit_static)) {
    st.slipping = 0;
    for (int a = 0; a < 3; ++a) f[a] -= k_t * st.s[a];
    return 0.0;  // sticking: the spring holds all the work (the formula above gives 0)
  }
  st.slipping = 1;
  const double keep = limit_kinetic / k_t;  // spring length carrying mu_k N
  for (int a = 0; a < 3; ++a) st.s[a] *= keep / len;
  double work = 0.0;  // k_t (s_n-1 + s_n) . D_n / 2
  for (int a = 0; a < 3; ++a) work += 0.5 * k_t * (previous[a] + st.s[a]) * stretch[a];
  const double dissipated = work - 0.5 * k_t * (keep * keep - len0 * len0);
  for (int a = 0; a < 3; ++a) f[a] -= k_t * st.s[a];
  return dissipated;
}

// A contact that opens loses its spring (no normal force, nothing to hold it): the energy of
// the step's balance above with s_n = 0, k_t s_n-1 . D_n / 2 + k_t |s_n-1|^2 / 2, is
// dissipated (the second half of the last force's work, and the energy the spring held).
// v_rel: the particle's velocity relative to the surface (D_n = v_rel dt). Resets the spring
// and returns that energy (J).
BRECCIA_HD inline double release_friction_spring(FrictionState& st, const double v_rel[3], double dt, double k_t) {
  if (st.s[0] == 0.0 && st.s[1] == 0.0 && st.s[2] == 0.0) {
    st.slipping = 0;
    return 0.0;
  }
  double work = 0.0, energy = 0.0;
  for (int a = 0; a < 3; ++a) {
    work += 0.5 * k_t * st.s[a] * v_rel[a] * dt;
    energy += 0.5 * k_t * st.s[a] * st.s[a];
  }
  st = FrictionState{};
  return work + energy;
}

}  // namespace breccia::mps
