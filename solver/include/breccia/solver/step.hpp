#pragma once
// One velocity-Verlet step of the PD solver, written once for every backend: the CPU in
// double and in float (model.precision: float32) and the CUDA backend in both. The step is a
// template over the working precision `Real` and over an execution space `Exec` that decides
// only how a loop over particles runs and where a sum is kept:
//
//   exec.for_each(n, functor, name)          functor(i) for i in [0, n)
//   exec.reduce(n, load, finish, name)        finish(combine of load(i) over i), e.g. into
//                                             energy accumulators in host or device memory;
//                                             load(i) runs exactly once per i (the step's
//                                             end-of-step load also kicks the particles)
//   exec.commit_min_stretch(arrays)           swap the compressive enhancement's s_min buffers
//   exec.contact(arrays)                      short-range forces between particles that are
//                                             not family members (a cell grid of the current
//                                             positions; the CPU builds it, CUDA refuses)
//   exec.gas_buffers(gas)                     where the gas load's arrays and partial sums
//   exec.gas_block_sums_on_host(gas, p, n)    live, and its n block sums readable on the host
//                                             (gas.hpp GasBuffers; gas_update runs the passes)
//   exec.exchange(arrays, field)              optional: a distributed run's halo exchange
//                                             (solver/mpi/; rank_system.hpp)
//
// (OpenMpExec in exec_openmp.hpp, CudaExec in solver/cuda/src/cuda_backend.cu.) Every
// per-particle phase is a functor over raw pointers calling the BRECCIA_HD kernels of
// pd_kernels.hpp / load_kernels.hpp, so the arithmetic is the same on every backend and the
// order of the phases is fixed here, with the one place where global sums are taken
// (`reduce`) and the points where a distributed run exchanges its halo (`exchange_halo`:
// the displacement before a force pass, the LPS and correspondence fields between their
// two passes, the minimum stretches when they are committed).
#include <chrono>
#include <ctime>
#include <cstdint>
#include <type_traits>
#include <utility>
#include <vector>

#include "breccia/solver/boundary_field.hpp"
#include "breccia/solver/correspondence_kernels.hpp"
#include "breccia/solver/halo_transport.hpp"
#include "breccia/solver/load_kernels.hpp"
#include "breccia/solver/pd_kernels.hpp"
#include "breccia/solver/pd_system.hpp"
#include "breccia/solver/sell_kernels.hpp"

