#pragma once
// Explosive gas in a charge hole (loads[].type: gas; docs/theory.md "Borehole gas").
//
// The case's pressure history is what the burning charge gives in the cavity at its
// reference volume V0. The pressure applied follows the cavity's current volume along an
// isentrope with a high- and a low-pressure gamma, so the gas loses pressure as the hole and
// the cracks it has entered open, and loses mass through a vent once its front reaches a
// free surface (or at once, through an open mouth). Every quantity the step needs is a
// per-particle functor over raw pointers (host and device alike) plus one host update of a
// few scalars per step:
//
//   V = V0 + sum over wall facets (-A n . u)            wall: the hole's facets, n outward
//                                                       from the body (into the cavity)
//         + 1/2 sum over open wetted entries a_k e_k     cracks: e_k = |y| - |xi| > 0
//
// with the crack-face area of entry k a_k = (kappa_i + kappa_j) / 2 V_i V_j, kappa_i = 2 d / m_i,
// m_i = sum_j V_j |xi|, d the dimension: for a straight crack opened by delta in a continuum
// this sum is exactly (crack area) x delta (docs/theory.md). The gas force on particle i is
// p dV/dy_i, so the gas work is the integral of p dV and the energy balance closes.
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "breccia/solver/hd.hpp"
#include "breccia/solver/load_kernels.hpp"
#include "breccia/solver/pd_kernels.hpp"

