// The OpenMP backend: launches the kernels of pd_kernels.hpp over all particles, plus the
// host-side pieces of a step (loads, constraints, energies).
#include <cmath>
#include <random>

#include "breccia/solver/correspondence.hpp"
#include "breccia/solver/forall.hpp"
#include "breccia/solver/load_kernels.hpp"
#include "breccia/solver/pd_system.hpp"

namespace breccia::solver {

void cpu_compute_forces(PdSystem& sys) {
  if (sys.f32.active) {  // model.precision: float32 — callers hold their state in double
    float32_upload(sys);
    float32_compute_forces(sys);
    float32_download(sys);
    return;
  }
  if (sys.config.model == PdModel::Correspondence) return cpu_correspondence_forces(sys);  // correspondence.cpp
  // Current positions once per force pass: the bond loop then gathers one array.
  if (sys.x.size() != sys.x0.size()) sys.x.resize(sys.x0.size());
  const int64_t n3 = static_cast<int64_t>(sys.x0.size());
#pragma omp parallel for schedule(static)
  for (int64_t k = 0; k < n3; ++k) sys.x[k] = sys.x0[k] + sys.u[k];
  const PdView p = sys.view();
  if (sys.config.model == PdModel::LPS) for_each_particle(p.n, [&](int64_t i) { lps_dilatation_kernel(p, i); });
  for_each_particle(p.n, [&](int64_t i) { force_kernel(p, i); });
  if (p.short_range_k) short_range_forces(sys, p, sys.x.data());
  double released = 0.0;
#pragma omp parallel for reduction(+ : released)
  for (int64_t i = 0; i < p.n; ++i) released += p.dissipated[i];
  sys.dissipated_energy += released;
}

namespace {
template <class Real>
void short_range_passes(PdSystem& sys, const PdViewT<Real>& p, const double* x_now) {
  for_each_particle(p.n, [&](int64_t i) { short_range_kernel(p, i); });
  sys.contact_cells.build(x_now, p.n, sys.contact_cell_edge);
  const ContactCellsView g = sys.contact_cells.view();
  for_each_particle(p.n, [&](int64_t i) { short_range_contact_kernel(p, g, i); });
}
}  // namespace

void short_range_forces(PdSystem& sys, const PdViewT<double>& p, const double* x_now) {
  short_range_passes(sys, p, x_now);
}
void short_range_forces(PdSystem& sys, const PdViewT<float>& p, const double* x_now) {
  short_range_passes(sys, p, x_now);
}

void commit_min_stretch(PdSystem& sys) {
  if (!sys.min_stretch.empty()) sys.min_stretch.swap(sys.min_stretch_next);
}

void compute_external(PdSystem& sys, double t) {
  std::fill(sys.body.begin(), sys.body.end(), 0.0);
  for (const auto& sl : sys.surface_loads) {
    const LoadSpec& ls = *sl.spec;
    const double h = ls.history.at(t);
    for (const auto& f : sl.facets) {
      if (!particle_attached(sys.offsets.data(), sys.state.data(), f.particle)) continue;
      double force[3];
      facet_force(ls.kind == LoadSpec::Kind::Pressure, h, f.area, f.normal, ls.vector.data(), force);
      for (int d = 0; d < 3; ++d) sys.body[3 * f.particle + d] += force[d] / sys.volume[f.particle];
    }
  }
  for (const auto& bl : sys.body_loads) {
    const double h = bl.spec->history.at(t);
    auto add = [&](int64_t i) {
      for (int d = 0; d < 3; ++d) sys.body[3 * i + d] += sys.density[i] * h * bl.spec->vector[d];
    };
    if (bl.particles.empty())
      for (size_t i = 0; i < sys.n; ++i) add(static_cast<int64_t>(i));
    else
      for (auto i : bl.particles) add(i);
  }
  const IndenterSpec& ind = sys.config.indenter;
  if (ind.enabled) {
    double c[3];
    for (int d = 0; d < 3; ++d) c[d] = ind.center[d] + ind.velocity[d] * t;
    for (int d = 0; d < 3; ++d) sys.indenter_position[d] = c[d];
    const double* x0 = sys.x0.data();
    const double* u = sys.u.data();
    double* body = sys.body.data();
#pragma omp parallel for
    for (int64_t i = 0; i < static_cast<int64_t>(sys.n); ++i)
      add_indenter_force(x0, u, i, c, ind.radius, ind.stiffness, body);
  }
}

void apply_constraints(PdSystem& sys, double t, double dt) {
  for (const auto& con : sys.constraints) {
    const BoundarySpec& b = *con.spec;
    double velocity[3], target[3];
    prescribed_values(b, t, dt, velocity, target);
    const int kind = static_cast<int>(b.kind);
    for (auto i : con.particles)
      for (int d = 0; d < 3; ++d) {
        if (!b.components[d]) continue;
        const int64_t k = 3 * static_cast<int64_t>(i) + d;
        constrain_component(kind, velocity[d], target[d], dt, sys.u[k], sys.v[k]);
      }
  }
}

void cpu_step(PdSystem& sys) {
  if (sys.f32.active) {  // float32: the time loop keeps the float state (make_float32_backend)
    float32_upload(sys);
    float32_step(sys);
    float32_download(sys);
    return;
  }
  commit_min_stretch(sys);
  const double dt = sys.dt, half = 0.5 * dt;
  PdView p = sys.view();
  // Work of external forces and reactions: trapezoid over the step.
  std::vector<double> u_before(sys.u);
  std::vector<double> f_before(3 * sys.n);
  for (size_t k = 0; k < 3 * sys.n; ++k) {
    const size_t i = k / 3;
    const bool constrained = sys.fixed_dof[i] & (1u << (k % 3));
    f_before[k] = sys.volume[i] * (constrained ? -sys.force[k] : sys.body[k]);
  }
  for_each_particle(p.n, [&](int64_t i) { kick_drift_kernel(p, i, half, dt); });
  sys.time += dt;
  apply_constraints(sys, sys.time, dt);
  compute_external(sys, sys.time);
  cpu_compute_forces(sys);
  for_each_particle(p.n, [&](int64_t i) { acceleration_kernel(p, i, half); });
  double work = 0.0;
#pragma omp parallel for reduction(+ : work)
  for (int64_t k = 0; k < static_cast<int64_t>(3 * sys.n); ++k) {
    const size_t i = static_cast<size_t>(k) / 3;
    const bool constrained = sys.fixed_dof[i] & (1u << (k % 3));
    const double f_after = sys.volume[i] * (constrained ? -sys.force[k] : sys.body[k]);
    work += 0.5 * (f_before[k] + f_after) * (sys.u[k] - u_before[k]);
  }
  sys.external_work += work;
  ++sys.step;
}

Energies measure(const PdSystem& sys) {
  Energies e;
  double ke = 0.0, se = 0.0, dmax = 0.0;
  long long broken = 0;
  int64_t bad = -1;
  const int64_t n = static_cast<int64_t>(sys.n);
  const PdView p = const_cast<PdSystem&>(sys).view();
#pragma omp parallel for reduction(+ : ke, se, broken) reduction(max : dmax, bad)
  for (int64_t i = 0; i < n; ++i) {
    double v2 = 0.0;
    bool finite = true;
    for (int d = 0; d < 3; ++d) {
      v2 += sys.v[3 * i + d] * sys.v[3 * i + d];
      finite = finite && std::isfinite(sys.u[3 * i + d]) && std::isfinite(sys.v[3 * i + d]);
    }
    if (!finite) bad = std::max<int64_t>(bad, i);
    ke += 0.5 * sys.density[i] * sys.volume[i] * v2;
    se += sys.volume[i] * sys.energy_density[i];
    dmax = std::max(dmax, sys.damage[i]);
    for (int64_t k = sys.offsets[i]; k < sys.offsets[i + 1]; ++k) broken += entry_broken(p, k);
  }
  e.kinetic = ke;
  e.strain = se;
  e.max_damage = dmax;
  e.broken_half_bonds = broken;
  e.finite = bad < 0 && std::isfinite(ke) && std::isfinite(se);
  e.bad_particle = bad;
  return e;
}

double estimate_max_frequency(PdSystem& sys, int iterations) {
  // Power iteration on M^-1 K with K applied through the force kernel at a displacement
  // small enough to be linear; fracture off, state restored afterwards.
  const size_t n3 = 3 * sys.n;
  const std::vector<double> u_saved(sys.u);
  const std::vector<uint8_t> state_saved(sys.state);
  const bool fracture = sys.config.fracture;
  const double dissipated = sys.dissipated_energy;
  // Strains of 1e-9 are below float's resolution: the estimate is always made in double.
  const bool float32 = sys.f32.active;
  sys.f32.active = false;
  sys.config.fracture = false;
  double length_scale = 0.0;
  for (size_t i = 0; i < sys.n; ++i) length_scale = std::max(length_scale, 2.0 * sys.half_cell[i]);
  const double amplitude = 1e-9 * length_scale;
  std::mt19937_64 rng(12345);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  std::vector<double> x(n3);
  for (size_t k = 0; k < n3; ++k) x[k] = (sys.dimension == 2 && k % 3 == 2) ? 0.0 : uni(rng);
  double lambda = 0.0;
  for (int it = 0; it < iterations; ++it) {
    double norm = 0.0;
    for (double xk : x) norm += xk * xk;
    norm = std::sqrt(norm);
    if (norm == 0) break;
    for (size_t k = 0; k < n3; ++k) sys.u[k] = amplitude * x[k] / norm;
    cpu_compute_forces(sys);
    double rayleigh = 0.0;
    for (size_t k = 0; k < n3; ++k) {
      const double y = -sys.force[k] / sys.density[k / 3] / amplitude;  // (M^-1 K) x_hat
      rayleigh += (x[k] / norm) * y;
      x[k] = (sys.dimension == 2 && k % 3 == 2) ? 0.0 : y;
    }
    lambda = rayleigh;
  }
  sys.u = u_saved;
  sys.state = state_saved;
  sys.config.fracture = fracture;
  sys.dissipated_energy = dissipated;
  sys.f32.active = float32;
  cpu_compute_forces(sys);  // restore force/energy fields at the real displacement
  // Power iteration approaches omega_max^2 from below; 2% margin keeps 'stable' honest.
  return std::sqrt(std::max(lambda, 1e-300)) * 1.02;
}

}  // namespace breccia::solver
