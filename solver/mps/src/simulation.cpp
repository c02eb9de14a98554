#include "breccia/mps/particles.hpp"
#include "breccia/mps/simulation.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "breccia/common/error.hpp"
#include "breccia/common/particle_file.hpp"

namespace breccia::mps {

// Below this many particles a step is a few microseconds of work and thread start-up and
// barriers (worse on a loaded machine) cost more than they save.
constexpr long long kParallelMin = 8192;

Simulation::Simulation(const CaseSpec& spec) : spec_(spec) {
  build_particles();
  bonds_ = build_bonds(dimension_, position_m_, spec_.re_over_spacing * spacing_m_, periodic_);
  // n0 and lambda from the intact lattice, before crack bonds are removed.
  norm_ = reference_normalisation(bonds_);
  scales_ = norm_.scales(dimension_);
  const MaterialSpec& m = spec_.material;
  if (spec_.equation == Equation::Navier) {
    coeffs_ = {(m.lame_lambda_pa + m.shear_modulus_pa) / m.density_kg_m3, m.shear_modulus_pa / m.density_kg_m3};
  } else {  // paper eq. (6): C13 grad(div u) + 2 C55 lap u
    coeffs_ = {m.lame_lambda_pa / m.density_kg_m3, 2.0 * m.shear_modulus_pa / m.density_kg_m3};
  }
  build_cracks();
  build_boundary();
  const size_t n = size();
  for (int a = 0; a < 3; ++a) {
    u_[a].assign(n, 0.0);
    v_[a].assign(n, 0.0);
    a_[a].assign(n, 0.0);
  }
  div_.assign(n, 0.0);
  if (spec_.initial) {
    const auto& g = *spec_.initial;
    for (size_t i = 0; i < n; ++i) {
      double r2 = 0.0;
      for (int a = 0; a < dimension_; ++a) r2 += std::pow(position_m_[3 * i + a] - g.center_m[a], 2);
      const double f = std::exp(-r2 / (g.width_m * g.width_m));
      for (int a = 0; a < dimension_; ++a) u_[a][i] = g.amplitude_m[a] * f;
    }
  }
  // The uniform initial velocity (docs/mps.md: both formulations; the stress one sets it in
  // make_solid); prescribed particles then take their own values.
  for (int a = 0; a < dimension_; ++a) v_[a].assign(n, spec_.initial_velocity_m_s[a]);
  choose_time_step();
  apply_prescribed(0.0);
}

void Simulation::build_particles() {
  ParticleCloud cloud = build_particle_cloud(spec_);
  dimension_ = cloud.dimension;
  spacing_m_ = cloud.spacing_m;
  thickness_m_ = cloud.thickness_m;
  periodic_ = cloud.periodic;
  position_m_ = std::move(cloud.position_m);
  volume_m3_ = std::move(cloud.volume_m3);
  content_id_ = std::move(cloud.content_id);
  set_names_ = std::move(cloud.set_names);
  set_members_ = std::move(cloud.set_members);
  if (dimension_ != 2 && !spec_.cracks.empty())
    throw InputError(spec_.file, "cracks", "cracks in a 3D particle model", "cracks in 2D models only");
}

void Simulation::build_cracks() {
  const double depth = dimension_ == 2 ? thickness_m_ : spacing_m_;
  pairs_ = build_crack_pairs(spec_, position_m_, spacing_m_, depth, periodic_, bonds_);
}

void Simulation::build_boundary() {
  ParticleCloud cloud;
  cloud.dimension = dimension_;
  cloud.spacing_m = spacing_m_;
  cloud.position_m = position_m_;
  cloud.set_names = set_names_;
  cloud.set_members = set_members_;
  prescribed_ = select_boundary(spec_, cloud);
}

void Simulation::apply_prescribed(double t) {
  apply_prescribed_sets(prescribed_, t, u_, v_);
}

namespace {

void elastic_pass(const BondList& bonds, OperatorScales s, ElasticCoefficients c,
                  const std::array<std::vector<double>, 3>& u, std::vector<double>& div,
                  std::array<std::vector<double>, 3>& out) {
  const BondsView b = bonds.view();
  const VectorField uf{u[0].data(), u[1].data(), u[2].data()};
  const long long n = static_cast<long long>(bonds.particles());
  double* d = div.data();
#pragma omp parallel for schedule(static) if (n > kParallelMin)
  for (long long i = 0; i < n; ++i) d[i] = divergence_at(i, b, uf, s.gradient);
  double* ox = out[0].data();
  double* oy = out[1].data();
  double* oz = out[2].data();
#pragma omp parallel for schedule(static) if (n > kParallelMin)
  for (long long i = 0; i < n; ++i) {
    double acc[3];
    elastic_acceleration_at(i, b, uf, d, s, c, acc);
    ox[i] = acc[0];
    oy[i] = acc[1];
    oz[i] = acc[2];
  }
}

}  // namespace

void Simulation::compute_acceleration(bool update_crack_state) {
  elastic_pass(bonds_, scales_, coeffs_, u_, div_, a_);
  // Pairs in order, each adding to its two particles: the CUDA launcher adds them per
  // particle in the same pair order (crack.hpp, add_pair_acceleration).
  const double rho = spec_.material.density_kg_m3;
  const CrackPairsView c = pairs_.view();
  const VectorField u{u_[0].data(), u_[1].data(), u_[2].data()}, v{v_[0].data(), v_[1].data(), v_[2].data()};
  for (long long p = 0; p < c.count; ++p) {
    PairState scratch = c.state[p];
    PairState& st = update_crack_state ? c.state[p] : scratch;
    double force[2];
    crack_pair_force_at(p, c, u, v, st, force);
    const int i = c.plus[p], j = c.minus[p];
    add_pair_acceleration(a_[0][i], a_[1][i], force, rho * volume_m3_[i], true);
    add_pair_acceleration(a_[0][j], a_[1][j], force, rho * volume_m3_[j], false);
  }
}

void Simulation::linear_operator(const std::array<std::vector<double>, 3>& u, std::array<std::vector<double>, 3>& out,
                                 bool with_crack_springs) const {
  std::vector<double> div(size());
  elastic_pass(bonds_, scales_, coeffs_, u, div, out);
  if (!with_crack_springs) return;
  const double rho = spec_.material.density_kg_m3;
  for (size_t p = 0; p < pairs_.size(); ++p) {
    const int i = pairs_.plus[p], j = pairs_.minus[p];
    const FrictionLaw& law = pairs_.law[pairs_.crack[p]];
    const double nx = pairs_.normal_x[p], ny = pairs_.normal_y[p], sx = pairs_.tangent_x[p], sy = pairs_.tangent_y[p];
    const double gx = u[0][i] - u[0][j], gy = u[1][i] - u[1][j];
    const double fn = -law.normal_stiffness_n_m * (gx * nx + gy * ny);
    const double fs = -law.shear_stiffness_n_m * (gx * sx + gy * sy);
    const double fx = fn * nx + fs * sx, fy = fn * ny + fs * sy;
    out[0][i] += fx / (rho * volume_m3_[i]);
    out[1][i] += fy / (rho * volume_m3_[i]);
    out[0][j] -= fx / (rho * volume_m3_[j]);
    out[1][j] -= fy / (rho * volume_m3_[j]);
  }
}

void Simulation::choose_time_step() {
  const MaterialSpec& m = spec_.material;
  double c_max = m.p_wave_speed();
  if (spec_.equation == Equation::RotationFree) c_max = std::max(c_max, std::sqrt(2.0 * m.shear_modulus_pa / m.density_kg_m3));
  cfl_dt_s_ = spec_.safety * spacing_m_ / c_max;

  // Leapfrog-type schemes are stable for dt < 2 / omega_max. The continuum part of
  // omega_max^2 (largest eigenvalue of -M^-1 K) comes from a power iteration (its top modes
  // are grid-scale waves spread over the body, where the iteration converges well). Modes
  // localised at a few crack pairs are found slowly by it, and an underestimate gives a slow
  // instability, so the pair springs are bounded separately (Gershgorin: a pair adds at most
  // k (1/m_i + 1/m_j) to omega^2).
  const size_t n = size();
  std::array<std::vector<double>, 3> x, y;
  for (int a = 0; a < 3; ++a) {
    x[a].assign(n, 0.0);
    y[a].assign(n, 0.0);
  }
  unsigned long long seed = 88172645463325252ull;
  for (int a = 0; a < dimension_; ++a)
    for (size_t i = 0; i < n; ++i) {
      seed ^= seed << 13;
      seed ^= seed >> 7;
      seed ^= seed << 17;
      x[a][i] = static_cast<double>(seed % 2000001) / 1000000.0 - 1.0;
    }
  double omega2 = 0.0;
  for (int it = 0; it < 60; ++it) {
    linear_operator(x, y, false);
    double xy = 0.0, xx = 0.0, yy = 0.0;
    for (int a = 0; a < dimension_; ++a)
      for (size_t i = 0; i < n; ++i) {
        xy -= x[a][i] * y[a][i];
        xx += x[a][i] * x[a][i];
        yy += y[a][i] * y[a][i];
      }
    if (xx <= 0 || yy <= 0) break;
    omega2 = xy / xx;
    const double norm = std::sqrt(yy);
    for (int a = 0; a < dimension_; ++a)
      for (size_t i = 0; i < n; ++i) x[a][i] = -y[a][i] / norm;
  }
  const double rho = m.density_kg_m3;
  double pair_omega2 = 0.0;
  for (size_t p = 0; p < pairs_.size(); ++p) {
    const FrictionLaw& law = pairs_.law[pairs_.crack[p]];
    const double k = std::max(law.normal_stiffness_n_m, law.shear_stiffness_n_m);
    pair_omega2 = std::max(pair_omega2, k * (1.0 / (rho * volume_m3_[pairs_.plus[p]]) +
                                             1.0 / (rho * volume_m3_[pairs_.minus[p]])));
  }
  omega2 += pair_omega2;
  spectral_dt_limit_s_ = omega2 > 0 ? 2.0 / std::sqrt(omega2) : 1e300;
  // 0.9: the Rayleigh quotient approaches omega_max^2 from below.
  dt_s_ = spec_.dt_s ? *spec_.dt_s : std::min(cfl_dt_s_, 0.9 * spectral_dt_limit_s_);
}

void Simulation::attach_device(std::unique_ptr<StepDevice> device) {
  sync_host();
  device_ = std::move(device);
  host_current_ = pairs_current_ = true;
}

std::string Simulation::backend_description() const {
  if (device_) return device_->description();
  return "cpu (OpenMP, " + std::to_string(omp_get_max_threads()) + " threads)";
}

void Simulation::sync_host() const {
  if (!device_ || host_current_) return;
  device_->download(u_, v_, a_, pairs_.state);
  host_current_ = pairs_current_ = true;
}

void Simulation::sync_pair_states() const {
  if (!device_ || pairs_current_) return;
  device_->download_pair_states(pairs_.state);
  pairs_current_ = true;
}

void Simulation::step() {
  const double dt = dt_s_;
  const long long n = static_cast<long long>(size());
  if (device_) {  // the same phases on the device (StepDevice); the clock stays here
    time_s_ += dt;
    device_->step(time_s_);
    host_current_ = pairs_current_ = false;
    acceleration_valid_ = true;
    ++steps_;
    return;
  }
  if (spec_.integrator == Integrator::SymplecticEuler) {
    // eqs (7)-(8): v^{k+1} = v^k + dt a(u^k), u^{k+1} = u^k + dt v^{k+1}
    compute_acceleration(true);
    symplectic_euler_update(u_, v_, a_, dimension_, dt);
    time_s_ += dt;
    apply_prescribed(time_s_);
  } else {
    const double half_dt = 0.5 * dt;
    if (!acceleration_valid_) compute_acceleration(true);
    for (int a = 0; a < dimension_; ++a) {
      double* u = u_[a].data();
      double* v = v_[a].data();
      const double* acc = a_[a].data();
#pragma omp parallel for schedule(static) if (n > kParallelMin)
      for (long long i = 0; i < n; ++i) verlet_kick_drift_at(u[i], v[i], acc[i], half_dt, dt);
    }
    time_s_ += dt;
    apply_prescribed(time_s_);
    compute_acceleration(true);
    for (int a = 0; a < dimension_; ++a) {
      double* v = v_[a].data();
      const double* acc = a_[a].data();
#pragma omp parallel for schedule(static) if (n > kParallelMin)
      for (long long i = 0; i < n; ++i) verlet_kick_at(v[i], acc[i], half_dt);
    }
    apply_prescribed(time_s_);
    acceleration_valid_ = true;
  }
  ++steps_;
}

double Simulation::kinetic_energy_j() const {
  sync_host();
  const double rho = spec_.material.density_kg_m3;
  double e = 0.0;
  const long long n = static_cast<long long>(size());
#pragma omp parallel for reduction(+ : e) schedule(static) if (n > kParallelMin)
  for (long long i = 0; i < n; ++i)
    e += 0.5 * rho * volume_m3_[i] * (v_[0][i] * v_[0][i] + v_[1][i] * v_[1][i] + v_[2][i] * v_[2][i]);
  return e;
}

double Simulation::elastic_energy_j() const {
  sync_host();
  const long long n = static_cast<long long>(size());
  std::vector<double> div(n);
  const BondsView b = bonds_.view();
  const VectorField uf{u_[0].data(), u_[1].data(), u_[2].data()};
#pragma omp parallel for schedule(static) if (n > kParallelMin)
  for (long long i = 0; i < n; ++i) div[i] = divergence_at(i, b, uf, scales_.gradient);
  const double rho = spec_.material.density_kg_m3;
  double e = 0.0;
#pragma omp parallel for reduction(+ : e) schedule(static) if (n > kParallelMin)
  for (long long i = 0; i < n; ++i)
    e += rho * volume_m3_[i] * elastic_energy_per_rho_at(i, b, uf, div.data(), scales_, coeffs_);
  for (size_t p = 0; p < pairs_.size(); ++p) {
    const int i = pairs_.plus[p], j = pairs_.minus[p];
    const FrictionLaw& law = pairs_.law[pairs_.crack[p]];
    const PairState& st = pairs_.state[p];
    const double gx = u_[0][i] - u_[0][j], gy = u_[1][i] - u_[1][j];
    const double gn = gx * pairs_.normal_x[p] + gy * pairs_.normal_y[p];
    const double gs = gx * pairs_.tangent_x[p] + gy * pairs_.tangent_y[p];
    if (!st.open) e += 0.5 * law.normal_stiffness_n_m * gn * gn;
    if (!st.open && !st.slipping) e += 0.5 * law.shear_stiffness_n_m * std::pow(gs - st.stick_reference_m, 2);
  }
  return e;
}

int Simulation::nearest_particle(const std::array<double, 3>& p) const {
  return mps::nearest_particle(position_m_, p);
}

double Simulation::sample(int i, const std::string& field) const {
  const int axis = field.back() - 'x';
  if (device_ && !host_current_) return device_->sample(i, axis, field.rfind("velocity", 0) == 0);
  return field.rfind("displacement", 0) == 0 ? u_[axis][i] : v_[axis][i];
}

double Simulation::slipping_fraction() const {
  if (pairs_.size() == 0) return 0.0;
  if (device_ && !host_current_) return static_cast<double>(device_->slipping_pairs()) / pairs_.size();
  size_t k = 0;
  for (const auto& s : pairs_.state) k += s.slipping;
  return static_cast<double>(k) / pairs_.size();
}

double Simulation::open_fraction() const {
  if (pairs_.size() == 0) return 0.0;
  if (device_ && !host_current_) return static_cast<double>(device_->open_pairs()) / pairs_.size();
  size_t k = 0;
  for (const auto& s : pairs_.state) k += s.open;
  return static_cast<double>(k) / pairs_.size();
}

}  // namespace breccia::mps
