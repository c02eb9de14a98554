#include "breccia/mps/particles.hpp"
#include "breccia/mps/solid.hpp"
#include "breccia/mps/solid_phases.hpp"
#include "breccia/mps/stability_checks.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "breccia/common/error.hpp"

namespace breccia::mps {

// Below this many particles thread start-up costs more than a step (as in simulation.cpp).
constexpr long long kSolidParallelMin = 8192;

Solid::Solid(std::vector<double> position_m, std::vector<double> volume_m3, double density_kg_m3, const SolidLaw& law,
             const SolidOptions& options)
    : position_m_(std::move(position_m)),
      volume_m3_(std::move(volume_m3)),
      density_kg_m3_(density_kg_m3),
      law_(law),
      options_(options) {
  const size_t n = volume_m3_.size();
  if (position_m_.size() != 3 * n) throw RunError("mps solid: positions and volumes disagree in size");
  // The elastic law from F needs F to hold the whole deformation: plastic flow (the rate law's
  // return mapping) and rebuilt stencils (F measured from the last rebuild) keep the rate form.
  if (law_.plastic || options_.updated_lagrangian) law_.elastic = ElasticLaw::Rate;
  // Plane strain: every particle in one plane, so that no bond has a z component (the 2D
  // kernels skip the z row and column of every matrix, solid_kernels.hpp "Plane strain").
  if (options_.dimension == 2)
    for (size_t i = 1; i < n; ++i)
      if (position_m_[3 * i + 2] != position_m_[2])
        throw RunError("mps solid: a 2D (plane strain) solid needs every particle at the same z; particle " +
                       std::to_string(i) + " is at z = " + std::to_string(position_m_[3 * i + 2]) + " m, particle 0 at " +
                       std::to_string(position_m_[2]) + " m");
  mean_volume_m3_ = 0.0;
  for (double v : volume_m3_) mean_volume_m3_ += v / n;
  stencil_volume_m3_ = volume_m3_;
  stencil_volume_ratio_.assign(n, 1.0);
  build_stencils(position_m_);
  gradient_.assign(n, Mat3{});
  f_inverse_.assign(n, identity3());
  matrices_.assign(n, ForceMatrices{});
  for (auto& m : matrices_) m.hourglass_stiffness = hourglass_stiffness();
  stress_.assign(n, SymTensor{});
  eq_plastic_strain_.assign(n, 0.0);
  stress_work_j_.assign(n, 0.0);
  if (law_.viscous_time_s > 0.0) {
    viscous_stress_.assign(n, SymTensor{});
    viscous_work_j_.assign(n, 0.0);
  }
  pressure_pa_.assign(n, 0.0);
  pressure_floor_pa_.assign(n, 0.0);
  for (int a = 0; a < 3; ++a) {
    u_[a].assign(n, 0.0);
    v_[a].assign(n, 0.0);
    a_[a].assign(n, 0.0);
    external_force_n_[a].assign(n, 0.0);
    if (options_.updated_lagrangian) {
      u_at_rebuild_[a].assign(n, 0.0);
      u_stencil_[a].assign(n, 0.0);
    }
  }
  // Material damping shortens the stable step (damped_step_factor, solid_kernels.hpp).
  cfl_dt_s_ = options_.safety * options_.spacing_m / p_wave_speed() *
              damped_step_factor(law_.viscous_time_s, p_wave_speed(), options_.spacing_m);
  dt_s_ = options_.dt_s ? *options_.dt_s : cfl_dt_s_;
  // Four P-wave transits of the largest extent of the reference configuration (update_substeps).
  double extent = 0.0;
  for (int a = 0; a < 3; ++a) {
    double lo = 1e300, hi = -1e300;
    for (size_t i = 0; i < n; ++i) {
      lo = std::min(lo, position_m_[3 * i + a]);
      hi = std::max(hi, position_m_[3 * i + a]);
    }
    if (n > 0) extent = std::max(extent, hi - lo);
  }
  substep_hold_steps_ = std::max<long long>(100, static_cast<long long>(std::ceil(4.0 * extent / (p_wave_speed() * dt_s_))));
}

// Bonds within re of each other in the given configuration, their moment matrices and the
// surface flags. n0 is taken from the first (initial) build and kept: it sets the MPS
// scales and the hourglass stiffness, which must not jump at a stencil rebuild.
void Solid::build_stencils(const std::vector<double>& position_m) {
  const size_t n = volume_m3_.size();
  bonds_ = build_bonds(options_.dimension, position_m, options_.re_over_spacing * options_.spacing_m);
  if (!options_.body_id.empty()) {  // separate bodies meet through contact, not bonds
    const std::vector<int>& body = options_.body_id;
    remove_bonds(bonds_, [&body](long long i, long long j, long long) { return body[i] != body[j]; });
  }
  if (norm_.number_density_n0 == 0.0) norm_ = reference_normalisation(bonds_);
  const double mps_scale = options_.dimension / norm_.number_density_n0;
  const BondsView b = bonds_.view();
  bond_coefficient_.resize(bonds_.size());
  for (size_t i = 0; i < n; ++i) refresh_bond_coefficients(static_cast<long long>(i));
  moment_inverse_.resize(n);
  for (size_t i = 0; i < n; ++i)
    moment_inverse_[i] = inverse_moment_matrix_at(i, b, stencil_volume_m3_.data(), options_.dimension, mps_scale);
  full_stencil_.assign(n, 0);
  for (size_t i = 0; i < n; ++i) {
    double number_density = 0.0;
    for (long long k = b.offset[i]; k < b.offset[i + 1]; ++k) number_density += b.weight[k];
    full_stencil_[i] = number_density >= 0.97 * norm_.number_density_n0;
  }
}

void Solid::refresh_bond_coefficients(long long i) {
  const BondsView b = bonds_.view();
  for (long long k = b.offset[i]; k < b.offset[i + 1]; ++k)
    bond_coefficient_[k] = bond_coefficient(b, k, stencil_volume_m3_.data(), nullptr);
}

// Updated Lagrangian: the current configuration becomes the stencils' reference. Each
// particle keeps its stress and plastic strain (they live on particles); its gradient
// restarts from H = 0 on the new stencil, so the next increment dF = F_new F_old^-1 is
// measured from here. Volumes follow the deformation (V = V0 J); masses do not change.
// The hourglass residual of the old stencils is discarded (it was the non-affine part of
// the flow since the last rebuild, which plastic flow does not recover): its energy is
// booked as dissipated so the energy balance stays closed.
void Solid::rebuild_stencils_on_current_configuration() {
  hourglass_released_j_ = hourglass_energy_j();  // what the stencils hold now + what earlier ones held
  const size_t n = size();
  std::vector<double> current(3 * n);
  for (size_t i = 0; i < n; ++i) {
    for (int a = 0; a < 3; ++a) current[3 * i + a] = position_m_[3 * i + a] + u_[a][i];
    const Mat3 f = deformation_gradient(gradient_[i]);
    stencil_volume_ratio_[i] *= det(f);
    stencil_volume_m3_[i] = volume_m3_[i] * stencil_volume_ratio_[i];
  }
  for (int a = 0; a < 3; ++a) {
    u_at_rebuild_[a] = u_[a];
    std::fill(u_stencil_[a].begin(), u_stencil_[a].end(), 0.0);
  }
  build_stencils(current);
  update_substeps();  // on the new stencils (their bonds are the current ones)
  const Mat3 zero{};
  for (size_t i = 0; i < n; ++i) {
    gradient_[i] = zero;
    f_inverse_[i] = identity3();
    matrices_[i] = force_matrices(stress_in_force(i), zero, f_inverse_[i], moment_inverse_[i], matrices_[i].hourglass_stiffness,
                                  options_.dimension);
  }
  ++stencil_rebuilds_;
}

// The stable step follows the current distance between bonded particles: where the flow
// squeezes neighbours together the stiffness grows, through the stencil coefficients w/r^2
// (updated stencils) or the tangent of P = J sigma F^-T (total Lagrangian, ~F^-T F^-T), and
// at the initial step a Taylor bar's face, axially a quarter of the spacing, inverts within
// 20 us. Each step() is split into as many equal substeps as bring the step down to
// safety x the shortest current bond / c_L (a quarter above it allowed, below), so dt_s()
// and the step count the caller sees do not change. A bond's length counts as:
// - total Lagrangian: spacing x current / reference length. The reference stencils were
//   stable at dt_s_, so what matters is the shortening; bonds shorter than the spacing from
//   the start (particles on circles) do not substep a body at rest.
// - updated: its current length (capped at the spacing), as the rebuilt coefficients' w/r^2.
// The count is recomputed every kClumpingCheckEvery steps, and a bond may close further in
// between: each is taken at its closest approach within that window at its present relative
// velocity. Cut bonds (fracture, weight 0) carry no force and do not count.
double Solid::shortest_squeezed_bond_m() const {
  const long long n = static_cast<long long>(size());
  const BondsView b = bonds_.view();
  const bool updated = options_.updated_lagrangian;
  const double spacing = options_.spacing_m, window = kClumpingCheckEvery * dt_s_;
  // Displacement since the stencils' reference (u_stencil_ is refreshed per substep only).
  const auto since_reference = [&](int a, long long i) { return updated ? u_[a][i] - u_at_rebuild_[a][i] : u_[a][i]; };
  double shortest = spacing;
#pragma omp parallel for schedule(static) reduction(min : shortest) if (n > kSolidParallelMin)
  for (long long i = 0; i < n; ++i) {
    for (long long k = b.offset[i]; k < b.offset[i + 1]; ++k) {
      if (b.weight[k] == 0.0) continue;  // cut: carries no force
      const long long j = b.neighbour[k];
      const double r[3] = {b.rx[k], b.ry[k], b.rz[k]};
      double d[3], w[3];
      for (int a = 0; a < 3; ++a) {
        d[a] = r[a] + since_reference(a, j) - since_reference(a, i);
        w[a] = v_[a][j] - v_[a][i];
      }
      shortest = std::min(shortest, squeezed_bond_length(r, d, w, window, spacing, updated));
    }
  }
  return shortest;
}

void Solid::update_substeps() {
  if (!options_.substeps) return;
  const double shortest =
      device_ ? device_->shortest_squeezed_bond_m(kClumpingCheckEvery * dt_s_) : shortest_squeezed_bond_m();
  // A bond at 1/kMaxSubsteps of its length is a collapse that the inversion and clumping
  // checks stop; the cap only keeps a projected closest approach of ~0 from stalling the run.
  constexpr int kMaxSubsteps = 64;
  // A substep may exceed safety x shortest / c_L by a quarter, so the step is split only once
  // a bond has shortened by more than a fifth (safety 0.3 leaves that margin): split at any
  // shortening, an elastic body in contact (strains ~1e-4) would run at twice the cost.
  constexpr double kSubstepExcess = 1.25;
  // With material damping, its bound for the bond's length as for the spacing in the
  // constructor (it falls with the length: a shorter bond's mode is faster and more damped).
  const double stable_dt = kSubstepExcess * options_.safety * shortest / p_wave_speed() *
                           damped_step_factor(law_.viscous_time_s, p_wave_speed(), shortest);
  double wanted = std::ceil(dt_s_ / stable_dt - 1e-9);
  if (!(wanted >= 1.0)) wanted = 1.0;  // NaN from non-finite fields: the inversion check reports those
  const int count = static_cast<int>(std::min(wanted, static_cast<double>(kMaxSubsteps)));
  // Raised at once (stability), lowered only when no check has needed the higher count for
  // four wave transits of the body. Changing the step of symplectic Euler changes the energy
  // it conserves (its shadow energy depends on dt), and a count that follows a vibration up
  // and down, split while the bonds are squeezed and whole while they are not, pumps energy
  // into it every cycle: the rubber rings gained 10.7% over 6 ms that way, against 2.6% with
  // no substeps (cases/mps-rubber-rings).
  if (count >= substeps_) {
    substeps_ = count;
    last_needed_step_ = steps_;
  } else if (steps_ - last_needed_step_ >= substep_hold_steps_) {
    substeps_ = count;
  }
}

std::vector<double> Solid::volume_ratio() const {
  sync_host(false);
  std::vector<double> j(size());
  for (size_t i = 0; i < size(); ++i) {
    const Mat3 f = deformation_gradient(gradient_[i]);
    j[i] = stencil_volume_ratio_[i] * det(f);
  }
  return j;
}

// K_hg = alpha mu d / (n0 V_mean): with the volume-weighted residual sum, the hourglass
// energy density is alpha mu times a dimensionless residual measure of order one.
double Solid::hourglass_stiffness() const {
  return options_.hourglass * law_.shear_modulus_pa * options_.dimension / (norm_.number_density_n0 * mean_volume_m3_);
}

double Solid::p_wave_speed() const {
  return std::sqrt((law_.lame_lambda_pa + 2.0 * law_.shear_modulus_pa) / density_kg_m3_);
}

void Solid::add_prescribed(PrescribedSet set) {
  prescribed_.push_back(std::move(set));
  apply_prescribed(time_s_);
}

void Solid::set_floor(const RigidFloor& floor) {
  HalfSpace h;
  h.point_m = floor.point_m;
  h.normal = floor.normal;
  h.law.normal_stiffness_n_m = floor.stiffness_factor * face_stiffness_n_m();
  h.law.tangential_stiffness_n_m = floor.tangential_stiffness_factor * shear_face_stiffness_n_m();
  h.law.static_friction = floor.static_friction;
  h.law.kinetic_friction = floor.kinetic_friction;
  h.motion = floor.motion;
  contact_.add_half_space(h);
}

double Solid::face_area_m2() const {
  return options_.dimension == 2 ? options_.spacing_m * options_.thickness_m : options_.spacing_m * options_.spacing_m;
}

double Solid::face_stiffness_n_m() const {
  return (law_.lame_lambda_pa + 2.0 * law_.shear_modulus_pa) * face_area_m2() / options_.spacing_m;
}

double Solid::shear_face_stiffness_n_m() const {
  return face_stiffness_n_m() * law_.shear_modulus_pa / (law_.lame_lambda_pa + 2.0 * law_.shear_modulus_pa);
}

ParticleStateView Solid::state_view() const {
  ParticleStateView s;
  s.dimension = options_.dimension;
  s.count = static_cast<long long>(size());
  s.position_m = position_m_.data();
  s.u = {u_[0].data(), u_[1].data(), u_[2].data()};
  s.v = {v_[0].data(), v_[1].data(), v_[2].data()};
  s.bonds = bonds_.view();
  return s;
}

void Solid::apply_prescribed(double t) {
  apply_prescribed_sets(prescribed_, t, u_, v_);
}

void Solid::compute_acceleration(double dt) {
  const long long n = static_cast<long long>(size());
  BondsView b = bonds_.view();
  const bool updated = options_.updated_lagrangian;
  if (updated)
    for (int a = 0; a < 3; ++a)
      for (long long i = 0; i < n; ++i) u_stencil_[a][i] = u_[a][i] - u_at_rebuild_[a][i];
  const auto& us = updated ? u_stencil_ : u_;  // displacement since the stencils' reference
  const VectorField u{us[0].data(), us[1].data(), us[2].data()};
  const double* volume = stencil_volume_m3_.data();
  const int dim = options_.dimension;
  const double hourglass = hourglass_stiffness();

  // 1. gradient, stress update, force matrices (all per particle).
  SolidStressInputs stress_in;
  stress_in.bonds = b;
  stress_in.u = u;
  stress_in.volume_m3 = volume;
  stress_in.moment_inverse = moment_inverse_.data();
  stress_in.law = law_;
  stress_in.dimension = dim;
  stress_in.hourglass_stiffness = hourglass;
  stress_in.dt_s = dt;
  stress_in.bond_coefficient = bond_coefficient_.data();
  SolidStressState state{gradient_.data(), f_inverse_.data(),   stress_.data(), eq_plastic_strain_.data(),
                         stress_work_j_.data(), pressure_pa_.data(), matrices_.data()};
  if (!viscous_stress_.empty()) {
    state.viscous_stress = viscous_stress_.data();
    state.viscous_work_j = viscous_work_j_.data();
  }
  long long inverted = 0;
  double largest_gradient2 = 0.0;  // max |H|^2 (Frobenius) over the particles
#pragma omp parallel for schedule(static) reduction(+ : inverted) reduction(max : largest_gradient2) if (n > kSolidParallelMin)
  for (long long i = 0; i < n; ++i) {
    const double h2 = stress_phase_at(i, stress_in, state);
    if (h2 < 0.0) {  // det F <= 0: left unchanged
      if (fracture_ && fracture_->absorb_inversion(i, bonds_)) continue;  // debris at a crack face
      ++inverted;
      continue;
    }
    largest_gradient2 = std::max(largest_gradient2, h2);
  }
  if (inverted > 0) throw_inverted(inverted, time_s_);
  if (updated && largest_gradient2 > options_.stencil_update_strain * options_.stencil_update_strain) {
    rebuild_stencils_on_current_configuration();  // the forces below use the new stencils
    b = bonds_.view();
  }
  if (fracture_) apply_fracture();  // cut bonds take no part in the forces below
  const bool repulsive = options_.pressure == PressureForce::Repulsive;
  if (repulsive) {
#pragma omp parallel for schedule(static) if (n > kSolidParallelMin)
    for (long long i = 0; i < n; ++i) pressure_floor_pa_[i] = pressure_floor_at(i, b, full_stencil_.data(), pressure_pa_.data());
  }

  // 3-4. contact, forces and acceleration.
  SolidAccelerationInputs in;
  in.forces.bonds = b;
  in.forces.u = u;
  in.forces.matrices = matrices_.data();
  in.forces.pressure_floor_pa = repulsive ? pressure_floor_pa_.data() : nullptr;
  in.forces.volume_m3 = volume;
  in.forces.bond_coefficient = bond_coefficient_.data();
  in.forces.dimension = dim;
  const bool contact = contact_.active();
  if (contact) contact_.compute_forces(state_view(), dt);
  for (int a = 0; a < 3; ++a) {
    in.external_n[a] = external_force_n_[a].data();
    in.contact_n[a] = contact ? contact_.force(a).data() : nullptr;
    in.gravity_m_s2[a] = options_.gravity_m_s2[a];
  }
  in.v = {v_[0].data(), v_[1].data(), v_[2].data()};
  in.volume_m3 = volume_m3_.data();
  in.density_kg_m3 = density_kg_m3_;
  in.damping_per_s = time_s_ < options_.damping_until_s ? options_.damping_per_s : 0.0;
  in.dimension = dim;
#pragma omp parallel for schedule(static) if (n > kSolidParallelMin)
  for (long long i = 0; i < n; ++i) solid_acceleration_at(i, in, a_[0].data(), a_[1].data(), a_[2].data());
}

void Solid::step() {
  // Substeps: 1 unless bonds have been squeezed (update_substeps()); counted before the
  // first step too, since the initial velocities are set after construction.
  if (steps_ % kClumpingCheckEvery == 0) update_substeps();
  const int substeps = substeps_;
  const double dt = dt_s_ / substeps;
  for (int s = 0; s < substeps; ++s) {
    if (device_) {  // the same phases on the device (SolidStepDevice); clock, checks and cuts stay here
      device_->stress_phase();
      state_current_ = false;
      // Checked after every stress phase, as compute_acceleration throws before its forces.
      if (const long long inverted = device_->inverted_particles(); inverted > 0) absorb_inverted_on_device(inverted);
      if (fracture_) fracture_on_device();  // cut bonds take no part in the forces below
      time_s_ += dt;
      device_->motion_phase(dt, time_s_);
      kinematics_current_ = contact_current_ = false;
      continue;
    }
    // Symplectic Euler (the paper's scheme): v^{k+1} = v^k + dt a(u^k), u^{k+1} = u^k + dt v^{k+1}.
    compute_acceleration(dt);
    symplectic_euler_update(u_, v_, a_, options_.dimension, dt);
    contact_.advance_rigid_bodies(dt, options_.gravity_m_s2);  // same step, reactions of the forces above
    contact_.advance_obstacles(time_s_, dt);                   // ground motion, the same step
    time_s_ += dt;
    apply_prescribed(time_s_);
  }
  ++steps_;
  if (steps_ % kClumpingCheckEvery != 0) return;
  // stability_checks.hpp. On a device the count is taken there; the host measure, on the
  // downloaded state, only writes the message.
  if (device_) {
    const long long clumped = device_->clumped_bonds();
    if (clumped == 0) return;
    require_no_clumping(*this);
    throw RunError("mps solid: particles clumping at t = " + std::to_string(time_s_) + " s: the device counted " +
                   std::to_string(clumped) + " nearest-neighbour bond(s) below " +
                   std::to_string(kMinNeighbourDistanceRatio) + " of their predicted length (raise model.hourglass, "
                   "try model.pressure_force: repulsive, or refine)");
  }
  require_no_clumping(*this);
}

void Solid::throw_inverted(long long inverted, double time_s) const {
  throw RunError("mps solid: " + std::to_string(inverted) + " particle(s) inverted (det F <= 0) at t = " +
                 std::to_string(time_s) + " s: the deformation is too large or too non-affine for the reference "
                 "stencils (raise model.hourglass, refine, or lower time.safety)");
}

void Solid::attach_device(std::unique_ptr<SolidStepDevice> device) {
  // What the launcher does not run (solid_device_refusal names the case keys; this guards
  // callers that build a Solid themselves).
  std::string missing;
  if (options_.updated_lagrangian) missing = "updated Lagrangian stencils";
  else if (contact_.particle_contact() && contact_.particle_settings().frictional())
    missing = "friction between particles";
  else if (contact_.polygon_count() > 0) missing = "rigid polygons";
  else if (contact_.moving_obstacles()) missing = "a moving floor (ground motion)";
  else if (std::isfinite(options_.damping_until_s)) missing = "a settling phase (model.damping_until)";
  else if (law_.viscous_time_s > 0.0) missing = "material damping";
  if (!missing.empty()) throw RunError("mps solid: the CUDA launcher does not run " + missing + "; use --backend cpu");
  sync_host(false);
  device_ = std::move(device);
  kinematics_current_ = state_current_ = separation_current_ = contact_current_ = true;  // the device starts from the host's state
}

std::string Solid::backend_description() const {
  if (device_) return device_->description();
  return "cpu (OpenMP, " + std::to_string(omp_get_max_threads()) + " threads)";
}

void Solid::sync_host(bool kinematics_only) const {
  if (!device_) return;
  if (kinematics_only ? kinematics_current_ : (kinematics_current_ && state_current_)) return;
  SolidHostState host;
  host.u = &u_;
  host.v = &v_;
  host.gradient = &gradient_;
  host.f_inverse = &f_inverse_;
  host.stress = &stress_;
  host.eq_plastic_strain = &eq_plastic_strain_;
  host.stress_work_j = &stress_work_j_;
  host.matrices = &matrices_;
  device_->download(host, kinematics_only);
  kinematics_current_ = true;
  if (!kinematics_only) state_current_ = true;
}

std::vector<double> Solid::internal_force_of_uniform_stress(const SymTensor& stress) const {
  const long long n = static_cast<long long>(size());
  std::vector<ForceMatrices> matrices(n);
  const Mat3 zero{};
  for (long long i = 0; i < n; ++i)
    matrices[i] = force_matrices(stress, zero, identity3(), moment_inverse_[i], 0.0);
  const std::vector<double> none(n, 0.0);
  SolidForceInputs in;
  in.bonds = bonds_.view();
  in.u = {none.data(), none.data(), none.data()};
  in.matrices = matrices.data();
  in.volume_m3 = stencil_volume_m3_.data();
  std::vector<double> force(3 * n);
  for (long long i = 0; i < n; ++i) solid_force_at(i, in, &force[3 * i]);
  return force;
}

double Solid::kinetic_energy_j() const {
  sync_host(true);
  double e = 0.0;
  for (size_t i = 0; i < size(); ++i)
    e += 0.5 * density_kg_m3_ * volume_m3_[i] * (v_[0][i] * v_[0][i] + v_[1][i] * v_[1][i] + v_[2][i] * v_[2][i]);
  return e + contact_.rigid_kinetic_energy_j();
}

double Solid::stress_work_j() const {
  sync_host(false);
  double e = 0.0;
  for (double w : stress_work_j_) e += w;
  return e;
}

double Solid::material_damping_j() const {
  double e = 0.0;
  for (double w : viscous_work_j_) e += w;
  return e;
}

double Solid::hourglass_energy_j() const {
  sync_host(false);
  const BondsView b = bonds_.view();
  std::array<std::vector<double>, 3> us;  // displacement since the stencils' reference
  for (int a = 0; a < 3; ++a) {
    us[a] = u_[a];
    if (options_.updated_lagrangian)
      for (size_t i = 0; i < size(); ++i) us[a][i] -= u_at_rebuild_[a][i];
  }
  const VectorField u{us[0].data(), us[1].data(), us[2].data()};
  // Plus what earlier stencils held when they were rebuilt (updated Lagrangian; dissipated).
  double e = hourglass_released_j_;
  for (size_t i = 0; i < size(); ++i) {
    const Mat3 h = displacement_gradient_at(i, b, u, stencil_volume_m3_.data(), moment_inverse_[i], options_.dimension,
                                            bond_coefficient_.data());
    e += hourglass_energy_at(i, b, u, stencil_volume_m3_.data(), h, matrices_[i].hourglass_stiffness, options_.dimension,
                             bond_coefficient_.data());
  }
  return e;
}

void Solid::sync_contact() const {
  if (!device_ || contact_current_) return;
  double spring = 0.0, dissipated = 0.0;
  device_->friction_totals(&spring, &dissipated);
  contact_.set_device_totals(spring, dissipated, device_->contact_pairs());
  contact_current_ = true;
}

double Solid::contact_energy_j() const {
  sync_host(true);
  sync_contact();
  return contact_.active() ? contact_.potential_energy_j(state_view()) : 0.0;
}

double Solid::gravity_energy_j() const {
  sync_host(true);
  double e = 0.0;
  for (size_t i = 0; i < size(); ++i)
    for (int a = 0; a < 3; ++a) e -= density_kg_m3_ * volume_m3_[i] * options_.gravity_m_s2[a] * u_[a][i];
  return e + contact_.rigid_gravity_energy_j(options_.gravity_m_s2);
}

double Solid::plastic_fraction() const {
  sync_host(false);
  if (size() == 0) return 0.0;
  const auto k = std::count_if(eq_plastic_strain_.begin(), eq_plastic_strain_.end(), [](double e) { return e > 0.0; });
  return static_cast<double>(k) / size();
}

int Solid::nearest_particle(const std::array<double, 3>& p) const {
  return mps::nearest_particle(position_m_, p);
}

double Solid::sample(int i, const std::string& field) const {
  sync_host(true);
  const int axis = field.back() - 'x';
  return field.rfind("displacement", 0) == 0 ? u_[axis][i] : v_[axis][i];
}

}  // namespace breccia::mps
