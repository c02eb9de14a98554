#include "breccia/mps/simulation.hpp"

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

double burst_displacement(const BurstHistory& h, double t) {
  const double tau = t - h.delay_s, length = h.cycles * h.period_s;
  if (tau < 0.0 || tau > length) return 0.0;
  const double carrier = h.amplitude_m * std::sin(2.0 * std::numbers::pi * tau / h.period_s);
  if (!h.hann) return carrier;
  return carrier * 0.5 * (1.0 - std::cos(2.0 * std::numbers::pi * tau / length));
}

double burst_velocity(const BurstHistory& h, double t) {
  const double tau = t - h.delay_s, length = h.cycles * h.period_s;
  if (tau < 0.0 || tau > length) return 0.0;
  const double w = 2.0 * std::numbers::pi / h.period_s, wl = 2.0 * std::numbers::pi / length;
  const double s = std::sin(w * tau), ds = w * std::cos(w * tau);
  if (!h.hann) return h.amplitude_m * ds;
  const double env = 0.5 * (1.0 - std::cos(wl * tau)), denv = 0.5 * wl * std::sin(wl * tau);
  return h.amplitude_m * (ds * env + s * denv);
}

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
  choose_time_step();
  apply_prescribed(0.0);
}

void Simulation::build_particles() {
  if (spec_.lattice) {
    const LatticeSpec& l = *spec_.lattice;
    dimension_ = l.dimension;
    spacing_m_ = l.spacing_m;
    thickness_m_ = l.thickness_m;
    std::array<long long, 3> count{1, 1, 1};
    for (int a = 0; a < dimension_; ++a) {
      count[a] = std::llround((l.high_m[a] - l.low_m[a]) / l.spacing_m);
      if (count[a] < 1) throw InputError(spec_.file, "specimen.lattice.spacing", "larger than the box", "spacing < box size");
      if (l.periodic[a]) periodic_.period_m[a] = count[a] * l.spacing_m;
    }
    const double volume = dimension_ == 2 ? l.spacing_m * l.spacing_m * l.thickness_m : std::pow(l.spacing_m, 3);
    const double re = spec_.re_over_spacing * spacing_m_;
    for (int a = 0; a < 3; ++a)
      if (periodic_.period_m[a] > 0 && periodic_.period_m[a] < 2.0 * re)
        throw InputError(spec_.file, "specimen.lattice.periodic", "periodic box shorter than 2 re",
                         "a periodic length of at least " + std::to_string(2.0 * re) + " m");
    for (long long k = 0; k < count[2]; ++k)
      for (long long j = 0; j < count[1]; ++j)
        for (long long i = 0; i < count[0]; ++i) {
          position_m_.push_back(l.low_m[0] + (i + 0.5) * l.spacing_m);
          position_m_.push_back(l.low_m[1] + (j + 0.5) * l.spacing_m);
          position_m_.push_back(dimension_ == 3 ? l.low_m[2] + (k + 0.5) * l.spacing_m : 0.0);
          volume_m3_.push_back(volume);
        }
    return;
  }
  const ParticleModel model = read_particle_file(spec_.particle_file);
  dimension_ = model.dimension;
  thickness_m_ = model.thickness_m;
  position_m_ = model.position_m;
  volume_m3_ = model.volume_m3;
  content_id_ = model.content_id;
  std::vector<double> sp = model.spacing_m;
  std::nth_element(sp.begin(), sp.begin() + sp.size() / 2, sp.end());
  spacing_m_ = sp[sp.size() / 2];
  for (const auto& s : model.sets) {
    set_names_.push_back(s.name);
    set_members_.push_back(s.indices);
  }
  if (dimension_ != 2 && !spec_.cracks.empty())
    throw InputError(spec_.file, "cracks", "cracks in a 3D particle model", "cracks in 2D models only");
}

void Simulation::build_cracks() {
  const double depth = dimension_ == 2 ? thickness_m_ : spacing_m_;
  pairs_ = build_crack_pairs(spec_, position_m_, spacing_m_, depth, periodic_, bonds_);
}

void Simulation::build_boundary() {
  const size_t n = size();
  std::array<double, 3> lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  for (size_t i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], position_m_[3 * i + a]);
      hi[a] = std::max(hi[a], position_m_[3 * i + a]);
    }
  for (size_t b = 0; b < spec_.boundary.size(); ++b) {
    const BoundarySpec& bs = spec_.boundary[b];
    PrescribedSet set;
    set.components = bs.components;
    set.burst = bs.burst;
    if (!bs.set.empty()) {
      const auto it = std::find(set_names_.begin(), set_names_.end(), bs.set);
      if (it == set_names_.end())
        throw InputError(spec_.file, "boundary[" + std::to_string(b) + "].set", "unknown set '" + bs.set + "'",
                         "a particle set of the particle file");
      for (auto i : set_members_[it - set_names_.begin()]) set.particles.push_back(static_cast<int>(i));
    } else {
      for (size_t i = 0; i < n; ++i) {
        const double* p = &position_m_[3 * i];
        bool in = false;
        if (bs.box_m) {
          const auto& bx = *bs.box_m;
          in = true;
          for (int a = 0; a < dimension_; ++a) in = in && p[a] >= bx[a] && p[a] <= bx[3 + a];
        } else {
          const double tol = 0.5 * spacing_m_;
          if (bs.face == "left") in = p[0] < lo[0] + tol;
          if (bs.face == "right") in = p[0] > hi[0] - tol;
          if (bs.face == "bottom") in = p[1] < lo[1] + tol;
          if (bs.face == "top") in = p[1] > hi[1] - tol;
          if (bs.face == "back") in = dimension_ == 3 && p[2] < lo[2] + tol;
          if (bs.face == "front") in = dimension_ == 3 && p[2] > hi[2] - tol;
        }
        if (in) set.particles.push_back(static_cast<int>(i));
      }
    }
    if (set.particles.empty())
      throw InputError(spec_.file, "boundary[" + std::to_string(b) + "]", "selects no particles",
                       "a face, box or set containing particles");
    prescribed_.push_back(std::move(set));
  }
}

