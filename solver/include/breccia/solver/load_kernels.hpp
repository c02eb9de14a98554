#pragma once
// Loads and constraints of one particle per call, written once for both backends
// (cpu_backend.cpp and solver/cuda/ call the same functions, so they round identically).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "breccia/solver/case_config.hpp"
#include "breccia/solver/hd.hpp"

namespace breccia::solver {

// Force of one loaded facet [N]. Pressure pushes against the outward normal; a traction is a
// force per area. `history` is the load's time history at this step (the pressure itself for
// a pressure load, a multiplier of `traction` otherwise).
BRECCIA_HD void facet_force(bool pressure, double history, double area, const double normal[3],
                            const double traction[3], double force[3]) {
  for (int d = 0; d < 3; ++d) force[d] = pressure ? -history * area * normal[d] : history * traction[d] * area;
}

// A surface load acts on a particle only while it is attached to the body (one intact
// bond at least): crushed debris leaves the loaded surface, and a constant blast pressure
// on a free particle would accelerate it without bound.
BRECCIA_HD bool particle_attached(const int64_t* offsets, const uint8_t* state, int64_t i) {
  for (int64_t k = offsets[i]; k < offsets[i + 1]; ++k)
    if (state[k]) return true;
  return false;
}

// Rigid sphere centred at c (LAMMPS fix indent): force density K (R - r)^2 pushing particle i
// out of the sphere, into f (zero outside it).
BRECCIA_HD void indenter_force(const double* x0, const double* u, int64_t i, const double c[3], double radius,
                               double stiffness, double f[3]) {
  double r[3], len2 = 0;
  for (int d = 0; d < 3; ++d) {
    f[d] = 0.0;
    r[d] = x0[3 * i + d] + u[3 * i + d] - c[d];
    len2 += r[d] * r[d];
  }
  const double len = std::sqrt(len2);
  if (len >= radius || len <= 0) return;
  const double mag = stiffness * (radius - len) * (radius - len);
  for (int d = 0; d < 3; ++d) f[d] = mag * r[d] / len;
}

// The same, added to body[3i .. 3i+2].
BRECCIA_HD void add_indenter_force(const double* x0, const double* u, int64_t i, const double c[3], double radius,
                                   double stiffness, double* body) {
  double f[3];
  indenter_force(x0, u, i, c, radius, stiffness, f);
  for (int d = 0; d < 3; ++d) body[3 * i + d] += f[d];
}

// One prescribed component at this step. kind: 0 fixed, 1 velocity, 2 displacement
// (BoundarySpec::Kind). `velocity` and `target` are the ramped values, evaluated once per
// step on the host.
BRECCIA_HD void constrain_component(int kind, double velocity, double target, double dt, double& u, double& v) {
  switch (kind) {
    case 0:
      u = 0.0;
      v = 0.0;
      break;
    case 1:
      v = velocity;
      u += dt * v;
      break;
    case 2:
      v = dt > 0 ? (target - u) / dt : 0.0;
      u = target;
      break;
  }
}

// The ramped values of one boundary at time t of a step of size dt (host side, once per
// step): the velocity a Velocity boundary imposes, the displacement a Displacement one does.
// Surface-load facets grouped by particle (CSR), kept in compute_external's (load, facet)
// order within a particle, so each particle's body force is summed in one fixed order.
struct FacetView {
  int64_t particle_count = 0;
  const int32_t* particle = nullptr;
  const int64_t* offsets = nullptr;
  const int32_t* load = nullptr;
  const double* area = nullptr;
  const double* normal = nullptr;           // 3 per facet
  const uint8_t* load_is_pressure = nullptr;
  const double* load_vector = nullptr;      // 3 per load
};

// The host arrays behind a FacetView (built once at set-up from PdSystem::surface_loads,
// group_facets_by_particle; the CUDA backend uploads them).
struct FacetLayout {
  std::vector<int32_t> particle, load;
  std::vector<int64_t> offsets;
  std::vector<double> area, normal, vectors;
  std::vector<uint8_t> is_pressure;
  FacetView view() const {
    return {static_cast<int64_t>(particle.size()), particle.data(), offsets.data(), load.data(),
            area.data(),    normal.data(),                         is_pressure.data(), vectors.data()};
  }
};

// A particle set (a constraint's or a body load's): `particles` null with count n: all.
struct SetView {
  int64_t count = 0;
  const int32_t* particles = nullptr;
};

// The time a boundary's value is taken at in a step ending at t: a velocity over the step
// at its middle, a displacement at its end.
inline double boundary_value_time(BoundarySpec::Kind kind, double t, double dt) {
  return kind == BoundarySpec::Kind::Velocity ? t - 0.5 * dt : t;
}

// A boundary's linear ramp at time t: 0 to 1 over ramp_time (1 without one).
inline double boundary_ramp(double ramp_time, double t) {
  return ramp_time > 0 ? std::clamp(t / ramp_time, 0.0, 1.0) : 1.0;
}

inline void prescribed_values(const BoundarySpec& b, double t, double dt, double velocity[3], double target[3]) {
  const double ramp = boundary_ramp(b.ramp_time, boundary_value_time(b.kind, t, dt));
  for (int d = 0; d < 3; ++d) {
    velocity[d] = target[d] = 0.0;
    if (b.kind == BoundarySpec::Kind::Velocity) velocity[d] = b.value[d] * ramp;
    else if (b.kind == BoundarySpec::Kind::Displacement) target[d] = b.value[d] * ramp;
  }
}

}  // namespace breccia::solver
