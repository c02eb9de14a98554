#include "breccia/mps/particles.hpp"
#include "breccia/mps/solid.hpp"
#include "breccia/mps/stability_checks.hpp"

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
  cfl_dt_s_ = options_.safety * options_.spacing_m / p_wave_speed();
  dt_s_ = options_.dt_s ? *options_.dt_s : cfl_dt_s_;
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
    Mat3 f = gradient_[i];
    f(0, 0) += 1.0;
    f(1, 1) += 1.0;
    f(2, 2) += 1.0;
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
    matrices_[i] = force_matrices(stress_[i], zero, f_inverse_[i], moment_inverse_[i], matrices_[i].hourglass_stiffness);
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
void Solid::update_substeps() {
  if (!options_.substeps) return;
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
      if (b.weight[k] == 0.0) continue;
      const long long j = b.neighbour[k];
      const double r[3] = {b.rx[k], b.ry[k], b.rz[k]};
      double d[3], w[3], dw = 0.0, ww = 0.0;
      for (int a = 0; a < 3; ++a) {
        d[a] = r[a] + since_reference(a, j) - since_reference(a, i);
        w[a] = v_[a][j] - v_[a][i];
        dw += d[a] * w[a];
        ww += w[a] * w[a];
      }
      const double t = dw < 0.0 && ww > 0.0 ? std::min(window, -dw / ww) : 0.0;  // closest approach
      double closest2 = 0.0;
      for (int a = 0; a < 3; ++a) closest2 += (d[a] + t * w[a]) * (d[a] + t * w[a]);
      const double closest = std::sqrt(closest2);
      const double length = updated ? closest : spacing * closest / std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
      shortest = std::min(shortest, length);
    }
  }
  // A bond at 1/kMaxSubsteps of its length is a collapse that the inversion and clumping
  // checks stop; the cap only keeps a projected closest approach of ~0 from stalling the run.
  constexpr int kMaxSubsteps = 64;
  // A substep may exceed safety x shortest / c_L by a quarter, so the step is split only once
  // a bond has shortened by more than a fifth (safety 0.3 leaves that margin): split at any
  // shortening, an elastic body in contact (strains ~1e-4) would run at twice the cost.
  constexpr double kSubstepExcess = 1.25;
  const double stable_dt = kSubstepExcess * options_.safety * shortest / p_wave_speed();
  double wanted = std::ceil(dt_s_ / stable_dt - 1e-9);
  if (!(wanted >= 1.0)) wanted = 1.0;  // NaN from non-finite fields: the inversion check reports those
  substeps_ = static_cast<int>(std::min(wanted, static_cast<double>(kMaxSubsteps)));
}

