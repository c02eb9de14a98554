#pragma once
// The per-particle phases of Solid::step (solid.cpp), one BRECCIA_HD body each, so the
// OpenMP loops and the CUDA launcher (solver/cuda/src/mps_solid_cuda.cu) run the same code
// on the same data in the same order:
//   1. stress_phase_at        gradient, stress update, force matrices (solid_kernels.hpp)
//   2. pressure_floor_at      repulsive pressure only: the lowest pressure around i
//   3. half_space_contact_at  rigid planes: penalty (half_space_force_at) and Coulomb friction
//   4. solid_acceleration_at  internal + external + contact force, gravity, damping
// and the two measures taken every kClumpingCheckEvery steps:
//   squeezed_bond_length      the substep count (Solid::update_substeps)
//   clumping_ratio            the clumping detector (stability_checks.hpp)
#include "breccia/mps/contact_kernels.hpp"
#include "breccia/mps/solid_kernels.hpp"

namespace breccia::mps {

// Per-particle arrays that phase 1 reads and writes.
struct SolidStressState {
  Mat3* gradient = nullptr;        // H = F - I at the end of the last step
  Mat3* f_inverse = nullptr;       // F^-1 of the same
  SymTensor* stress = nullptr;     // Cauchy stress, Pa
  double* eq_plastic_strain = nullptr;
  double* stress_work_j = nullptr; // accumulated stress work of the particle
  double* pressure_pa = nullptr;   // -tr(sigma)/3
  ForceMatrices* matrices = nullptr;
  // Material damping (law.viscous_time_s > 0; nullptr: none): the viscous stress of the last
  // step, and the energy it has dissipated per particle.
  SymTensor* viscous_stress = nullptr;
  double* viscous_work_j = nullptr;
};

struct SolidStressInputs {
  BondsView bonds;
  VectorField u;                   // displacement since the stencils' reference
  const double* volume_m3 = nullptr;  // stencil volumes
  const Mat3* moment_inverse = nullptr;
  SolidLaw law;
  int dimension = 2;
  double hourglass_stiffness = 0.0;  // K_hg before the plastic scaling
  double dt_s = 0.0;                 // the (sub)step: the strain rate of material damping
  const double* bond_coefficient = nullptr;  // c_k per bond (bond_coefficient; nullptr: computed per bond)
};

// Phase 1 for particle i: H from the current displacement, the stress update over the step
// (rotation, Hooke increment, radial return), the stress work, and the force matrices with
// the hourglass stiffness scaled by the radial return's deviatoric factor. Returns |H|^2
// (Frobenius), or -1 when the new F is inverted (det F <= 0, or not finite); the particle is
// then left unchanged, and the caller decides (fracture may detach it; otherwise an error).
BRECCIA_HD BRECCIA_FLATTEN inline double stress_phase_at(long long i, const SolidStressInputs& in, const SolidStressState& s) {
  const Mat3 h_new =
      displacement_gradient_at(i, in.bonds, in.u, in.volume_m3, in.moment_inverse[i], in.dimension, in.bond_coefficient);
  const Mat3 f = deformation_gradient(h_new);
  if (!(det(f, in.dimension) > 0.0)) return -1.0;  // also catches NaN
  double deviatoric_scale = 1.0;
  SymTensor strain_increment;
  s.stress_work_j[i] += in.volume_m3[i] * update_stress(in.law, s.gradient[i], s.f_inverse[i], h_new, in.dimension,
                                                        s.stress[i], s.eq_plastic_strain[i], &deviatoric_scale,
                                                        &strain_increment);
  double h2 = 0.0;
  for (double v : h_new.a) h2 += v * v;
  s.gradient[i] = h_new;
  s.f_inverse[i] = inverse(f, in.dimension);
  s.pressure_pa[i] = pressure_of(s.stress[i]);
  SymTensor force_stress = s.stress[i];
  if (s.viscous_stress && in.law.viscous_time_s > 0.0) {
    // Material damping. The viscous stress of the last step drove the particles from the
    // last configuration to this one, so its work is booked on this step's strain increment
    // (the work of that force over that motion); the new one, from this increment over dt (a
    // backward difference: explicit, as the force must be), acts over the next step.
    SymTensor& viscous = s.viscous_stress[i];
    s.viscous_work_j[i] += in.volume_m3[i] * contract(viscous, strain_increment);
    viscous = viscous_stress_of(in.law, strain_increment, in.dt_s);
    force_stress = add_stresses(force_stress, viscous);
  }
  s.matrices[i] = force_matrices(force_stress, h_new, s.f_inverse[i], in.moment_inverse[i],
                                 in.hourglass_stiffness * deviatoric_scale, in.dimension);
  return h2;
}

// Phase 2 (pressure_force: repulsive): p^_i, the lowest pressure over i and its neighbours,
// from which solid_force_at measures the pressure of i's bonds. A particle near a free
// surface (number density below 0.97 n0, full_stencil 0) gets 0: there the shift would act
// as a surface pressure and feed back on itself, so it keeps the conservative form, as MPS
// fluids hold surface particles at zero pressure.
BRECCIA_HD inline double pressure_floor_at(long long i, BondsView b, const char* full_stencil, const double* pressure_pa) {
  if (!full_stencil[i]) return 0.0;
  double lowest = pressure_pa[i];
  for (long long k = b.offset[i]; k < b.offset[i + 1]; ++k) {
    const double p = pressure_pa[b.neighbour[k]];
    lowest = p < lowest ? p : lowest;
  }
  return lowest;
}

// Phase 3, one rigid plane {x : (x - point) . normal >= 0} (normal of unit length) and a
// particle at current position x: adds the penalty force k g normal (g = the depth below
// the plane) to f and returns g, 0 when the particle is on the allowed side. The energy
// k g^2 / 2 makes the frictionless bounce conservative (solid.hpp, RigidFloor).
BRECCIA_HD inline double half_space_force_at(const double x[3], const double point[3], const double normal[3],
                                             double stiffness_n_m, double f[3]) {
  double height = 0.0;
  for (int a = 0; a < 3; ++a) height += (x[a] - point[a]) * normal[a];
  if (height >= 0.0) return 0.0;
  const double normal_force = stiffness_n_m * -height;
  for (int a = 0; a < 3; ++a) f[a] += normal_force * normal[a];
  return -height;
}

// A rigid plane and its contact law as plain values (HalfSpace of contact.hpp, flattened
// for the device).
struct PlaneContact {
  double point[3] = {0.0, 0.0, 0.0};
  double normal[3] = {0.0, 1.0, 0.0};  // unit
  double normal_stiffness = 0.0, tangential_stiffness = 0.0;
  double static_friction = 0.0, kinetic_friction = 0.0;
  double velocity[3] = {0.0, 0.0, 0.0};  // of the plane (ground motion); friction acts on the relative velocity
};

// Phase 3 for one plane and a particle at current position x with velocity v (the plane moves
// at plane.velocity): the penalty (half_space_force_at), then, if the plane has friction, the
// particle's tangential spring on it updated over dt (coulomb_tangential_force, with the
// penalty's size as the normal force), adding the slip's dissipation to *dissipated_j and
// the spring's energy to *spring_energy_j. A particle off the plane loses its spring
// (release_friction_spring: what it held is dissipated).
// Returns the depth (<= 0: no contact). Contact::obstacle_forces and the CUDA launcher run it.
BRECCIA_HD inline double half_space_contact_at(const double x[3], const double v[3], const PlaneContact& plane,
                                               double dt, FrictionState& spring, double f[3], double* dissipated_j,
                                               double* spring_energy_j) {
  const double depth = half_space_force_at(x, plane.point, plane.normal, plane.normal_stiffness, f);
  const double v_rel[3] = {v[0] - plane.velocity[0], v[1] - plane.velocity[1], v[2] - plane.velocity[2]};
  if (depth <= 0.0) {
    *dissipated_j += release_friction_spring(spring, v_rel, dt, plane.tangential_stiffness);
    return depth;
  }
  if (plane.static_friction > 0.0 || plane.kinetic_friction > 0.0) {
    *dissipated_j += coulomb_tangential_force(spring, plane.normal, v_rel, dt, plane.normal_stiffness * depth,
                                              plane.tangential_stiffness, plane.static_friction,
                                              plane.kinetic_friction, f);
    const double* e = spring.s;
    *spring_energy_j += 0.5 * plane.tangential_stiffness * (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
  }
  return depth;
}

struct SolidAccelerationInputs {
  SolidForceInputs forces;
  const double* external_n[3] = {nullptr, nullptr, nullptr};
  const double* contact_n[3] = {nullptr, nullptr, nullptr};  // nullptr: no contact
  VectorField v;
  const double* volume_m3 = nullptr;  // initial volumes: mass = density x volume
  double density_kg_m3 = 0.0;
  double gravity_m_s2[3] = {0.0, 0.0, 0.0};
  double damping_per_s = 0.0;
  int dimension = 2;
};

// Phase 4: a_i = (internal + external + contact force) / m_i + g - damping v_i on the
// components 0..dimension-1 (the others are left as they are).
BRECCIA_HD inline void solid_acceleration_at(long long i, const SolidAccelerationInputs& in, double* ax, double* ay,
                                             double* az) {
  double f[3];
  solid_force_at(i, in.forces, f);
  for (int a = 0; a < 3; ++a) f[a] += in.external_n[a][i];
  if (in.contact_n[0])
    for (int a = 0; a < 3; ++a) f[a] += in.contact_n[a][i];
  const double mass = in.density_kg_m3 * in.volume_m3[i];
  const double v[3] = {in.v.x[i], in.v.y[i], in.v.z[i]};
  double* out[3] = {ax, ay, az};
  for (int a = 0; a < in.dimension; ++a)
    out[a][i] = f[a] / mass + in.gravity_m_s2[a] - in.damping_per_s * v[a];
}

// The length that sets the substeps (Solid::update_substeps) of one intact bond with
// reference vector r, current vector d (r plus the displacement difference since the
// stencils' reference) and relative velocity w: its closest approach within `window` seconds
// at that velocity, as spacing x current / reference length (total Lagrangian: only the
// shortening matters), or as the current length itself (updated stencils).
BRECCIA_HD inline double squeezed_bond_length(const double r[3], const double d[3], const double w[3], double window_s,
                                              double spacing_m, bool updated) {
  double dw = 0.0, ww = 0.0;
  for (int a = 0; a < 3; ++a) {
    dw += d[a] * w[a];
    ww += w[a] * w[a];
  }
  double t = 0.0;  // time of the closest approach
  if (dw < 0.0 && ww > 0.0) t = -dw / ww < window_s ? -dw / ww : window_s;
  double closest2 = 0.0;
  for (int a = 0; a < 3; ++a) closest2 += (d[a] + t * w[a]) * (d[a] + t * w[a]);
  const double closest = std::sqrt(closest2);
  return updated ? closest : spacing_m * closest / std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
}

// Nearest-neighbour bond: reference length up to `near` (1.5 spacings, stability_checks.cpp).
BRECCIA_HD inline bool is_near_bond(BondsView b, long long k, double near_m) {
  return std::sqrt(b.rx[k] * b.rx[k] + b.ry[k] * b.ry[k] + b.rz[k] * b.rz[k]) <= near_m;
}

// A crack-face particle: one of its nearest-neighbour bonds is cut (weight 0).
BRECCIA_HD inline bool on_crack_face_at(long long i, BondsView b, double near_m) {
  for (long long k = b.offset[i]; k < b.offset[i + 1]; ++k)
    if (b.weight[k] == 0.0 && is_near_bond(b, k, near_m)) return true;
  return false;
}

// The clumping measure of bond k of particle i (stability_checks.hpp): its current length
// over the length F_i = I + h predicts, |x_j - x_i| / |F_i r|, in *ratio. Returns false for a
// bond that is not measured: cut (weight 0), beyond the nearest neighbours, or no shorter
// than its reference length: clumping pulls neighbours together, and particles moved as one
// rigid block (a driven or held end) next to a stretching region would read 1 / (1 + strain),
// F_i being fitted over a stencil that reaches into the stretch (measured: 0.64 at 70 %
// nominal strain, 0.50 at 100 %). u: displacement since the stencils' reference.
BRECCIA_HD inline bool clumping_ratio(BondsView b, long long i, long long k, VectorField u, const Mat3& h, double near_m,
                                      double* ratio) {
  if (b.weight[k] == 0.0 || !is_near_bond(b, k, near_m)) return false;
  const double r[3] = {b.rx[k], b.ry[k], b.rz[k]};
  const long long j = b.neighbour[k];
  double predicted2 = 0.0;
  for (int a = 0; a < 3; ++a) {
    const double fr = r[a] + h(a, 0) * r[0] + h(a, 1) * r[1] + h(a, 2) * r[2];
    predicted2 += fr * fr;
  }
  // Reference bond vectors may be periodic images: the current one is r + u_j - u_i.
  const double d[3] = {r[0] + u.x[j] - u.x[i], r[1] + u.y[j] - u.y[i], r[2] + u.z[j] - u.z[i]};
  const double length2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
  if (length2 >= r[0] * r[0] + r[1] * r[1] + r[2] * r[2]) return false;
  *ratio = std::sqrt(length2 / predicted2);
  return true;
}

}  // namespace breccia::mps