namespace breccia::solver {

// Isentrope of the detonation or deflagration products: p rho^-gamma constant, gamma_high
// above switch_pressure, gamma_low below (the two-gamma law of blasting practice).
struct GasLaw {
  double gamma_high = 3.0;
  double gamma_low = 1.3;
  double switch_pressure = 0.1e9;  // Pa, absolute
};

// Absolute pressure at relative density rho on the isentrope through (1, p_ref): rho is the
// gas's density over its density in the reference cavity with all its mass.
BRECCIA_HD double gas_isentrope_pressure(double p_ref, double rho, const GasLaw& g) {
  if (p_ref <= 0.0 || rho <= 0.0) return 0.0;
  if (p_ref >= g.switch_pressure) {
    const double rho_switch = std::pow(g.switch_pressure / p_ref, 1.0 / g.gamma_high);  // <= 1
    return rho >= rho_switch ? p_ref * std::pow(rho, g.gamma_high)
                             : g.switch_pressure * std::pow(rho / rho_switch, g.gamma_low);
  }
  const double rho_switch = std::pow(g.switch_pressure / p_ref, 1.0 / g.gamma_low);  // > 1
  return rho <= rho_switch ? p_ref * std::pow(rho, g.gamma_low)
                           : g.switch_pressure * std::pow(rho / rho_switch, g.gamma_high);
}

BRECCIA_HD double gas_local_gamma(double p, const GasLaw& g) {
  return p >= g.switch_pressure ? g.gamma_high : g.gamma_low;
}

// Choked (sonic) mass flux through an orifice: mdot = Gamma A sqrt(gamma p rho), with
// Gamma = (2 / (gamma + 1))^((gamma + 1) / (2 (gamma - 1))) (isentropic nozzle flow).
BRECCIA_HD double choked_flow_factor(double gamma) {
  return std::pow(2.0 / (gamma + 1.0), (gamma + 1.0) / (2.0 * (gamma - 1.0)));
}

// Can the gas pass between the two ends of entry k? Only when no half-bond that exists is
// intact (a bond carrying no force: broken, or cut by a pre-crack).
template <class Real>
BRECCIA_HD bool gas_entry_open(const PdViewT<Real>& p, int64_t k) {
  const uint8_t st = p.state[k];
  const bool own = p.vol_own[k] > Real(0) && (st & kOwnIntact);
  const bool dual = p.k_dual[k] > Real(0) && (st & kDualIntact);
  return !own && !dual;
}

// Device-side arrays of the gas (GasState below holds them on the host).
struct GasView {
  int load = -1;                   // index of the gas among the surface loads (FacetView::load)
  double* wall_dv = nullptr;       // per facet particle: -sum A n.u of its gas facets (frozen once it detaches)
  double* arrival = nullptr;       // per particle: time the gas reached it (+inf: dry); null: no crack entry
  double* arrival_next = nullptr;  // the front pass writes here, then copies back
  const double* kappa = nullptr;   // per particle: 2 d / sum_j V_j |xi|
  const uint8_t* vent_face = nullptr;  // per particle: owns a facet of a vent surface
  double* push = nullptr;          // 3 per particle: dV_crack/dy_i / V_i (the crack force is -p push)
  uint8_t* front_done = nullptr;   // per particle: wetted, and every partner is too (stops pushing)
};

BRECCIA_HD bool gas_wetted(const GasView& g, int64_t i) { return g.arrival[i] < 1e300; }
BRECCIA_HD bool gas_wetted_next(const GasView& g, int64_t i) { return g.arrival_next[i] < 1e300; }

// Wall volume change of facet particle q: while the particle is attached its share follows
// its displacement; when it loses its last bond it leaves the wall and its share is frozen
// (the gas neither pushes it any more, SurfaceLoads, nor follows it).
struct GasWallVolume {
  FacetView f;
  GasView g;
  const double* u;
  const int64_t* offsets;
  const uint8_t* state;
  BRECCIA_HD void operator()(int64_t q) const {
    const int64_t i = f.particle[q];
    if (!particle_attached(offsets, state, i)) return;
    double dv = 0.0;
    for (int64_t e = f.offsets[q]; e < f.offsets[q + 1]; ++e)
      if (f.load[e] == g.load)
        for (int d = 0; d < 3; ++d) dv -= f.area[e] * f.normal[3 * e + d] * u[3 * i + d];
    g.wall_dv[q] = dv;
  }
};

// *a = min(*a, value), atomically. A minimum does not depend on the order of the updates, so
// the result is the same on any number of threads.
BRECCIA_HD void atomic_min(double* a, double value) {
#if defined(__CUDA_ARCH__)
  auto* bits = reinterpret_cast<unsigned long long*>(a);
  unsigned long long old = *bits;
  while (value < __longlong_as_double(old)) {
    const unsigned long long seen = atomicCAS(bits, old, __double_as_longlong(value));
    if (seen == old) break;
    old = seen;
  }
#else
  std::atomic_ref<double> ref(*a);
  double current = ref.load(std::memory_order_relaxed);
  while (value < current && !ref.compare_exchange_weak(current, value, std::memory_order_relaxed)) {
  }
#endif
}

// The gas front: a dry particle is reached when an open entry joins it to a wetted one and
// the gas has had time to run the entry's length at `speed` (one entry per step at most).
// Pushed from the wetted particles (few, in a case that does not pulverise) rather than
// pulled by every dry one: arrival_next starts as a copy of arrival (GasFrontCopy), and each
// wetted particle lowers its dry partners' arrival times.
struct GasFrontCopy {
  GasView g;
  BRECCIA_HD void operator()(int64_t i) const { g.arrival_next[i] = g.arrival[i]; }
};

// A wetted particle all of whose partners are wetted has nothing left to push (wetting is
// for good): it is marked once and skipped from then on.
struct GasFront {
  PdView p;
  GasView g;
  double t, speed;
  BRECCIA_HD void operator()(int64_t i) const {
    if (!gas_wetted(g, i) || g.front_done[i]) return;
    bool dry_partner = false;
    for (int64_t k = p.offsets[i]; k < p.offsets[i + 1]; ++k) {
      const int32_t j = p.neighbor[k];
      if (gas_wetted(g, j)) continue;
      dry_partner = true;
      if (!gas_entry_open(p, k)) continue;
      const double reached = g.arrival[i] + p.xi_len[k] / speed;
      if (reached <= t) atomic_min(&g.arrival_next[j], reached);
    }
    if (!dry_partner) g.front_done[i] = 1;
  }
};

struct GasFrontCommit {
  GasView g;
  BRECCIA_HD void operator()(int64_t i) const { g.arrival[i] = g.arrival_next[i]; }
};

// Opening and unit direction of entry k (i -> j) in the current configuration.
BRECCIA_HD double gas_entry_opening(const PdView& p, int64_t i, int64_t k, double dir[3]) {
  const int64_t j = p.neighbor[k];
  double len2 = 0.0;
  for (int d = 0; d < 3; ++d) {
    dir[d] = (p.x0[3 * j + d] + p.u[3 * j + d]) - (p.x0[3 * i + d] + p.u[3 * i + d]);
    len2 += dir[d] * dir[d];
  }
  const double len = std::sqrt(len2);
  for (int d = 0; d < 3; ++d) dir[d] = len > 0 ? dir[d] / len : 0.0;
  return len - p.xi_len[k];
}

struct GasSums {
  double volume;         // m3
  double volume_before;  // m3, of the cracks the gas filled before this step's front moved
  double vents;          // crack-wetted particles on a vent surface
};

// Sum of the wall shares.
struct GasWallSum {
  using Value = GasSums;
  const double* wall_dv;
  BRECCIA_HD static Value identity() { return {0.0, 0.0, 0.0}; }
  BRECCIA_HD static Value combine(Value a, Value b) {
    return {a.volume + b.volume, a.volume_before + b.volume_before, a.vents + b.vents};
  }
  BRECCIA_HD Value operator()(int64_t q) const { return {wall_dv[q], wall_dv[q], 0.0}; }
};

// Crack volume the gas fills (each pair seen from both ends, hence the half) with the front
// this step has reached (arrival_next) and with the one before it (arrival): the difference is
// crack the gas has just spread into, a free expansion that does no work on the solid. And
// whether the front stands on a vent surface: a wall particle (arrival 0) on a vent surface
// does not vent; the gas has to get there through a crack. The same loop keeps each
// particle's dV_crack/dy_i (push), so that the crack forces need no second pass over the
// entries once the pressure is known.
struct GasCrackSum {
  using Value = GasSums;
  PdView p;
  GasView g;
  BRECCIA_HD static Value identity() { return {0.0, 0.0, 0.0}; }
  BRECCIA_HD static Value combine(Value a, Value b) {
    return {a.volume + b.volume, a.volume_before + b.volume_before, a.vents + b.vents};
  }
  BRECCIA_HD Value operator()(int64_t i) const {
    if (!gas_wetted_next(g, i)) return identity();
    const bool before_i = gas_wetted(g, i);
    Value v{0.0, 0.0, g.vent_face[i] && g.arrival_next[i] > 0.0 ? 1.0 : 0.0};
    double push[3] = {0.0, 0.0, 0.0};
    for (int64_t k = p.offsets[i]; k < p.offsets[i + 1]; ++k) {
      const int32_t j = p.neighbor[k];
      if (!gas_wetted_next(g, j) || !gas_entry_open(p, k)) continue;
      double dir[3];
      const double e = gas_entry_opening(p, i, k, dir);
      if (!(e > 0.0)) continue;
      const double a_over_vi = 0.5 * (g.kappa[i] + g.kappa[j]) * p.volume[j];
      const double share = a_over_vi * p.volume[i] * e * 0.5;
      v.volume += share;
      if (before_i && gas_wetted(g, j)) v.volume_before += share;
      for (int d = 0; d < 3; ++d) push[d] += a_over_vi * dir[d];
    }
    for (int d = 0; d < 3; ++d) g.push[3 * i + d] = push[d];
    return v;
  }
};

struct GasSumsInto {
  GasSums* out;
  BRECCIA_HD void operator()(GasSums s) const { *out = s; }
};

// Gas pressure on the faces of the cracks it fills: -p a_k e_hat on i for each open wetted
// entry (the derivative of p V_crack), as a force density: -p push_i (GasCrackSum).
struct GasCrackPressure {
  GasView g;
  double pressure;
  double* body;
  BRECCIA_HD void operator()(int64_t i) const {
    if (!gas_wetted(g, i)) return;
    for (int d = 0; d < 3; ++d) body[3 * i + d] -= pressure * g.push[3 * i + d];
  }
};

// The host's side of the gas: the arrays behind GasView and the scalars of its state.
struct GasState {
  bool active = false;
  int load = -1;                  // surface load index
  const LoadSpec* spec = nullptr;
  GasLaw law;
  double reference_volume = 0.0;  // V0 [m3]
  double vent_area = 0.0;         // [m2]
  double reference_density = 0.0; // gas density in V0 with all its mass [kg/m3]
  double ambient = 0.0;           // [Pa]
  double fixed_front_speed = 0.0; // [m/s]; 0: the escape speed 2 c / (gamma - 1)
  bool crack_entry = false;
  std::vector<double> wall_dv, arrival, arrival_next, kappa, push;
  std::vector<uint8_t> vent_face, front_done;
  // evolving state (checkpointed with the particles')
  double volume = 0.0, wall_volume = 0.0, crack_volume = 0.0;
  double pressure = 0.0;          // gauge pressure applied [Pa]
  double pressure_abs = 0.0;      // absolute gas pressure [Pa]
  double mass_fraction = 1.0;     // of the charge's gas still in the cavity
  double work = 0.0;              // integral of p dV [J]
  bool vented = false;
  double vent_time = -1.0;
  double peak_pressure = 0.0;     // largest gauge pressure so far [Pa]
  // Vented and down to 0.1% of its peak: the gas has done its work; its passes stop and it
  // pushes no more (a pulverised block would otherwise pay a bond pass per step for nothing).
  bool spent = false;
  double wall_s = 0.0;            // wall time spent in the gas's passes (not checkpointed)

