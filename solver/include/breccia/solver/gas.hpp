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
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>
#include <utility>
#include <vector>

#include "breccia/solver/gas_law.hpp"
#include "breccia/solver/hd.hpp"
#include "breccia/solver/load_kernels.hpp"
#include "breccia/solver/pd_kernels.hpp"

namespace breccia::solver {

// Can the gas pass between the two ends of entry k? Only when no half-bond that exists is
// intact (a bond carrying no force: broken, or cut by a pre-crack). `halves`: per entry, the
// intact bits of the halves that exist (kOwnIntact: j in i's horizon, PdSystem::own_half_exists;
// kDualIntact: i in j's, k_dual > 0; setup_gas), so the test reads two bytes, not two doubles.
BRECCIA_HD bool gas_entry_open(const uint8_t* state, const uint8_t* halves, int64_t k) {
  return (state[k] & halves[k]) == 0;
}

// Device-side arrays of the gas (GasState below holds them on the host).
struct GasView {
  int load = -1;                   // index of the gas among the surface loads (FacetView::load)
  double* wall_dv = nullptr;       // per facet particle: -sum A n.u of its gas facets (frozen once it detaches)
  uint8_t* wall_on = nullptr;      // per facet particle: still on the wall (attached at the last update)
  double* wall_left = nullptr;     // per facet particle: the dV of this step's motion of one that left now
  double* arrival = nullptr;       // per particle: time the gas reached it (+inf: dry); null: no crack entry
  double* arrival_next = nullptr;  // the front pass writes here, then copies back
  // per particle: kappa_i = 2 d / sum_j V_j |xi| and V_i side by side (one cache line per
  // partner in the crack pass)
  const double* kappa_volume = nullptr;
  const double* vent_area = nullptr;  // per particle: its facet area on vent surfaces [m2] (0: none)
  const uint8_t* halves = nullptr; // per bond entry: the halves that exist (gas_entry_open)
  double* position = nullptr;      // 3 per particle: x0 + u at this update (one gather per partner)
  double* push = nullptr;          // 3 per particle: dV_crack/dy_i / V_i (the crack force is -p push)
  // Per particle, bits (not checkpointed: a restart starts at 0 and the first pass sets them
  // again): kGasFrontDone, wetted and every partner is too (the front stops pushing);
  // kGasCrackDone, debris whose entries have all left the volume (the crack pass skips it).
  uint8_t* front_done = nullptr;
  // Per bond entry: 1 once the entry is open with both ends wetted at an update, so that its
  // crack is in the gas's volume (for good: bonds do not heal and wetting is for good). The
  // entries so marked skip the open and wetted checks, and the work counts only their motion.
  // 2 once an end of the entry is debris (gas_debris_entry): its share is frozen in the volume.
  uint8_t* in_crack = nullptr;
  // Per particle (owned and ghosts): it keeps at least one intact bond (GasAttached, each
  // exact crack pass). A particle that has lost every bond is debris (gas_debris_entry).
  uint8_t* attached = nullptr;
  // The settled chunks of the crack pass (null: none, every pass picks every entry in full;
  // a distributed run's ranks, whose ghosts have no rows to mark from). row_mark, per
  // particle: 1 when the next crack pass has to pick the row's entries in full (set-up, a
  // restart; the particle or one of its partners reached by the front or become debris at
  // this pass: GasMarkNewlyWetted, GasAttached). chunk_live, per bond entry, at the first
  // entry of each chunk of kBondChunk entries of a row: the chunk's sum of the intact halves
  // (gas_chunk_live) at the last pass; it only falls, as halves break. Neither is
  // checkpointed (a restart marks every row).
  uint8_t* row_mark = nullptr;
  uint8_t* chunk_live = nullptr;
};

inline constexpr uint8_t kGasFrontDone = 1;
// A particle that has lost every bond, at a crack pass that has taken its entries out of the
// volume: every entry of its row is then out of the volume for good (0: never joins, its end
// being debris; 2: frozen), so its later passes add nothing but its vent flag and keep its
// push at the zero that pass wrote (GasCrackSum).
inline constexpr uint8_t kGasCrackDone = 2;

BRECCIA_HD bool gas_wetted(const GasView& g, int64_t i) { return g.arrival[i] < 1e300; }

// Row i's entries to be picked in full at the next crack pass (GasView::row_mark). Several
// threads may mark one row in a pass: the same byte, the same value.
BRECCIA_HD void gas_mark_row(uint8_t* row_mark, int64_t i) {
#if defined(__CUDA_ARCH__)
  row_mark[i] = 1;
#else
  std::atomic_ref<uint8_t>(row_mark[i]).store(1, std::memory_order_relaxed);
#endif
}

// Particle i's row and its partners' (the families are symmetric: j in i's iff i in j's).
BRECCIA_HD void gas_mark_row_and_partners(uint8_t* row_mark, const int64_t* offsets, const int32_t* neighbor,
                                          int64_t i) {
  gas_mark_row(row_mark, i);
  for (int64_t k = offsets[i]; k < offsets[i + 1]; ++k) gas_mark_row(row_mark, neighbor[k]);
}

// Sum over the entries [begin, end) of a chunk (at most kBondChunk) of the intact halves that
// exist (gas_entry_open's bits; at most 3 x 64, a byte): it falls whenever a half breaks
// (bonds do not heal), so an unchanged sum means no entry of the chunk has changed its state.
BRECCIA_HD uint8_t gas_chunk_live(const uint8_t* state, const uint8_t* halves, int64_t begin, int64_t end) {
  unsigned live = 0;
  for (int64_t k = begin; k < end; ++k) live += state[k] & halves[k];
  return static_cast<uint8_t>(live);
}
BRECCIA_HD bool gas_wetted_next(const GasView& g, int64_t i) { return g.arrival_next[i] < 1e300; }

// Is entry i -> j a debris entry: has either end lost every bond? A crack is the gap between
// two faces of the solid; a particle with no bond left is a loose grain, and its entries'
// openings measure how far it has flown, not a gap the gas fills (only openings count, so a
// grain moving through the solid would open volume without bound). Such an entry leaves the
// crack for good (bonds do not heal): its share is frozen in the volume at the pass that
// finds it (the gap it bounded then stays, around the grain), and it pushes neither end, as
// a wall particle that leaves the wall is no longer pushed (GasWallVolume, SurfaceLoads).
BRECCIA_HD bool gas_debris_entry(const GasView& g, int64_t i, int64_t j) { return !g.attached[i] || !g.attached[j]; }

// Whether particle i keeps at least one intact bond (GasView::attached).
struct GasAttached {
  PdView p;
  GasView g;
  BRECCIA_HD void operator()(int64_t i) const {
    // Bonds do not heal: a particle found detached stays so (its row is not read again).
    if (!g.attached[i] || particle_attached(p.offsets, p.state, i)) return;
    g.attached[i] = 0;
    // Its entries and its partners' entries to it leave the volume at this pass.
    if (g.row_mark) gas_mark_row_and_partners(g.row_mark, p.offsets, p.neighbor, i);
  }
};

// After the front, before the crack pass: the particles the front has just reached (wetted
// in arrival_next, not yet in arrival: the crack pass commits it) have their rows and their
// partners' picked in full (their entries may join the volume now).
struct GasMarkNewlyWetted {
  PdView p;
  GasView g;
  BRECCIA_HD void operator()(int64_t i) const {
    if (gas_wetted_next(g, i) && !gas_wetted(g, i)) gas_mark_row_and_partners(g.row_mark, p.offsets, p.neighbor, i);
  }
};

// Wall volume change of facet particle q: while the particle is attached its share follows
// its displacement; when it loses its last bond it leaves the wall and its share is frozen
// (the gas neither pushes it any more, SurfaceLoads, nor follows it). At the update it
// leaves, its force of the last update still acts in the step's work trapezoid over this
// step's displacement: wall_left keeps that displacement's dV for the gas work.
struct GasWallVolume {
  FacetView f;
  GasView g;
  const double* u;
  const int64_t* offsets;
  const uint8_t* state;
  BRECCIA_HD void operator()(int64_t q) const {
    const int64_t i = f.particle[q];
    const bool attached = particle_attached(offsets, state, i);
    g.wall_left[q] = 0.0;
    if (!attached && !g.wall_on[q]) return;
    double dv = 0.0;
    for (int64_t e = f.offsets[q]; e < f.offsets[q + 1]; ++e)
      if (f.load[e] == g.load)
        for (int d = 0; d < 3; ++d) dv -= f.area[e] * f.normal[3 * e + d] * u[3 * i + d];
    if (attached) {
      g.wall_dv[q] = dv;
    } else {  // leaves now
      g.wall_left[q] = dv - g.wall_dv[q];
      g.wall_on[q] = 0;
    }
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
// The same pass forms the crack pass's current positions (one pass over the particles, not two).
struct GasFrontCopy {
  GasView g;
  const double* x0;
  const double* u;
  BRECCIA_HD void operator()(int64_t i) const {
    g.arrival_next[i] = g.arrival[i];
    for (int d = 0; d < 3; ++d) g.position[3 * i + d] = x0[3 * i + d] + u[3 * i + d];
  }
};

// A wetted particle all of whose partners are wetted has nothing left to push (wetting is
// for good): it is marked once and skipped from then on.
// With the crack pass every k steps (crack_pass_every) the front runs at the exact passes only,
// one hop as every step: a step between passes is one where it would reach nothing
// (GasCrackChange forces the pass at any step where it would).
struct GasFront {
  PdView p;
  GasView g;
  double t, speed;
  BRECCIA_HD bool wet(int64_t j) const { return gas_wetted(g, j); }
  BRECCIA_HD void operator()(int64_t i) const {
    if (!wet(i) || (g.front_done[i] & kGasFrontDone)) return;
    const double arrival_i = g.arrival[i];
    bool dry_partner = false;
    for (int64_t k = p.offsets[i]; k < p.offsets[i + 1]; ++k) {
      if (g.in_crack[k]) continue;  // both ends wetted
      const bool open = gas_entry_open(p.state, g.halves, k);
      // A closed entry only tells whether a partner is still dry: once one is known, its
      // partner's arrival time (a read from anywhere in memory) is not needed.
      if (!open && dry_partner) continue;
      const int32_t j = p.neighbor[k];
      if (wet(j)) continue;
      dry_partner = true;
      if (!open) continue;
      const double reached = arrival_i + p.xi_len[k] / speed;
      if (reached <= t) atomic_min(&g.arrival_next[j], reached);
    }
    if (!dry_partner) g.front_done[i] |= kGasFrontDone;
  }
};

struct GasSums {
  double volume;         // m3
  double volume_before;  // m3, of the cracks that were in the volume at the last update
  double vents;          // crack-wetted particles on a vent surface
  double vent_area;      // m2, the cracks' mouths on the vent surfaces (opening x trace length)
  double joined;         // m3, -sum V_i a_k e_hat . du_i over the entries that joined this step
  double left;           // m3, the dV of this step's motion of the wall particles and crack entries that left it
  double frozen;         // m3, the shares of the entries that became debris entries now (gas_debris_entry)
};

BRECCIA_HD GasSums gas_sums_add(GasSums a, GasSums b) {
  return {a.volume + b.volume, a.volume_before + b.volume_before, a.vents + b.vents, a.vent_area + b.vent_area,
          a.joined + b.joined, a.left + b.left, a.frozen + b.frozen};
}

// Sum of the wall shares.
struct GasWallSum {
  using Value = GasSums;
  const double* wall_dv;
  const double* wall_left;
  BRECCIA_HD static Value identity() { return {0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0}; }
  BRECCIA_HD static Value combine(Value a, Value b) { return gas_sums_add(a, b); }
  BRECCIA_HD Value operator()(int64_t q) const { return {wall_dv[q], wall_dv[q], 0.0, 0.0, 0.0, wall_left[q], 0.0}; }
};

// Entry k of particle i (at x_i) in the current configuration: returns its opening
// |y| - |xi|, with the unit direction (ux, uy, uz) from i to j and a_k / V_i, the crack-face
// area over i's volume, a_k = (kappa_i + kappa_j)/2 V_i V_j. Branch-free, so that the host
// computes a chunk of entries at once (SIMD: the square root and divisions are its cost).
// (The arrays come as pointers, not in the GasView: a pointer read from a struct in memory
// inside the loop is one the vectoriser will not hoist past the stores of the terms.)
BRECCIA_HD double gas_entry_opening(const double* position, const double* kappa_volume, const int32_t* neighbor,
                                    const double* xi_len, double kappa_i, double xx, double xy, double xz, int64_t k,
                                    double& ux, double& uy, double& uz, double& a_over_vi) {
  const int64_t j = neighbor[k];
  const double dx = position[3 * j] - xx, dy = position[3 * j + 1] - xy, dz = position[3 * j + 2] - xz;
  const double len = std::sqrt(dx * dx + dy * dy + dz * dz);
  ux = len > 0 ? dx / len : 0.0;
  uy = len > 0 ? dy / len : 0.0;
  uz = len > 0 ? dz / len : 0.0;
  a_over_vi = 0.5 * (kappa_i + kappa_volume[2 * j]) * kappa_volume[2 * j + 1];
  return len - xi_len[k];
}

// The host crack pass's vectorised stage over one chunk of picked entries (GasCrackSum): each
// entry's opening e, direction u, a_k / V_i (gas_entry_opening) and, where open, its share
// a_k/V_i V_i e / 2 and push a_k/V_i u (+0 where closed). Compiled in gas.cpp for the portable
// target and for AVX2 (chosen at run time; no FMA, so the same roundings: square root,
// divisions and products are correctly rounded at any vector width), bit for bit the same.
struct GasChunkTerms {
  double e[kBondChunk], ux[kBondChunk], uy[kBondChunk], uz[kBondChunk], a[kBondChunk];
  double share[kBondChunk], px[kBondChunk], py[kBondChunk], pz[kBondChunk];
};
void gas_chunk_openings(const double* position, const double* kappa_volume, const int32_t* neighbor,
                        const double* xi_len, const int32_t* pick, int count, double kappa_i, double volume_i,
                        double xx, double xy, double xz, GasChunkTerms& out);

// Crack volume the gas fills (each pair seen from both ends, hence the half) with the front
// this step has reached (arrival_next). The entries already in the volume at the last update
// (in_crack) give volume_before: an entry that joins now (the front has just reached it, or
// its bond has just broken between wetted particles) is crack the gas spreads into, a free
// expansion that does no work on the solid. Its force starts now, and the step's work
// trapezoid counts half of it over this step's displacement (u_before: the displacement at
// the step's start; null outside a step): `joined` is that displacement's dV, so that the
// gas work counts the same. Whether the front stands on a vent surface: a wall particle
// (arrival 0) on a vent surface does not vent; the gas has to get there through a crack;
// and the crack's mouth there: a vent particle's crack volume over its own volume (the
// crack's volume density, opening x crack area per unit volume) times its facet area on the
// vent surface sums, over the surface, to opening x trace length (docs/theory.md). The same
// loop keeps each particle's dV_crack/dy_i (push), so that the crack forces need no second
// pass over the entries once the pressure is known.
//
// On the host each chunk of kBondChunk entries runs in three stages: pick the entries in the
// volume (in entry order; marking those that join), compute their openings (the stage the
// compiler vectorises: square root and divisions), then add their terms in entry order. The sums are therefore the
// one-entry-at-a-time loop's (the CUDA build's) bit for bit.
template <class UBefore>
struct GasCrackSum {
  using Value = GasSums;
  PdView p;
  GasView g;
  const UBefore* u_before;
  BRECCIA_HD static Value identity() { return {0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0}; }
  BRECCIA_HD static Value combine(Value a, Value b) { return gas_sums_add(a, b); }

  // One entry's terms of the sums, +0 where it adds nothing (closed: e <= 0), so that they are
  // formed branch-free. Adding +0 changes no sum: one that starts at +0 never becomes -0.
  struct Terms {
    double volume, volume_before, joined, left, frozen, density, push[3];
  };
  // What an entry is at this pass: in the volume since the last update, joined it now, or
  // left it now (an end became debris: gas_debris_entry).
  enum Mode : uint8_t { kKept = 0, kJoined = 1, kLeft = 2 };
  // Entry at opening e, direction u (i -> j), a_k / V_i, in `mode`. `moved` is minus the
  // first-order dV of the pair over i's motion this step (du), both halves (a_k e_hat . du_i).
  // An entry that leaves keeps its share in the volume (frozen: `frozen`), and its last force
  // acted over this step's motion (the trapezoid's first half): `left` is that motion's dV and
  // volume_before its share before it, so that the work counts it as the trapezoid does, as for
  // a wall particle that leaves the wall (GasWallVolume).
  BRECCIA_HD static Terms entry_terms(double e, double ux, double uy, double uz, double a_over_vi, uint8_t mode,
                                      double volume_i, const double du[3]) {
    const bool open = e > 0.0;
    const bool kept = mode == kKept, joined = mode == kJoined, left = mode == kLeft;
    const double share = a_over_vi * volume_i * e * 0.5;
    const double moved = volume_i * a_over_vi * (ux * du[0] + uy * du[1] + uz * du[2]);
    const double density = a_over_vi * e * 0.5;
    const double px = a_over_vi * ux, py = a_over_vi * uy, pz = a_over_vi * uz;
    const bool live = open & !left;
    return {open ? share : 0.0,
            open & kept ? share : (open & left ? share + moved : 0.0),
            open & joined ? moved : 0.0,
            open & left ? -moved : 0.0,
            open & left ? share : 0.0,
            live ? density : 0.0,
            {live ? px : 0.0, live ? py : 0.0, live ? pz : 0.0}};
  }
  // Particle i's running sums, added in entry order.
  struct Particle {
    Value v;
    double push[3], density;
    BRECCIA_HD void add(const Terms& t) {
      v.volume += t.volume;
      v.volume_before += t.volume_before;
      v.joined -= t.joined;
      v.left += t.left;
      v.frozen += t.frozen;
      density += t.density;
      for (int d = 0; d < 3; ++d) push[d] += t.push[d];
    }
  };

  // Entry k of i at this pass (Mode), or kNone: not in the volume (closed, a dry or debris
  // end, or frozen since an earlier pass). Marks the entries that join (1) or leave (2)
  // in in_crack; only i writes its entries.
  static constexpr uint8_t kNone = 3;
  BRECCIA_HD static uint8_t entry_mode(const GasView& g, const uint8_t* state, uint8_t* in_crack,
                                       const int32_t* neighbor, int64_t i, int64_t k) {
    // Branch-free but for the stores, which are rare: where the gas has broken up a block,
    // entries in the crack and intact ones alternate at random along a row, and a branch on
    // each would be mispredicted about every other entry. The partner's arrival and
    // attachment are read for every entry (the particles near i are in cache: Morton order).
    const uint8_t counted = in_crack[k];
    const int32_t j = neighbor[k];
    const bool debris = gas_debris_entry(g, i, j);
    const bool joins = (counted == 0) & gas_entry_open(state, g.halves, k) & gas_wetted_next(g, j) & !debris;
    const bool before = counted == 1;
    const bool leaves = before & debris;
    if (joins | leaves) in_crack[k] = uint8_t(counted + 1);  // 0 -> 1 (joins), 1 -> 2 (leaves)
    // The mode as arithmetic, not as the choice `before ? (leaves ? kLeft : kKept) : (joins ?
    // kJoined : kNone)`, which GCC compiles into a branch on `before`: on a pulverised block the
    // entries in the volume (1) and frozen (2) alternate at random along a row, and that branch
    // was mispredicted about every other entry.
    const uint8_t if_before = static_cast<uint8_t>(static_cast<uint8_t>(leaves) << 1);         // kKept 0, kLeft 2
    const uint8_t if_not = static_cast<uint8_t>(3 - (static_cast<uint8_t>(joins) << 1));       // kNone 3, kJoined 1
    const uint8_t mask = static_cast<uint8_t>(-static_cast<int>(before));
    static_assert(kKept == 0 && kJoined == 1 && kLeft == 2 && kNone == 3, "the arithmetic above");
    return static_cast<uint8_t>((if_before & mask) | (if_not & static_cast<uint8_t>(~mask)));
  }


  BRECCIA_HD Value operator()(int64_t i) const {
    // The front's commit: nothing in this pass reads `arrival`, only arrival_next.
    g.arrival[i] = g.arrival_next[i];
    if (!gas_wetted_next(g, i)) return identity();
    const bool vent = g.vent_area[i] > 0.0 && g.arrival_next[i] > 0.0;
    // Debris whose entries have all left the volume: its row would add only +0 terms.
    if (g.front_done[i] & kGasCrackDone) return {0.0, 0.0, vent ? 1.0 : 0.0, 0.0, 0.0, 0.0, 0.0};
    Particle s{{0.0, 0.0, vent ? 1.0 : 0.0, 0.0, 0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, 0.0};
    double du[3] = {0.0, 0.0, 0.0};
    if (u_before)
      for (int d = 0; d < 3; ++d) du[d] = p.u[3 * i + d] - double(u_before[3 * i + d]);
    // The arrays as locals: the in_crack byte stores would otherwise make the compiler reload
    // every pointer of the views after each one (a char store may alias anything).
    const GasView gv = g;
    const int32_t* neighbor = p.neighbor;
    const double* xi_len = p.xi_len;
    const uint8_t* state = p.state;
    uint8_t* in_crack = gv.in_crack;
    const double* position = gv.position;
    const double* kv = gv.kappa_volume;
    const double kappa_i = kv[2 * i], volume_i = kv[2 * i + 1];
    const double xx = position[3 * i], xy = position[3 * i + 1], xz = position[3 * i + 2];
    const int64_t begin = p.offsets[i], end = p.offsets[i + 1];
    // A settled chunk: none of its entries changed its state since the last pass, and neither
    // the particle nor a partner was reached by the front or became debris at this pass
    // (GasView::row_mark). Every input of entry_mode is then as it was at the last pass, where
    // each entry that could join or leave did (in_crack), so its entries in the volume (1) are
    // kept and the others (0, 2) are not in it: the pick reads in_crack alone and stores
    // nothing. The same modes, so the same sums bit for bit.
    const bool row_marked = !gv.row_mark || gv.row_mark[i];
    if (gv.row_mark) gv.row_mark[i] = 0;
    const auto chunk_settled = [&](int64_t base, int64_t stop) {
      if (!gv.chunk_live) return false;
      const uint8_t live = gas_chunk_live(state, gv.halves, base, stop);
      const bool same = !row_marked && gv.chunk_live[base] == live;
      gv.chunk_live[base] = live;
      return same;
    };
#if defined(__CUDA_ARCH__)
    for (int64_t base = begin; base < end; base += kBondChunk) {
      const int64_t stop = end - base < kBondChunk ? end : base + kBondChunk;
      const bool settled = chunk_settled(base, stop);
      for (int64_t k = base; k < stop; ++k) {
        const uint8_t mode = settled ? (in_crack[k] == 1 ? uint8_t(kKept) : uint8_t(kNone))
                                     : entry_mode(gv, state, in_crack, neighbor, i, k);
        if (mode == kNone) continue;
        double ux, uy, uz, a;
        const double e = gas_entry_opening(position, kv, neighbor, xi_len, kappa_i, xx, xy, xz, k, ux, uy, uz, a);
        s.add(entry_terms(e, ux, uy, uz, a, mode, volume_i, du));
      }
    }
#else
    int32_t pick[kBondChunk];
    uint8_t modes[kBondChunk];
    GasChunkTerms terms;
    const double *e = terms.e, *ux = terms.ux, *uy = terms.uy, *uz = terms.uz, *a = terms.a;
    const double *share = terms.share, *px = terms.px, *py = terms.py, *pz = terms.pz;
    for (int64_t base = begin; base < end; base += kBondChunk) {
      const int m = static_cast<int>(end - base < kBondChunk ? end - base : kBondChunk);
      int count = 0;  // branch-free (entry_mode): every entry is written, the count says which stay
      int changes = 0;  // entries that join or leave the volume now (most chunks: none)
      if (chunk_settled(base, base + m)) {
        const uint8_t* chunk_in_crack = in_crack + base;
        for (int q = 0; q < m; ++q) {
          pick[count] = q;
          count += chunk_in_crack[q] == 1;
        }
      } else {
        for (int q = 0; q < m; ++q) {
          const uint8_t mode = entry_mode(gv, state, in_crack, neighbor, i, base + q);
          pick[count] = q;
          modes[count] = mode;
          count += mode != kNone;
          changes += (mode == kJoined) | (mode == kLeft);
        }
      }
      // The openings and, for a kept entry, its nonzero terms (entry_terms' products, the same
      // operations in the same order): the vectorised stage.
      gas_chunk_openings(position, kv, neighbor + base, xi_len + base, pick, count, kappa_i, volume_i, xx, xy, xz,
                         terms);
      if (changes == 0) {
        // Every entry kept: its terms are share (volume and volume_before), push and, at a
        // vent, the density; joined, left and frozen are +0, which leave a sum as it is (one
        // that starts at +0 is never -0), and the density is read only at a vent. So these
        // sums are entry_terms' bit for bit.
        for (int c = 0; c < count; ++c) {
          s.v.volume += share[c];
          s.v.volume_before += share[c];
          s.push[0] += px[c];
          s.push[1] += py[c];
          s.push[2] += pz[c];
        }
        if (vent)
          for (int c = 0; c < count; ++c) s.density += e[c] > 0.0 ? a[c] * e[c] * 0.5 : 0.0;
      } else {
        for (int c = 0; c < count; ++c) s.add(entry_terms(e[c], ux[c], uy[c], uz[c], a[c], modes[c], volume_i, du));
      }
    }
#endif
    if (vent) s.v.vent_area = s.density * gv.vent_area[i];
    for (int d = 0; d < 3; ++d) gv.push[3 * i + d] = s.push[d];
    // Debris now: this pass has taken its entries out of the volume (entry_mode), for good.
    if (!gv.attached[i]) gv.front_done[i] |= kGasCrackDone;
    return s.v;
  }
};

// Between two crack passes (crack_pass_every > 1): the crack volume's change over this step
// to first order, dV = sum_i dV/dy_i . du_i = -sum_i V_i push_i . du_i, with the push vectors
// of the last pass; that is exactly the work the crack forces -p push_i do over the step
// (GasCrackPressure applies the same vectors), so the gas work and the external work stay
// together. The volume so followed drifts from the entries' exact openings at second order
// in the motion since the last pass; the next pass puts it back (the difference counted as a
// free expansion, like a joining entry: no work). O(particles), not O(entries).
template <class UBefore>
struct GasCrackDrift {
  using Value = GasSums;
  PdView p;
  GasView g;
  const UBefore* u_before;
  BRECCIA_HD static Value identity() { return {0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0}; }
  BRECCIA_HD static Value combine(Value a, Value b) { return gas_sums_add(a, b); }
  BRECCIA_HD Value operator()(int64_t i) const {
    if (!u_before || !gas_wetted(g, i)) return identity();
    double dot = 0.0;
    for (int d = 0; d < 3; ++d) dot += g.push[3 * i + d] * (p.u[3 * i + d] - double(u_before[3 * i + d]));
    const double dv = -g.kappa_volume[2 * i + 1] * dot;
    return {dv, dv, 0.0, 0.0, 0.0, 0.0, 0.0};
  }
};

// Between two crack passes (crack_pass_every > 1): would this step's exact pass change which
// entries are in the gas's volume? That is what the drift cannot follow: the front reaching a
// dry particle through an open entry (the front pass's own test, reached <= t), an entry
// opening between two wetted particles (a bond broken since the last pass: it joins), or a
// wetted particle that has lost its last bond (its entries in the volume leave it: debris).
// Any of these forces the exact pass at this step, so that the sparse passes find every
// change at the step the every-step passes do (found a step late, the first crack's gas
// entered late and the answer of a disc breaking into grains moved by 3-4%: docs/performance-log.md).
// The check reads bytes per entry of the wetted particles (state, halves, in_crack) and the
// partner's arrival only where an entry is open and not yet in the volume: no openings.
// A partner's attachment is the last pass's (GasAttached; it only goes from 1 to 0), so a
// stale one can only force a pass that finds nothing. Returns the count in `volume`.
struct GasCrackChange {
  using Value = GasSums;
  PdView p;
  GasView g;
  double t, speed;
  // crack_pass_new_crack: tolerance, once the gas is in cracks: only the front reaching a dry
  // particle forces the pass (a particle whose partners are all wetted is skipped), not the
  // entries that join or leave between wetted particles.
  bool front_only = false;
  BRECCIA_HD static Value identity() { return {0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0}; }
  BRECCIA_HD static Value combine(Value a, Value b) { return gas_sums_add(a, b); }
  BRECCIA_HD Value operator()(int64_t i) const {
    if (!gas_wetted(g, i) || (front_only && (g.front_done[i] & kGasFrontDone))) return identity();
    bool intact = false, in_volume = false, change = false;
    for (int64_t k = p.offsets[i]; k < p.offsets[i + 1]; ++k) {
      const uint8_t counted = g.in_crack[k];
      intact |= p.state[k] != 0;
      in_volume |= counted == 1;
      if (counted != 0 || !gas_entry_open(p.state, g.halves, k)) continue;
      const int32_t j = p.neighbor[k];
      if (gas_wetted(g, j) ? !front_only && !gas_debris_entry(g, i, j) : g.arrival[i] + p.xi_len[k] / speed <= t)
        change = true;
    }
    if (!front_only && !intact && g.attached[i] && in_volume) change = true;  // debris now (gas_debris_entry)
    return {change ? 1.0 : 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  }
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

// A sum over [0, n) in a fixed order whatever the thread count: fixed blocks of kGasBlock
// indices, each summed in index order, their sums then added in block order on the host
// (gas_fixed_order_sum). The blocks are dealt out in a scrambled order (block = c x stride
// mod blocks, stride coprime to the block count), so that the run of them a thread takes
// under a static schedule comes from all over the body and two threads share the reached
// particles evenly.
inline constexpr int64_t kGasBlock = 256;

inline int64_t gas_blocks(int64_t n) { return (n + kGasBlock - 1) / kGasBlock; }
// About 0.62 of the block count (the golden section spreads a run best), coprime to it.
inline int64_t gas_block_stride(int64_t blocks) {
  int64_t stride = (blocks * 5 + 4) / 8;
  auto gcd = [](int64_t a, int64_t b) { while (b) { const int64_t r = a % b; a = b; b = r; } return a; };
  while (stride > 1 && gcd(stride, blocks) != 1) --stride;
  return stride < 1 ? 1 : stride;
}

// f(i) over [0, n) by the same scrambled blocks (the front: balanced between threads).
template <class F>
struct GasBlocks {
  F f;
  int64_t n, blocks, stride;
  BRECCIA_HD void operator()(int64_t c) const {
    const int64_t b = (c * stride) % blocks;
    const int64_t end = (b + 1) * kGasBlock < n ? (b + 1) * kGasBlock : n;
    for (int64_t i = b * kGasBlock; i < end; ++i) f(i);
  }
};

template <class Load>
struct GasBlockSum {
  Load load;
  int64_t n, blocks, stride;
  typename Load::Value* sums;
  BRECCIA_HD void operator()(int64_t c) const {
    const int64_t b = (c * stride) % blocks;
    const int64_t end = (b + 1) * kGasBlock < n ? (b + 1) * kGasBlock : n;
    typename Load::Value acc = Load::identity();
    for (int64_t i = b * kGasBlock; i < end; ++i) acc = Load::combine(acc, load(i));
    sums[b] = acc;
  }
};

// The host's side of the gas: the arrays behind GasView and the scalars of its state.
struct GasState {
  bool active = false;
  int load = -1;                  // surface load index
  const LoadSpec* spec = nullptr;
  GasLaw law;
  double reference_volume = 0.0;  // V0 [m3]
  double vent_area = 0.0;         // [m2] fixed part: the mouth's (stemming open) or the case's
  bool vent_crack_opening = false;  // add the cracks' mouths on the vent surfaces (GasCrackSum)
  double crack_vent_area = 0.0;   // [m2] that part at the last update
  double reference_density = 0.0; // gas density in V0 with all its mass [kg/m3]
  double ambient = 0.0;           // [Pa]
  double fixed_front_speed = 0.0; // [m/s]; 0: the escape speed (gas_escape_speed)
  bool crack_entry = false;
  int crack_pass_every = 1;       // at most this many steps between exact crack passes (GasCrackDrift between)
  double crack_pass_tolerance = 1e-3;  // missed crack volume over V at a pass (gas_crack_pass_interval)
  bool crack_pass_new_crack_at_once = true;  // GasCrackChange forces a pass (crack_pass_new_crack: at_once)
  std::vector<double> wall_dv, arrival, arrival_next, kappa_volume, push, vent_facet_area;
  std::vector<uint8_t> front_done, in_crack, wall_on;
  std::vector<uint8_t> attached;  // per particle (GasView::attached; derived each pass, not checkpointed)
  std::vector<uint8_t> halves;    // per bond entry (gas_entry_open; set-up, not checkpointed)
  // GasView::row_mark (per particle) and chunk_live (per bond entry); set-up, not
  // checkpointed; empty on a distributed run's ranks: every entry picked in full
  std::vector<uint8_t> row_mark, chunk_live;
  std::vector<double> position;   // 3 per particle: the crack pass's x0 + u
  std::vector<GasSums> block_sums;  // gas_fixed_order_sum's per-block sums (setup_gas sizes it once)
  std::vector<double> wall_left;
  // evolving state (checkpointed with the particles')
  double volume = 0.0, wall_volume = 0.0, crack_volume = 0.0;
  double debris_volume = 0.0;     // [m3] the frozen shares of the debris entries, in crack_volume
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
  // crack_pass_every > 1: steps to the next exact crack pass (0: this step's), and whether one
  // has run (push holds its vectors; a restart restores them: outputs.cpp).
  // crack_pass_interval: the steps between passes now, adapted at each pass (gas_update).
  int crack_pass_countdown = 0;
  int crack_pass_interval = 1;
  bool crack_pass_done = false;
  double wall_s = 0.0;            // wall time spent in the gas's passes (not checkpointed)
  double cpu_s = 0.0;             // their process CPU time, all threads (robust to other load)

  GasView view() {
    GasView v;
    v.load = load;
    v.wall_dv = wall_dv.data();
    v.wall_on = wall_on.data();
    v.wall_left = wall_left.data();
    v.arrival = crack_entry ? arrival.data() : nullptr;
    v.arrival_next = crack_entry ? arrival_next.data() : nullptr;
    v.kappa_volume = kappa_volume.data();
    v.vent_area = vent_facet_area.data();
    v.halves = halves.data();
    v.position = position.data();
    v.push = push.data();
    v.front_done = front_done.data();
    v.in_crack = in_crack.data();
    v.attached = attached.data();
    v.row_mark = row_mark.empty() ? nullptr : row_mark.data();
    v.chunk_live = chunk_live.empty() ? nullptr : chunk_live.data();
    return v;
  }
  // The area the gas escapes through once vented [m2]: the fixed part and the cracks' mouths.
  double outflow_area() const { return vent_area + (vent_crack_opening ? crack_vent_area : 0.0); }
  // Speed of the gas front along open bonds now: the fixed one, or the speed of a gas
  // expanding into an empty channel (gas_escape_speed, gas_law.hpp).
  double front_speed() const;
  // The evolving scalars of `o`, the crack passes' schedule with them (a distributed run's
  // ranks each advance the same ones; the global system's writers read them from the rank's).
  void copy_scalars(const GasState& o) {
    volume = o.volume, wall_volume = o.wall_volume, crack_volume = o.crack_volume, crack_vent_area = o.crack_vent_area;
    debris_volume = o.debris_volume;
    pressure = o.pressure, pressure_abs = o.pressure_abs, mass_fraction = o.mass_fraction, work = o.work;
    vented = o.vented, vent_time = o.vent_time, peak_pressure = o.peak_pressure, spent = o.spent;
    wall_s = o.wall_s, cpu_s = o.cpu_s;
    crack_pass_countdown = o.crack_pass_countdown, crack_pass_interval = o.crack_pass_interval;
    crack_pass_done = o.crack_pass_done;
  }
  // One update of the scalars from the summed wall and crack volumes at time t (dt: the
  // step, 0 outside one: no outflow). crack.volume_before: the cracks that were in the volume
  // at the last update, at the current positions (the work counts only the motion's dV).
  void advance(double wall, const GasSums& crack, double t, double dt);
};

// Where a backend keeps the gas's per-step arrays (`view`) and the partial sums of
// gas_fixed_order_sum. The host sums each block of kGasBlock particles in one loop index,
// adding each particle's terms as it forms them (`particle_sums` null). A device, where one
// thread per block would leave most of it idle, forms each particle's terms in a thread of
// its own into `particle_sums` and then folds each block in index order (GasBlockFold): the
// same additions in the same order, so its sums are the host's bit for bit.
struct GasBuffers {
  GasView view;
  GasSums* block_sums = nullptr;     // at least gas_blocks(max(n, wall particles)) entries
  GasSums* particle_sums = nullptr;  // at least max(n, wall particles) entries; null: host's fused blocks
};

// The host's buffers: the GasState's own arrays (setup_gas sizes block_sums once).
inline GasBuffers host_gas_buffers(GasState& gas) { return {gas.view(), gas.block_sums.data(), nullptr}; }

// Particle i's terms of a sum, one index per particle (the device path of GasBuffers).
template <class Load>
struct GasParticleTerms {
  Load load;
  typename Load::Value* terms;
  BRECCIA_HD void operator()(int64_t i) const { terms[i] = load(i); }
};

// Block b's sum of the per-particle terms, in index order from the identity, as GasBlockSum adds them.
template <class Load>
struct GasBlockFold {
  const typename Load::Value* terms;
  int64_t n;
  typename Load::Value* sums;
  BRECCIA_HD void operator()(int64_t b) const {
    const int64_t end = (b + 1) * kGasBlock < n ? (b + 1) * kGasBlock : n;
    typename Load::Value acc = Load::identity();
    for (int64_t i = b * kGasBlock; i < end; ++i) acc = Load::combine(acc, terms[i]);
    sums[b] = acc;
  }
};

// What a gas sum runs over: the wall's facet particles (FacetView order) or the particles.
enum class GasSumOver : int { Facets, Particles };

// A distributed run's execution space (solver/mpi/) holds a rank's share of the particles
// and facet particles, and its ghosts; it declares `kGasRanks` and provides
//   exec.gas_ghosts(d, g)               the ghosts' displacement and attachment (g.attached)
//                                       from their owners; returns how many ghosts follow
//                                       the d.n owned particles
//   exec.gas_front_to_ghosts(g)         the front's arrival times: the smallest any rank
//                                       reached to the owner, then the owner's to its ghosts
//                                       (after each hop of the front: gas_update)
//   exec.gas_rank_terms(count)          a buffer for count per-item terms
//   exec.gas_sum_over_ranks(t, n, over) the sum of every rank's terms in one process's order
// (C++17 detection: nvcc compiles this header too.)
template <class Exec, class = void>
struct GasOnRanks : std::false_type {};
template <class Exec>
struct GasOnRanks<Exec, std::void_t<decltype(Exec::kGasRanks)>> : std::true_type {};

// The sum of load(i) over [0, n) in a fixed order (GasBlockSum, or GasParticleTerms and
// GasBlockFold): the same on any number of threads and on either path, so the gas's volume,
// and the motion it drives, do not depend on them. The block sums are read on the host
// (exec.gas_block_sums_on_host: the device copies them back) and added there in block order.
// On ranks each forms its items' terms and the execution space adds every rank's in the
// order one process adds them (the same blocks over the global index), so the sum is one
// process's bit for bit at any rank count.
template <class Exec, class Load>
GasSums gas_fixed_order_sum(Exec& exec, int64_t n, const Load& load, const GasBuffers& buffers, GasState& gas,
                            const char* name, GasSumOver over) {
  if constexpr (GasOnRanks<Exec>::value) {
    GasSums* terms = exec.gas_rank_terms(n);
    if (n > 0) exec.for_each(n, GasParticleTerms<Load>{load, terms}, name);
    return exec.gas_sum_over_ranks(terms, n, over);
  }
  (void)over;
  const int64_t blocks = gas_blocks(n);
  if (blocks == 0) return Load::identity();
  if (buffers.particle_sums) {
    exec.for_each(n, GasParticleTerms<Load>{load, buffers.particle_sums}, name);
    exec.for_each(blocks, GasBlockFold<Load>{buffers.particle_sums, n, buffers.block_sums}, name);
  } else {
    exec.for_each(blocks, GasBlockSum<Load>{load, n, blocks, gas_block_stride(blocks), buffers.block_sums}, name);
  }
  const GasSums* sums = exec.gas_block_sums_on_host(gas, buffers.block_sums, blocks);
  GasSums total = Load::identity();
  for (int64_t b = 0; b < blocks; ++b) total = Load::combine(total, sums[b]);
  return total;
}

// The next interval between crack passes (crack_pass_every > 1) from what this pass found:
// `missed`, the crack volume the drift did not follow since the last pass (cracks the gas
// entered, entries that opened between wetted particles, the second-order drift), against
// the cavity's volume. Applied at once at the pass, it moves the pressure by about
// gamma missed / V: a tolerance of 1e-3 (crack_pass_tolerance, the default) keeps that
// below 0.3% (gamma 3) per pass. Above the tolerance the interval halves (down to 1: every
// step), well below it (a quarter) it doubles (up to `every`).
inline int gas_crack_pass_interval(int interval, int every, double missed, double volume, double tolerance) {
  const double share = std::fabs(missed) / std::max(volume, 1e-300);
  if (share > tolerance) return interval / 2 > 1 ? interval / 2 : 1;
  if (share < 0.25 * tolerance) return interval * 2 < every ? interval * 2 : every;
  return interval;
}

// The gas at time t on the double arrays `d` (after the drift): front, volume, pressure.
// u_before: the displacement at the step's start (null outside a step). The arrays are where
// the backend keeps them (exec.gas_buffers: the host's GasState, or device copies).
template <class Exec, class UBefore>
void gas_update(Exec& exec, const PdView& d, const FacetView& f, GasState& gas, double t, double dt,
                const UBefore* u_before) {
  if (gas.spent) return;
  const GasBuffers buffers = exec.gas_buffers(gas);
  const GasView& g = buffers.view;
  exec.for_each(f.particle_count, GasWallVolume{f, g, d.u, d.offsets, d.state}, "gas_wall_volume");
  GasSums crack{};
  const GasSums wall = gas_fixed_order_sum(exec, f.particle_count, GasWallSum{g.wall_dv, g.wall_left}, buffers, gas,
                                           "gas wall volume", GasSumOver::Facets);
  if (g.arrival) {
    // crack_pass_every k > 1: the exact pass every crack_pass_interval steps (and at the first
    // call; a call outside a step, dt 0, moves nothing and keeps the count), GasCrackDrift in
    // between. The interval adapts (gas_crack_pass_interval): 1 while the passes find the
    // gas spreading into new crack, up to k while the crack it fills only moves.
    const int every = gas.crack_pass_every;
    bool exact = every <= 1 || !gas.crack_pass_done || (dt > 0.0 && gas.crack_pass_countdown == 0);
    // crack_pass_new_crack: tolerance keeps only the front's part of the check once the gas is
    // in cracks; until then all of it, so that the first crack is found at the step it opens (a
    // pass that finds nothing missed doubles the interval, and a first crack found late let a
    // disc breaking into grains miss 4% of the work: docs/performance-log.md). The front itself
    // takes one hop per pass, so a front held back for k steps would lag (measured: at 20 MPa
    // on the quick concrete block, 41% less gas work without the front's check).
    const bool front_only = !gas.crack_pass_new_crack_at_once && gas.crack_volume > 0.0;
    if (!exact && dt > 0.0)
      exact = gas_fixed_order_sum(exec, d.n, GasCrackChange{d, g, t, gas.front_speed(), front_only}, buffers, gas,
                                  "gas crack change", GasSumOver::Particles)
                  .volume > 0.0;
    if (every > 1 && dt > 0.0 && !exact) --gas.crack_pass_countdown;
    if (exact) {
      // The step's motion along the vectors its forces had (the last pass's): the work.
      const double moved = every > 1 && gas.crack_pass_done
                               ? gas_fixed_order_sum(exec, d.n, GasCrackDrift<UBefore>{d, g, u_before}, buffers, gas,
                                                     "gas crack drift", GasSumOver::Particles)
                                     .volume
                               : 0.0;
      // Which particles are debris now (gas_debris_entry), before the crack pass reads them.
      exec.for_each(d.n, GasAttached{d, g}, "gas_attached");
      // On ranks the front and the crack pass read the ghosts' positions, arrival times and
      // attachment too.
      int64_t ghosts = 0;
      if constexpr (GasOnRanks<Exec>::value) ghosts = exec.gas_ghosts(d, g);
      exec.for_each(d.n + ghosts, GasFrontCopy{g, d.x0, d.u}, "gas_front_copy");
      GasFront front{d, g, t, gas.front_speed()};
      // The front's minima do not depend on the order: a device takes a thread per particle,
      // the host the scrambled blocks (balanced between its few threads).
      const int64_t blocks = gas_blocks(d.n);
      if (buffers.particle_sums)
        exec.for_each(d.n, front, "gas_front");
      else
        exec.for_each(blocks, GasBlocks<GasFront>{front, d.n, blocks, gas_block_stride(blocks)}, "gas_front");
      // A ghost reached here is reached on its owner's rank too; a minimum, so exact.
      if constexpr (GasOnRanks<Exec>::value) exec.gas_front_to_ghosts(g);
      // The rows the crack pass has to pick in full because the front reached them or a partner.
      if (g.row_mark) exec.for_each(d.n, GasMarkNewlyWetted{d, g}, "gas_mark_wetted");
      crack = gas_fixed_order_sum(exec, d.n, GasCrackSum<UBefore>{d, g, u_before}, buffers, gas, "gas crack volume",
                                  GasSumOver::Particles);
      // The debris entries' frozen shares stay in the volume; those frozen now join them.
      crack.volume += gas.debris_volume;
      crack.volume_before += gas.debris_volume;
      gas.debris_volume += crack.frozen;
      // The old entries' volume at the current positions less the volume followed so far is
      // the drift since the last pass: put back without work (the forces never did it). The
      // drift followed the entries that left now along their old push: their step's motion,
      // which `left` counts.
      if (every > 1 && gas.crack_pass_done) {
        // The drift's own error (second order in the motion since the last pass): the old
        // entries' exact volume less the volume followed. New crack is not a miss: the pass
        // comes at the step it joins (GasCrackChange), as it does every step.
        const double drift_error = crack.volume_before - (gas.crack_volume + moved - crack.left);
        // With crack_pass_new_crack: tolerance no check forces the pass where the gas enters
        // new crack: what joined the volume at this pass (less the entries that left's
        // first-order motion) was missed since the last one, and counts with the drift's error.
        const double new_crack = gas.crack_pass_new_crack_at_once ? 0.0 : crack.volume - crack.volume_before;
        crack.volume_before = gas.crack_volume + moved - crack.left;
        // The step's work trapezoid takes the forces at its start along the old push vectors
        // and at its end along this pass's: 1/2 p_old dV(old push) + 1/2 p_new dV(new push).
        // GasState::advance counts 1/2 (p_old + p_new) (moved - left) + 1/2 p_new joined +
        // 1/2 p_old left, so `joined` becomes the new push's dV less the old's (kept entries
        // turned, entries joined): the gas work stays the work of its forces at a pass too.
        // (Every step, the kept entries' exact dV is already the secant of the two pushes.)
        if (u_before) {
          const double moved_new = gas_fixed_order_sum(exec, d.n, GasCrackDrift<UBefore>{d, g, u_before}, buffers, gas,
                                                       "gas crack drift", GasSumOver::Particles)
                                       .volume;
          crack.joined = moved_new - (moved - crack.left);
        }
        if (dt > 0.0) {
          gas.crack_pass_interval =
              gas_crack_pass_interval(gas.crack_pass_interval, every, std::fabs(drift_error) + std::fabs(new_crack),
                                      gas.volume, gas.crack_pass_tolerance);
          gas.crack_pass_countdown = gas.crack_pass_interval - 1;
        }
      }
      gas.crack_pass_done = true;
    } else {
      crack = gas_fixed_order_sum(exec, d.n, GasCrackDrift<UBefore>{d, g, u_before}, buffers, gas, "gas crack drift",
                                  GasSumOver::Particles);
      crack.volume += gas.crack_volume;
      crack.volume_before += gas.crack_volume;
      crack.vent_area = gas.crack_vent_area;
    }
  }
  crack.left += wall.left;
  gas.advance(wall.volume, crack, t, dt);
}

// The gas's pressure on the crack faces it fills, added to `body` (after the surface loads).
template <class Exec>
void gas_crack_forces(Exec& exec, const PdView& d, GasState& gas, double* body) {
  if (!gas.crack_entry || gas.pressure <= 0.0) return;
  exec.for_each(d.n, GasCrackPressure{exec.gas_buffers(gas).view, gas.pressure, body}, "gas_crack_pressure");
}

}  // namespace breccia::solver