std::vector<double> Solid::volume_ratio() const {
  std::vector<double> j(size());
  for (size_t i = 0; i < size(); ++i) {
    Mat3 f = gradient_[i];
    f(0, 0) += 1.0;
    f(1, 1) += 1.0;
    f(2, 2) += 1.0;
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
  contact_.add_half_space(h);
}

double Solid::face_stiffness_n_m() const {
  const double face_area = options_.dimension == 2 ? options_.spacing_m * options_.thickness_m
                                                   : options_.spacing_m * options_.spacing_m;
  return (law_.lame_lambda_pa + 2.0 * law_.shear_modulus_pa) * face_area / options_.spacing_m;
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
  for (const auto& set : prescribed_) {
    const double u = set.burst ? burst_displacement(*set.burst, t) : 0.0;
    const double v = set.burst ? burst_velocity(*set.burst, t) : 0.0;
    for (int a = 0; a < 3; ++a) {
      if (!set.components[a]) continue;
      for (int i : set.particles) {
        u_[a][i] = u;
        v_[a][i] = v;
      }
    }
  }
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

  // 1-2. gradient, stress update, force matrices (all per particle).
  long long inverted = 0;
  double largest_gradient2 = 0.0;  // max |H|^2 (Frobenius) over the particles
#pragma omp parallel for schedule(static) reduction(+ : inverted) reduction(max : largest_gradient2) if (n > kSolidParallelMin)
  for (long long i = 0; i < n; ++i) {
    const Mat3 h_new = displacement_gradient_at(i, b, u, volume, moment_inverse_[i]);
    Mat3 f = h_new;
    f(0, 0) += 1.0;
    f(1, 1) += 1.0;
    f(2, 2) += 1.0;
    if (!(det(f) > 0.0)) {  // also catches NaN
      if (fracture_ && fracture_->absorb_inversion(i, bonds_)) continue;  // debris at a crack face
      ++inverted;
      continue;
    }
    double deviatoric_scale = 1.0;
    stress_work_j_[i] += volume[i] * update_stress(law_, gradient_[i], f_inverse_[i], h_new, dim, stress_[i],
                                                   eq_plastic_strain_[i], &deviatoric_scale);
    double h2 = 0.0;
    for (double v : h_new.a) h2 += v * v;
    largest_gradient2 = std::max(largest_gradient2, h2);
    gradient_[i] = h_new;
    f_inverse_[i] = inverse(f);
    pressure_pa_[i] = pressure_of(stress_[i]);
    matrices_[i] = force_matrices(stress_[i], h_new, f_inverse_[i], moment_inverse_[i], hourglass * deviatoric_scale);
  }
  if (inverted > 0)
    throw RunError("mps solid: " + std::to_string(inverted) + " particle(s) inverted (det F <= 0) at t = " +
                   std::to_string(time_s_) + " s: the deformation is too large or too non-affine for the reference "
                   "stencils (raise model.hourglass, refine, or lower time.safety)");
  if (updated && largest_gradient2 > options_.stencil_update_strain * options_.stencil_update_strain) {
    rebuild_stencils_on_current_configuration();  // the forces below use the new stencils
    b = bonds_.view();
  }
  if (fracture_) apply_fracture();  // cut bonds take no part in the forces below
  const bool repulsive = options_.pressure == PressureForce::Repulsive;
  if (repulsive) {
#pragma omp parallel for schedule(static) if (n > kSolidParallelMin)
    for (long long i = 0; i < n; ++i) {
      // Near a free surface the shift would act as a surface pressure (and feed back on
      // itself); those particles keep the conservative form, as MPS fluids hold surface
      // particles (number density below 0.97 n0) at zero pressure.
      if (!full_stencil_[i]) {
        pressure_floor_pa_[i] = 0.0;
        continue;
      }
      double lowest = pressure_pa_[i];
      for (long long k = b.offset[i]; k < b.offset[i + 1]; ++k) lowest = std::min(lowest, pressure_pa_[b.neighbour[k]]);
      pressure_floor_pa_[i] = lowest;
    }
  }

  // 3. forces and acceleration.
  SolidForceInputs in;
  in.bonds = b;
  in.u = u;
  in.matrices = matrices_.data();
  in.pressure_floor_pa = repulsive ? pressure_floor_pa_.data() : nullptr;
  in.volume_m3 = volume;
  const double damping = options_.damping_per_s;
  const auto& g = options_.gravity_m_s2;
  const bool contact = contact_.active();
  if (contact) contact_.compute_forces(state_view(), dt);
#pragma omp parallel for schedule(static) if (n > kSolidParallelMin)
  for (long long i = 0; i < n; ++i) {
    double f[3];
    solid_force_at(i, in, f);
    for (int a = 0; a < 3; ++a) f[a] += external_force_n_[a][i];
    if (contact)
      for (int a = 0; a < 3; ++a) f[a] += contact_.force(a)[i];
    const double mass = density_kg_m3_ * volume_m3_[i];
    for (int a = 0; a < dim; ++a) a_[a][i] = f[a] / mass + g[a] - damping * v_[a][i];
  }
}

void Solid::step() {
  // Substeps: 1 unless bonds have been squeezed (update_substeps()); counted before the
  // first step too, since the initial velocities are set after construction.
  if (steps_ % kClumpingCheckEvery == 0) update_substeps();
  const int substeps = substeps_;
  const double dt = dt_s_ / substeps;
  for (int s = 0; s < substeps; ++s) {
    // Symplectic Euler (the paper's scheme): v^{k+1} = v^k + dt a(u^k), u^{k+1} = u^k + dt v^{k+1}.
    compute_acceleration(dt);
    symplectic_euler_update(u_, v_, a_, options_.dimension, dt);
    contact_.advance_rigid_bodies(dt, options_.gravity_m_s2);  // same step, reactions of the forces above
    time_s_ += dt;
    apply_prescribed(time_s_);
  }
  ++steps_;
  if (steps_ % kClumpingCheckEvery == 0) require_no_clumping(*this);  // stability_checks.hpp
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
  double e = 0.0;
  for (size_t i = 0; i < size(); ++i)
    e += 0.5 * density_kg_m3_ * volume_m3_[i] * (v_[0][i] * v_[0][i] + v_[1][i] * v_[1][i] + v_[2][i] * v_[2][i]);
  return e + contact_.rigid_kinetic_energy_j();
}

double Solid::stress_work_j() const {
  double e = 0.0;
  for (double w : stress_work_j_) e += w;
  return e;
}

double Solid::hourglass_energy_j() const {
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
    const Mat3 h = displacement_gradient_at(i, b, u, stencil_volume_m3_.data(), moment_inverse_[i]);
    e += hourglass_energy_at(i, b, u, stencil_volume_m3_.data(), h, matrices_[i].hourglass_stiffness);
  }
  return e;
}

double Solid::contact_energy_j() const { return contact_.active() ? contact_.potential_energy_j(state_view()) : 0.0; }

double Solid::gravity_energy_j() const {
  double e = 0.0;
  for (size_t i = 0; i < size(); ++i)
    for (int a = 0; a < 3; ++a) e -= density_kg_m3_ * volume_m3_[i] * options_.gravity_m_s2[a] * u_[a][i];
  return e + contact_.rigid_gravity_energy_j(options_.gravity_m_s2);
}

double Solid::plastic_fraction() const {
  if (size() == 0) return 0.0;
  const auto k = std::count_if(eq_plastic_strain_.begin(), eq_plastic_strain_.end(), [](double e) { return e > 0.0; });
  return static_cast<double>(k) / size();
}

int Solid::nearest_particle(const std::array<double, 3>& p) const {
  return mps::nearest_particle(position_m_, p);
}

double Solid::sample(int i, const std::string& field) const {
  const int axis = field.back() - 'x';
  return field.rfind("displacement", 0) == 0 ? u_[axis][i] : v_[axis][i];
}

}  // namespace breccia::mps