  GasView view() {
    GasView v;
    v.load = load;
    v.wall_dv = wall_dv.data();
    v.arrival = crack_entry ? arrival.data() : nullptr;
    v.arrival_next = crack_entry ? arrival_next.data() : nullptr;
    v.kappa = kappa.data();
    v.vent_face = vent_face.data();
    v.push = push.data();
    v.front_done = front_done.data();
    return v;
  }
  // Speed of the gas front along open bonds now: the fixed one, or the speed of a gas
  // expanding into an empty channel, 2 c / (gamma - 1) with c = sqrt(gamma p / rho).
  double front_speed() const;
  // One update of the scalars from the summed wall and crack volumes at time t (dt: the
  // step, 0 outside one: no outflow). crack_before: the cracks filled before the front's
  // move this step, at the current positions (the work counts only the motion's dV).
  void advance(double wall, double crack, double crack_before, double vents, double t, double dt);
};

// The gas at time t on the double arrays `d` (after the drift): front, volume, pressure.
template <class Exec>
void gas_update(Exec& exec, const PdView& d, const FacetView& f, GasState& gas, double t, double dt) {
  if (gas.spent) return;
  GasView g = gas.view();
  exec.for_each(f.particle_count, GasWallVolume{f, g, d.u, d.offsets, d.state}, "gas_wall_volume");
  GasSums wall{0.0, 0.0, 0.0}, crack{0.0, 0.0, 0.0};
  exec.reduce(f.particle_count, GasWallSum{g.wall_dv}, GasSumsInto{&wall}, "gas wall volume");
  if (g.arrival) {
    exec.for_each(d.n, GasFrontCopy{g}, "gas_front_copy");
    exec.for_each(d.n, GasFront{d, g, t, gas.front_speed()}, "gas_front");
    exec.reduce(d.n, GasCrackSum{d, g}, GasSumsInto{&crack}, "gas crack volume");
    exec.for_each(d.n, GasFrontCommit{g}, "gas_front_commit");
  }
  gas.advance(wall.volume, crack.volume, crack.volume_before, crack.vents, t, dt);
}

// The gas's pressure on the crack faces it fills, added to `body` (after the surface loads).
template <class Exec>
void gas_crack_forces(Exec& exec, const PdView& d, GasState& gas, double* body) {
  if (!gas.crack_entry || gas.pressure <= 0.0) return;
  exec.for_each(d.n, GasCrackPressure{gas.view(), gas.pressure, body}, "gas_crack_pressure");
}

}  // namespace breccia::solver