namespace breccia::solver {

inline constexpr int kMaxSurfaceLoads = 64;  // load histories travel by value (one kernel parameter)

struct LoadHistories {
  double value[kMaxSurfaceLoads];  // history of each surface load at this step
};

// Prescribed components of one constraint at this step; the ramps are evaluated on the host.
struct ConstraintStep {
  int kind;            // BoundarySpec::Kind
  unsigned components; // bit d: component d prescribed
  double velocity[3];  // Velocity: v at this step
  double target[3];    // Displacement: u at this step
  double dt;
};

// ---------------------------------------------------------------------------------------
// The phases, as functors (callable on host and device).

// Force times displacement before the step, for the trapezoidal work of loads and reactions
// (in double for float runs too), of component k.
template <class Real>
BRECCIA_HD void work_before(const PdViewT<Real>& p, Real* u_before, double* f_before, int64_t k) {
  const int64_t i = k / 3;
  const bool constrained = p.fixed_dof[i] & (1u << (k % 3));
  u_before[k] = p.u[k];
  f_before[k] = double(p.volume[i]) * (constrained ? -double(p.force[k]) : double(p.body[k]));
}

// The start of a step, one pass per particle (one loop, one barrier, where three were): the
// work's "before" values of its components, then its first half kick and drift, then, when
// `x` is given (double runs), its current position x0 + u. Each reads and writes particle i's
// values only, so fusing them changes no bits. A constraint that prescribes a component
// afterwards writes that component's position again (Constrain).
template <class Real>
struct StartOfStep {
  PdViewT<Real> p;
  Real* u_before;
  double* f_before;
  double half_dt, dt;
  double* x;  // null: the force pass forms the positions (float runs never do)
  BRECCIA_HD void operator()(int64_t i) const {
    for (int d = 0; d < 3; ++d) work_before(p, u_before, f_before, 3 * i + d);
    kick_drift_kernel(p, i, half_dt, dt);
    if (x)
      for (int64_t k = 3 * i; k < 3 * i + 3; ++k) x[k] = double(p.x0[k]) + double(p.u[k]);
  }
};

// The ramped values are imposed in double and rounded to Real. A boundary by expression
// reads its per-particle values (3 per entry of the set, boundary_field.hpp) instead of c's.
template <class Real>
struct Constrain {
  SetView set;
  ConstraintStep c;
  const double* values;  // null: c's values for every particle
  Real* u;
  Real* v;
  const Real* x0;
  double* x;  // non-null: the positions StartOfStep formed, kept current
  BRECCIA_HD void operator()(int64_t q) const {
    const int64_t i = set.particles[q];
    for (int d = 0; d < 3; ++d)
      if (c.components & (1u << d)) {
        double uk = u[3 * i + d], vk = v[3 * i + d];
        const double velocity = values ? values[3 * q + d] : c.velocity[d];
        const double target = values ? values[3 * q + d] : c.target[d];
        constrain_component(c.kind, velocity, target, c.dt, uk, vk);
        u[3 * i + d] = static_cast<Real>(uk);
        v[3 * i + d] = static_cast<Real>(vk);
        if (x) x[3 * i + d] = double(x0[3 * i + d]) + double(u[3 * i + d]);
      }
  }
};

struct ClearArray {
  double* a;
  BRECCIA_HD void operator()(int64_t k) const { a[k] = 0.0; }
};

struct SurfaceLoads {
  FacetView f;
  LoadHistories h;
  const double* volume;
  const int64_t* bond_offsets;
  const uint8_t* bond_state;
  double* body;
  BRECCIA_HD void operator()(int64_t q) const {
    const int64_t i = f.particle[q];
    if (!particle_attached(bond_offsets, bond_state, i)) return;
    for (int64_t e = f.offsets[q]; e < f.offsets[q + 1]; ++e) {
      const int l = f.load[e];
      double force[3];
      facet_force(f.load_is_pressure[l], h.value[l], f.area[e], &f.normal[3 * e], &f.load_vector[3 * l], force);
      for (int d = 0; d < 3; ++d) body[3 * i + d] += force[d] / volume[i];
    }
  }
};

struct BodyLoad {
  SetView set;
  double history, g[3];
  const double* density;
  double* body;
  BRECCIA_HD void operator()(int64_t q) const {
    const int64_t i = set.particles ? set.particles[q] : q;
    for (int d = 0; d < 3; ++d) body[3 * i + d] += density[i] * history * g[d];
  }
};

struct Indenter {
  const double* x0;
  const double* u;
  double c[3], radius, stiffness;
  double* body;
  BRECCIA_HD void operator()(int64_t i) const { add_indenter_force(x0, u, i, c, radius, stiffness, body); }
};

template <class From, class To>
struct Convert {
  const From* from;
  To* to;
  BRECCIA_HD void operator()(int64_t k) const { to[k] = static_cast<To>(from[k]); }
};

struct CurrentPositions {
  const double* x0;
  const double* u;
  double* x;
  BRECCIA_HD void operator()(int64_t k) const { x[k] = x0[k] + u[k]; }
};

template <class Real>
struct Dilatation {
  PdViewT<Real> p;
  BRECCIA_HD void operator()(int64_t i) const { lps_dilatation_kernel(p, i); }
};

template <class Real>
struct BondForces {
  static constexpr int kMinBlocksPerSm = 2;  // CUDA launch bounds: at most 128 registers (cuda_launch.cuh)
  PdViewT<Real> p;
  BRECCIA_HD void operator()(int64_t i) const { force_kernel(p, i); }
};

template <class Real>
struct FamilyShortRange {
  PdViewT<Real> p;
  BRECCIA_HD void operator()(int64_t i) const { short_range_kernel(p, i); }
};

struct CorrespondenceDeformation {
  CorrespondenceView c;
  BRECCIA_HD void operator()(int64_t i) const { correspondence_deformation_kernel(c, i); }
};

struct CorrespondenceForces {
  CorrespondenceView c;
  BRECCIA_HD void operator()(int64_t i) const { correspondence_force_kernel(c, i); }
};

// ---------------------------------------------------------------------------------------
// Reductions: a load per index, an associative combine, and a finish that adds the total to
// accumulators wherever the backend keeps them.

struct StepSums {
  double released;  // energy of the bonds broken this step [J]
  double work;      // work of external forces and reactions over the step [J]
  // 1/2 m v^2 of the prescribed components [J]: StepLoad's at the step's end, PrescribedKinetic's
  // at its start. A boundary's reaction counts the internal forces only, so the kinetic energy
  // a velocity or displacement boundary gives its own particles is booked as work this way.
  double prescribed_kinetic;
};

// The sums' combine, written once for every load over StepSums.
BRECCIA_HD StepSums step_sums_add(StepSums a, StepSums b) {
  return {a.released + b.released, a.work + b.work, a.prescribed_kinetic + b.prescribed_kinetic};
}

// Component k's kinetic energy where a boundary prescribes it, else 0.
template <class Real>
BRECCIA_HD double prescribed_kinetic_energy(const PdViewT<Real>& p, int64_t k) {
  const int64_t i = k / 3;
  const bool constrained = p.fixed_dof[i] & (1u << (k % 3));
  const double v = double(p.v[k]);
  return constrained ? 0.5 * double(p.density[i]) * double(p.volume[i]) * v * v : 0.0;
}

// The end of a step in one pass (one loop where there were two): component k's share of the
// step's sums, and, at each particle's first component, that particle's acceleration and
// second half kick. The kick writes a and v, which no share reads, so fusing changes no
// bits; the sum still runs over the 3N components in the same order, split among threads as
// before. (A prescribed component's v is the boundary's, set before this pass; the kick
// leaves it.)
template <class Real>
struct StepLoad {
  using Value = StepSums;
  PdViewT<Real> p;
  const Real* u_before;
  const double* f_before;
  double half_dt;
  BRECCIA_HD static Value identity() { return {0.0, 0.0, 0.0}; }
  BRECCIA_HD static Value combine(Value a, Value b) { return step_sums_add(a, b); }
  // k runs over 3N components; the first N also carry the particles' released energy.
  BRECCIA_HD Value operator()(int64_t k) const {
    const int64_t i = k / 3;
    if (k % 3 == 0) acceleration_kernel(p, i, half_dt);
    const bool constrained = p.fixed_dof[i] & (1u << (k % 3));
    const double f_after = double(p.volume[i]) * (constrained ? -double(p.force[k]) : double(p.body[k]));
    return {k < p.n ? p.dissipated[k] : 0.0, 0.5 * (f_before[k] + f_after) * (double(p.u[k]) - double(u_before[k])),
            prescribed_kinetic_energy(p, k)};
  }
};

// The prescribed components' kinetic energy at a step's start (before the boundaries move
// them), taken off the work; StepFinish adds it at the step's end.
template <class Real>
struct PrescribedKinetic {
  using Value = StepSums;
  PdViewT<Real> p;
  BRECCIA_HD static Value identity() { return {0.0, 0.0, 0.0}; }
  BRECCIA_HD static Value combine(Value a, Value b) { return step_sums_add(a, b); }
  BRECCIA_HD Value operator()(int64_t k) const { return {0.0, 0.0, prescribed_kinetic_energy(p, k)}; }
};
struct PrescribedKineticBefore {
  double* external_work;
  BRECCIA_HD void operator()(StepSums s) const { *external_work -= s.prescribed_kinetic; }
};

// Released energy alone, for a force pass outside a step.
struct ReleasedLoad {
  using Value = StepSums;
  const double* dissipated;
  BRECCIA_HD static Value identity() { return {0.0, 0.0, 0.0}; }
  BRECCIA_HD static Value combine(Value a, Value b) { return step_sums_add(a, b); }
  BRECCIA_HD Value operator()(int64_t i) const { return {dissipated[i], 0.0, 0.0}; }
};

struct StepFinish {
  double* external_work;
  double* dissipated_energy;
  BRECCIA_HD void operator()(StepSums s) const {
    *dissipated_energy += s.released;
    *external_work += s.work + s.prescribed_kinetic;
  }
};

// ---------------------------------------------------------------------------------------
// What a distributed run's ranks exchange: HaloField (halo_transport.hpp).

// Everything one step touches, as raw pointers into the backend's memory. `p` is the working
// precision; `d` holds the double arrays the loads are evaluated on (for a double run the
// same arrays as `p`; for a float run the double mirror that float32_state.hpp describes).
template <class Real>
struct StepArrays {
  PdViewT<Real> p;
  PdView d;
  double* x = nullptr;        // current positions, double runs
  Real* u_before = nullptr;   // 3N scratch
  double* f_before = nullptr; // 3N scratch
  FacetView facets;
  std::vector<SetView> constraint_sets;  // one per PdSystem::constraints entry
  std::vector<const double*> constraint_values;  // per entry: its field's values (null: constant)
  std::vector<SetView> body_load_sets;   // one per PdSystem::body_loads entry
  CorrespondenceView corr{};             // correspondence model: moduli, F, A, non-affine energy
  double* external_work = nullptr;       // accumulators (StepFinish)
  double* dissipated_energy = nullptr;
  // A distributed run's ghosts: held after the p.n owned particles, their values arrive by
  // exchange_halo (never computed here). Zero on one process.
  int64_t ghosts = 0;
  // The SELL-C-sigma layout of the bonds (sell_layout.hpp; lanes 0: none, the CSR passes run):
  // the fast passes then walk `sell_entries`, and every break is also written to the CSR's
  // state (sell.csr_state, the state in `p`), which the other passes read.
  SellView sell{};
  SellEntriesT<Real> sell_entries{};
};

// The arrays a halo exchange of `field` carries, in the step's memory (host or device), for
// every execution space that exchanges (the CPU's and the CUDA backend's under MPI), so that
// what travels is decided once. `velocity`: a rate law (materials[].strength_rate) reads the
// partners' velocities too (bond_stretch_rate): the half-step velocity the owner's drift left.
template <class Real>
HaloArrays halo_arrays(const StepArrays<Real>& a, HaloField field, bool velocity) {
  HaloArrays h;
  auto add = [&h](const void* data, size_t bytes) { h.item[h.count++] = {const_cast<void*>(data), bytes}; };
  switch (field) {
    case HaloField::Displacement:
      add(a.p.u, 3 * sizeof(Real));
      if (velocity) add(a.p.v, 3 * sizeof(Real));
      break;
    case HaloField::Lps:
      add(a.p.dilatation, sizeof(Real));
      if (a.p.lps_a) {
        add(a.p.lps_a, sizeof(Real));
        add(a.p.lps_b, sizeof(Real));
      }
      break;
    case HaloField::Correspondence:
      add(a.corr.force_tensor, 9 * sizeof(double));
      break;
  }
  return h;
}

// exec.exchange(a, field) where the execution space has one (a distributed run's); nothing
// otherwise. Detected at compile time (C++17: nvcc compiles this header too).
template <class Exec, class A, class = void>
struct HasExchange : std::false_type {};
template <class Exec, class A>
struct HasExchange<Exec, A, std::void_t<decltype(std::declval<Exec&>().exchange(std::declval<const A&>(), HaloField{}))>>
    : std::true_type {};

template <class Exec, class Real>
void exchange_halo(Exec& exec, const StepArrays<Real>& a, HaloField field) {
  if constexpr (HasExchange<Exec, StepArrays<Real>>::value) exec.exchange(a, field);
}

// External force density at time t on the double arrays (float runs included: their loads
// are evaluated in double and rounded once, docs/theory.md Precision).
// A gas load's pressure follows the displacement at t (gas.hpp); `dt` is the step that led
// to t (0 outside a step: the gas keeps its mass).
// `gas_pass`: false takes the gas as it stands (its pressure on the wall, no update of its
// volume, front or cracks): the loads at t = 0 before the first step (pd_initial_accelerations).
template <class Exec, class Real>
void pd_external(Exec& exec, const StepArrays<Real>& a, PdSystem& sys, double t, double dt = 0.0, bool gas_pass = true) {
  const PdView& d = a.d;
  const int64_t n = d.n;
  const bool gas = sys.gas.active && gas_pass;
  // The gas's own cost is timed (summary.json gas_wall_s, and gas_cpu_s, which other load on
  // the machine does not inflate; the requirement bounds it at 5% of a step).
  const auto gas_start = std::chrono::steady_clock::now();
  const std::clock_t gas_cpu_start = gas ? std::clock() : 0;
  if (gas) gas_update(exec, d, a.facets, sys.gas, t, dt, dt > 0.0 ? static_cast<const Real*>(a.u_before) : nullptr);
  const auto gas_mid = std::chrono::steady_clock::now();
  const std::clock_t gas_cpu_mid = gas ? std::clock() : 0;
  exec.for_each(3 * n, ClearArray{const_cast<double*>(d.body)}, "clear body forces");
  double* body = const_cast<double*>(d.body);
  if (a.facets.particle_count > 0) {
    LoadHistories h{};
    for (size_t l = 0; l < sys.surface_loads.size(); ++l)
      h.value[l] = sys.gas.active && static_cast<int>(l) == sys.gas.load ? sys.gas.pressure
                                                                          : sys.surface_loads[l].spec->history.at(t);
    exec.for_each(a.facets.particle_count, SurfaceLoads{a.facets, h, d.volume, d.offsets, d.state, body},
                  "surface_load");
  }
  if (gas) {
    const auto crack_start = std::chrono::steady_clock::now();
    const std::clock_t crack_cpu_start = std::clock();
    gas_crack_forces(exec, d, sys.gas, body);
    sys.gas.wall_s += std::chrono::duration<double>(gas_mid - gas_start).count() +
                      std::chrono::duration<double>(std::chrono::steady_clock::now() - crack_start).count();
    sys.gas.cpu_s += static_cast<double>((gas_cpu_mid - gas_cpu_start) + (std::clock() - crack_cpu_start)) / CLOCKS_PER_SEC;
  }
  for (size_t b = 0; b < sys.body_loads.size(); ++b) {
    const LoadSpec& spec = *sys.body_loads[b].spec;
    const SetView set = a.body_load_sets[b];
    // (every particle: count n and no list; a set this system holds none of: count 0)
    exec.for_each(set.count,
                  BodyLoad{set, spec.history.at(t), {spec.vector[0], spec.vector[1], spec.vector[2]}, d.density, body},
                  "body_load");
  }
  const IndenterSpec& ind = sys.config.indenter;
  if (ind.enabled) {
    Indenter f{d.x0, d.u, {0, 0, 0}, ind.radius, ind.stiffness, body};
    for (int k = 0; k < 3; ++k) f.c[k] = sys.indenter_position[k] = ind.center[k] + ind.velocity[k] * t;
    exec.for_each(n, f, "indenter");
  }
}

// exec.upload_boundary_values(c, values) where the execution space keeps its own copy of a
// boundary's per-particle values (a device's); host spaces read the PdSystem's directly.
template <class Exec, class = void>
struct HasBoundaryUpload : std::false_type {};
template <class Exec>
struct HasBoundaryUpload<Exec, std::void_t<decltype(std::declval<Exec&>().upload_boundary_values(
                                   size_t{}, std::declval<const std::vector<double>&>()))>> : std::true_type {};

// Prescribed components at time t: one pass per boundary, in the case's order (a particle
// in two boundaries takes the later one's value), the ramps (and fields by expression)
// evaluated here on the host. `positions`: current positions (double) formed before, kept
// current for the components prescribed here.
template <class Exec, class Real>
void pd_constraints(Exec& exec, const StepArrays<Real>& a, PdSystem& sys, double t, double dt,
                    double* positions = nullptr) {
  for (size_t c = 0; c < sys.constraints.size(); ++c) {
    PdSystem::Constraint& con = sys.constraints[c];
    const BoundarySpec& b = *con.spec;
    ConstraintStep cs{static_cast<int>(b.kind), 0u, {0, 0, 0}, {0, 0, 0}, dt};
    for (int d = 0; d < 3; ++d)
      if (b.components[d]) cs.components |= 1u << d;
    prescribed_values(b, t, dt, cs.velocity, cs.target);
    const SetView set = a.constraint_sets[c];
    if (set.count == 0) continue;
    const double* values = nullptr;
    if (con.field) {
      if (refresh_boundary_values(con, sys.x0, boundary_value_time(b.kind, t, dt)))
        if constexpr (HasBoundaryUpload<Exec>::value) exec.upload_boundary_values(c, con.values);
      values = a.constraint_values[c];
    }
    exec.for_each(set.count, Constrain<Real>{set, cs, values, a.p.u, a.p.v, a.p.x0, positions}, "constraint");
  }
}

// Internal forces at the current displacement: bond forces (LPS: dilatation first;
// correspondence: its two passes), then the short-range forces. Released energy summed into
// the accumulators when `sum_released` (a step sums it with the work instead).
// `owned_positions_current`: the owned particles' positions a.x were formed already (a
// step's StartOfStep); the ghosts' are formed here, after their displacement arrived.
template <class Exec, class Real>
void pd_force_pass(Exec& exec, const StepArrays<Real>& a, bool sum_released, bool owned_positions_current = false) {
  const PdViewT<Real>& p = a.p;
  const int64_t n = p.n;
  exchange_halo(exec, a, HaloField::Displacement);
  if constexpr (std::is_same_v<Real, double>) {  // float never forms x0 + u (float32_state.hpp)
    if (!owned_positions_current)
      exec.for_each(3 * (n + a.ghosts), CurrentPositions{p.x0, p.u, a.x}, "current_positions");
    else if (a.ghosts > 0)
      exec.for_each(3 * a.ghosts, CurrentPositions{p.x0 + 3 * n, p.u + 3 * n, a.x + 3 * n}, "ghost_positions");
    if (p.model == static_cast<int>(PdModel::Correspondence)) {
      exec.for_each(n, CorrespondenceDeformation{a.corr}, "correspondence_deformation_kernel");
      exchange_halo(exec, a, HaloField::Correspondence);
      exec.for_each(n, CorrespondenceForces{a.corr}, "correspondence_force_kernel");
    }
  }
  if (p.model != static_cast<int>(PdModel::Correspondence)) {
    // The layout's passes where they apply (one constant horizon: the fast paths; variable
    // horizons: the dual-horizon pass), one launch per path; otherwise the CSR's, after which
    // the layout's state is refreshed from the CSR's (those passes break bonds there only).
    const bool fast = a.sell.lanes > 0 && sell_fast_pass(p);
    const bool general = a.sell.lanes > 0 && !fast && sell_general_pass(p, a.sell_entries);
    const bool sell = fast || general;
    const PdViewT<Real> e = sell ? sell_entry_view(p, a.sell_entries) : p;
    const bool lps = p.model == static_cast<int>(PdModel::LPS);
    if (lps) {
      if (sell) exec.for_each(a.sell.lanes, SellDilatation<Real>{e, a.sell}, "sell_dilatation_kernel");
      else exec.for_each(n, Dilatation<Real>{p}, "lps_dilatation_kernel");
      exchange_halo(exec, a, HaloField::Lps);
    }
    if (general && p.diagnostics) {
      exec.for_each(a.sell.lanes, SellGeneralForces<Real, true>{e, a.sell}, "sell_dual_horizon_diagnostics_kernel");
    } else if (general) {
      exec.for_each(a.sell.lanes, SellGeneralForces<Real, false>{e, a.sell}, "sell_dual_horizon_force_kernel");
    } else if (fast && lps) {
      exec.for_each(a.sell.lanes, SellLpsForces<Real>{e, a.sell}, "sell_lps_force_kernel");
    } else if (fast) {
      exec.for_each(a.sell.lanes, SellPmbForces<Real>{e, a.sell}, "sell_pmb_force_kernel");
    } else {
      exec.for_each(n, BondForces<Real>{p}, "force_kernel");
      if (a.sell.lanes > 0)
        exec.for_each(a.sell.lanes, SellStateFromCsr{a.sell, a.sell_entries.state}, "sell_state_from_csr");
    }
    if (p.short_range_k) {
      exec.for_each(n, FamilyShortRange<Real>{p}, "short_range_kernel");
      exec.contact(a);
    }
  }
  if (sum_released)
    exec.reduce(n, ReleasedLoad{p.dissipated}, StepFinish{a.external_work, a.dissipated_energy},
                "released energy reduction");
}

// The accelerations at t = 0, no kick (accelerations_kernel, pd_kernels.hpp).
template <class Real>
struct InitialAccelerations {
  PdViewT<Real> p;
  BRECCIA_HD void operator()(int64_t i) const { accelerations_kernel(p, i); }
};

// Velocity Verlet's a(0), before a run's first step: the internal forces at the initial
// displacement (sys.force, which the set-up's last force pass left, or a restart's
// read_checkpoint) and the loads at t = 0 (the gas as set up: its pressure at t = 0 on the
// wall, no pass). Later steps carry a from the step before (StepLoad), a restart past step 0
// from its checkpoint. Without it (before 2026-12-07) the first half kick read a = 0: a body
// under a constant load lagged half a step's velocity for the whole run (its displacement
// short by g dt t / 2), a body released from a strained state started with half its first
// kick, and the lost kick's kinetic energy stayed in the energy balance as an error.
template <class Exec, class Real>
void pd_initial_accelerations(Exec& exec, StepArrays<Real>& a, PdSystem& sys) {
  constexpr bool single = std::is_same_v<Real, float>;
  const int64_t n = a.p.n;
  if (sys.loads_vary()) {
    // The indenter and the gas read the double displacement: a float run copies it first.
    if (single && (sys.config.indenter.enabled || sys.gas.active))
      exec.for_each(3 * n, Convert<Real, double>{a.p.u, const_cast<double*>(a.d.u)}, "float u to double");
    pd_external(exec, a, sys, sys.time, 0.0, false);
    if (single) exec.for_each(3 * n, Convert<double, Real>{a.d.body, const_cast<Real*>(a.p.body)}, "body force to float");
  }
  exec.for_each(n, InitialAccelerations<Real>{a.p}, "initial_accelerations_kernel");
}

// One velocity-Verlet step of size sys.dt: the phases of every backend, in this order.
template <class Exec, class Real>
void pd_step(Exec& exec, StepArrays<Real>& a, PdSystem& sys) {
  constexpr bool single = std::is_same_v<Real, float>;
  const double dt = sys.dt, half = 0.5 * dt;
  const int64_t n = a.p.n;
  exec.commit_min_stretch(a);  // the last step's s_min is what this step's pass reads
  if (n == 0) {  // nothing to launch (a grid of zero blocks is a launch error)
    sys.time += dt;
    ++sys.step;
    return;
  }
  if (sys.step == 0) pd_initial_accelerations(exec, a, sys);
  // A velocity or displacement boundary: its particles' kinetic energy before it moves them
  // (StepFinish books the change; fixed components hold v = 0 and add nothing).
  if (sys.prescribes_motion())
    exec.reduce(3 * n, PrescribedKinetic<Real>{a.p}, PrescribedKineticBefore{a.external_work},
                "prescribed kinetic energy");
  // Double runs form the owned positions here (float never forms x0 + u): nothing moves u
  // between here and the force pass but the constraints, which keep them current.
  double* positions = single ? nullptr : a.x;
  exec.for_each(n, StartOfStep<Real>{a.p, a.u_before, a.f_before, half, dt, positions}, "start_of_step_kernel");
  sys.time += dt;
  const double t = sys.time;
  pd_constraints(exec, a, sys, t, dt, positions);
  if (sys.loads_vary()) {
    // The indenter and the gas read the double displacement: a float run copies it first.
    if (single && (sys.config.indenter.enabled || sys.gas.active))
      exec.for_each(3 * n, Convert<Real, double>{a.p.u, const_cast<double*>(a.d.u)}, "float u to double");
    pd_external(exec, a, sys, t, dt);
    if (single) exec.for_each(3 * n, Convert<double, Real>{a.d.body, const_cast<Real*>(a.p.body)}, "body force to float");
  }
  pd_force_pass(exec, a, false, !single);
  exec.reduce(3 * n, StepLoad<Real>{a.p, a.u_before, a.f_before, half}, StepFinish{a.external_work, a.dissipated_energy},
              "end_of_step_kernel");
  ++sys.step;
}

}  // namespace breccia::solver