void Simulation::apply_prescribed(double t) {
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
  const double rho = spec_.material.density_kg_m3;
  for (size_t p = 0; p < pairs_.size(); ++p) {
    const int i = pairs_.plus[p], j = pairs_.minus[p];
    const double nx = pairs_.normal_x[p], ny = pairs_.normal_y[p], sx = pairs_.tangent_x[p], sy = pairs_.tangent_y[p];
    const double gx = u_[0][i] - u_[0][j], gy = u_[1][i] - u_[1][j];
    const double vs = (v_[0][i] - v_[0][j]) * sx + (v_[1][i] - v_[1][j]) * sy;
    PairState scratch = pairs_.state[p];
    PairState& st = update_crack_state ? pairs_.state[p] : scratch;
    const PairForce f = friction_pair_force(pairs_.law[pairs_.crack[p]], gx * nx + gy * ny, gx * sx + gy * sy, vs, st);
    const double fx = f.normal_n * nx + f.tangent_n * sx, fy = f.normal_n * ny + f.tangent_n * sy;
    const double mi = rho * volume_m3_[i], mj = rho * volume_m3_[j];
    a_[0][i] += fx / mi;
    a_[1][i] += fy / mi;
    a_[0][j] -= fx / mj;
    a_[1][j] -= fy / mj;
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

void Simulation::step() {
  const double dt = dt_s_;
  const long long n = static_cast<long long>(size());
  if (spec_.integrator == Integrator::SymplecticEuler) {
    // eqs (7)-(8): v^{k+1} = v^k + dt a(u^k), u^{k+1} = u^k + dt v^{k+1}
    compute_acceleration(true);
    for (int a = 0; a < dimension_; ++a) {
      double* u = u_[a].data();
      double* v = v_[a].data();
      const double* acc = a_[a].data();
#pragma omp parallel for schedule(static) if (n > kParallelMin)
      for (long long i = 0; i < n; ++i) {
        v[i] += dt * acc[i];
        u[i] += dt * v[i];
      }
    }
    time_s_ += dt;
    apply_prescribed(time_s_);
  } else {
    if (!acceleration_valid_) compute_acceleration(true);
    for (int a = 0; a < dimension_; ++a) {
      double* u = u_[a].data();
      double* v = v_[a].data();
      const double* acc = a_[a].data();
#pragma omp parallel for schedule(static) if (n > kParallelMin)
      for (long long i = 0; i < n; ++i) {
        v[i] += 0.5 * dt * acc[i];
        u[i] += dt * v[i];
      }
    }
    time_s_ += dt;
    apply_prescribed(time_s_);
    compute_acceleration(true);
    for (int a = 0; a < dimension_; ++a) {
      double* v = v_[a].data();
      const double* acc = a_[a].data();
#pragma omp parallel for schedule(static) if (n > kParallelMin)
      for (long long i = 0; i < n; ++i) v[i] += 0.5 * dt * acc[i];
    }
    apply_prescribed(time_s_);
    acceleration_valid_ = true;
  }
  ++steps_;
}

double Simulation::kinetic_energy_j() const {
  const double rho = spec_.material.density_kg_m3;
  double e = 0.0;
  const long long n = static_cast<long long>(size());
#pragma omp parallel for reduction(+ : e) schedule(static) if (n > kParallelMin)
  for (long long i = 0; i < n; ++i)
    e += 0.5 * rho * volume_m3_[i] * (v_[0][i] * v_[0][i] + v_[1][i] * v_[1][i] + v_[2][i] * v_[2][i]);
  return e;
}

double Simulation::elastic_energy_j() const {
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
  int best = -1;
  double best_d2 = 1e300;
  for (size_t i = 0; i < size(); ++i) {
    double d2 = 0.0;
    for (int a = 0; a < 3; ++a) d2 += std::pow(position_m_[3 * i + a] - p[a], 2);
    if (d2 < best_d2) {
      best_d2 = d2;
      best = static_cast<int>(i);
    }
  }
  return best;
}

double Simulation::sample(int i, const std::string& field) const {
  const int axis = field.back() - 'x';
  return field.rfind("displacement", 0) == 0 ? u_[axis][i] : v_[axis][i];
}

double Simulation::slipping_fraction() const {
  if (pairs_.size() == 0) return 0.0;
  size_t k = 0;
  for (const auto& s : pairs_.state) k += s.slipping;
  return static_cast<double>(k) / pairs_.size();
}

double Simulation::open_fraction() const {
  if (pairs_.size() == 0) return 0.0;
  size_t k = 0;
  for (const auto& s : pairs_.state) k += s.open;
  return static_cast<double>(k) / pairs_.size();
}

}  // namespace breccia::mps
