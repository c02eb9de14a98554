#include "breccia/solver/boundary_field.hpp"
#include "breccia/solver/rank_system.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "breccia/common/error.hpp"
#include "breccia/solver/correspondence_kernels.hpp"
#include "breccia/solver/distributed_setup.hpp"

namespace breccia::solver {
namespace {

// The rank's particles (owned, then ghosts) in the system they are cut from: `global` their
// internal indices, `held` their indices in the system's own arrays (a window system's local
// ones, PdSystem::window_global; else the same). An array is read by its length: the system's
// n (its own arrays), the whole body's (a restart's on rank 0 with a serial HDF5), or the
// rank's owned particles' (a distributed restart's: read_checkpoint).
struct RankIds {
  std::vector<int32_t> global, held;
  size_t n = 0, whole = 0, owned = 0;
  size_t size() const { return global.size(); }
};

// Rows `ids` of a per-particle array of `width` values each; an array that is not held
// (empty: the feature is off) stays empty. An array of the owned rows alone gives them and
// zeros for the ghosts, whose values the time loop's backend then takes from their owners
// (its halo exchange, mpi_backend.cpp).
template <class T>
std::vector<T> take(const std::vector<T>& global, const RankIds& r, size_t width) {
  if (global.empty()) return {};
  const std::vector<int32_t>* ids = global.size() == width * r.n ? &r.held : global.size() == width * r.whole ? &r.global : nullptr;
  if (!ids && global.size() == width * r.owned) {
    std::vector<T> out(width * r.size(), T{});
    std::copy(global.begin(), global.end(), out.begin());
    return out;
  }
  if (!ids) throw std::logic_error("restrict_to_rank: a per-particle array of unexpected size");
  std::vector<T> out(width * ids->size());
  for (size_t q = 0; q < ids->size(); ++q)
    std::copy_n(global.begin() + static_cast<int64_t>(width) * (*ids)[q], width, out.begin() + static_cast<int64_t>(width * q));
  return out;
}

// A state array a distributed set-up's ranks other than 0 do not hold in their global system
// (docs/parallel.md, Memory): `a` and `body`, zero at set-up, are never allocated there
// (setup_system); `u` and `v` are let go once the stable-step estimate's cut took them into
// the rank's system (mpi_stable_step_forces). The rank's system then keeps its own values (nothing
// between that cut and the loop's backend changes them), or, cut afresh, starts from zeros
// where the set-up's values are zeros (`zero_at_setup`). A held global array (one process,
// rank 0, a restart's read): its rows, as take.
template <class T>
void take_or_keep(std::vector<T>& local, const std::vector<T>& global, const RankIds& ids, size_t width,
                  bool zero_at_setup) {
  if (!global.empty() || ids.whole == 0) {
    local = take(global, ids, width);
    return;
  }
  const size_t rows = width * ids.size();
  if (local.size() == rows) return;
  if (!zero_at_setup)
    throw std::logic_error("copy_rank_state: a state array held by neither the global system nor the rank's");
  local.assign(rows, T{});
}

// take_or_keep for a field only some models hold (LPS's fast-path factors, correspondence's
// tensors): held by neither system, it stays empty (the model has none); the rank's own, of
// its particles' size, is kept where the global system let it go (mpi_stable_step_forces).
template <class T>
void take_or_keep_if_held(std::vector<T>& local, const std::vector<T>& global, const RankIds& ids, size_t width) {
  if (!global.empty() || ids.whole == 0 || local.empty()) {
    local = take(global, ids, width);
    return;
  }
  if (local.size() != width * ids.size())
    throw std::logic_error("copy_rank_state: a field the rank's system holds for other particles");
}

// Entries [b, e) of a per-entry array; empty stays empty.
template <class T, class A>
std::vector<T, A> slice(const std::vector<T, A>& global, int64_t b, int64_t e) {
  if (global.empty()) return {};
  return std::vector<T, A>(global.begin() + b, global.begin() + e);
}

// A rank's rows [eb, ee) of a global per-entry state array (the bond states, a gas load's
// entered cracks), which the global system holds whole (one process's set-up, rank 0's
// staging: its slice), or as this rank's rows alone (a distributed restart's read_checkpoint:
// a copy), or not at all: then `mine`, the rank's system's own rows, is already the state
// and stays.
template <class T, class A>
void take_entry_rows(std::vector<T, A>& mine, const std::vector<T, A>& global, size_t entries, int64_t eb, int64_t ee) {
  if (global.empty()) return;
  mine = global.size() == entries ? slice(global, eb, ee) : global;
}

}  // namespace

int64_t RankLayout::local_index(int64_t j) const {
  if (j >= begin() && j < begin() + owned()) return j - begin();
  const auto it = std::lower_bound(halo.ghosts.begin(), halo.ghosts.end(), static_cast<int32_t>(j));
  if (it == halo.ghosts.end() || *it != j) return -1;
  return owned() + (it - halo.ghosts.begin());
}

RankLayout rank_layout(const PdSystem& g, int ranks, int rank) {
  RankLayout L;
  try {
    // A distributed set-up cut the partition before its families existed (its global
    // system holds this rank's rows only): the same cut, from the same family sizes.
    if (!g.distributed_rows.empty() && static_cast<int>(g.distributed_rows.size()) == ranks + 1)
      L.part.begin = g.distributed_rows;
    else
      L.part = MortonRangePartitioner().partition(g.offsets, ranks);
  } catch (const std::invalid_argument& e) {
    throw InputError(g.config.file, "mpirun -np", e.what(), "at most one rank per particle");
  }
  L.rank = rank;
  L.halo = build_halo(L.part, rank, g.offsets, g.neighbor, g.window_global.empty() ? nullptr : &g.window_global);
  return L;
}

namespace {
void restrict_gas(PdSystem& s, const PdSystem& g, const RankLayout& L, const RankIds& ids);
}  // namespace

int64_t first_facet_of(const PdSystem& g, int64_t particle) {
  const std::vector<int32_t>& fp = g.facets.particle;  // ascending (group_facets_by_particle), the system's indices
  return std::lower_bound(fp.begin(), fp.end(), static_cast<int32_t>(g.system_index(particle))) - fp.begin();
}

namespace {

// Local index -> global internal index: owned, then ghosts.
std::vector<int32_t> local_to_global(const RankLayout& L) {
  const int64_t b = L.begin(), owned = L.owned();
  std::vector<int32_t> ids(static_cast<size_t>(owned) + L.halo.ghosts.size());
  for (int64_t i = 0; i < owned; ++i) ids[i] = static_cast<int32_t>(b + i);
  std::copy(L.halo.ghosts.begin(), L.halo.ghosts.end(), ids.begin() + owned);
  return ids;
}

// local_to_global, with each particle's index in g's own arrays (RankIds).
RankIds rank_ids(const PdSystem& g, const RankLayout& L) {
  RankIds r;
  r.global = local_to_global(L);
  r.n = g.n;
  r.whole = g.whole_n();
  r.owned = static_cast<size_t>(L.owned());
  if (g.window_global.empty()) {
    r.held = r.global;
    return r;
  }
  r.held.resize(r.global.size());
  for (size_t q = 0; q < r.global.size(); ++q) {
    const int64_t k = g.system_index(r.global[q]);
    if (k >= static_cast<int64_t>(g.n) || g.window_global[static_cast<size_t>(k)] != r.global[q])
      throw std::logic_error("restrict_to_rank: particle " + std::to_string(r.global[q]) +
                             " of the rank's system is outside its window system");
    r.held[q] = static_cast<int32_t>(k);
  }
  return r;
}

// The row of g.offsets of the whole body's internal row i: a window system's set-up offsets
// are its own (n + 1, local rows); the whole row offsets (finish_distributed_setup) global.
int64_t offsets_row(const PdSystem& g, int64_t i) {
  return g.offsets.size() == g.n + 1 ? g.system_index(i) : i;
}

// The entries [first, end) of the rank's rows in g's per-entry numbering: from g's row
// offsets, or, where a finished distributed set-up left none (the ranks other than 0),
// from its entry ranges.
std::pair<int64_t, int64_t> rank_entries(const PdSystem& g, const RankLayout& L) {
  if (g.offsets.empty() && !g.distributed_entries.empty())
    return {g.distributed_entries[L.rank], g.distributed_entries[L.rank + 1]};
  const int64_t rb = offsets_row(g, L.begin());
  return {g.offsets[rb], g.offsets[rb + L.owned()]};
}

// restrict_to_rank; `partners`: the owned rows' partners, renumbered to local indices in
// place and kept (restrict_to_rank_taking_bonds), or null: copied from g's and renumbered.
// `s`: the arrays already taken (take_releasing), which stay where the global system let them go.
PdSystem restrict_rank(const PdSystem& g, const RankLayout& L, std::vector<int32_t>* partners, PdSystem s = {}) {
  s.config = g.config;
  s.dimension = g.dimension;
  s.thickness = g.thickness;
  const int64_t b = L.begin(), owned = L.owned();
  s.n = static_cast<size_t>(owned);
  const RankIds ids = rank_ids(g, L);
  // What the set-up fixes before its stable-step estimate: geometry, materials, families and
  // their coefficients, loads and constraints. The state follows (copy_rank_state).
  s.original_index = take(g.original_index, ids, 1);
  // The reference arrays: a distributed set-up's ranks other than 0 let go of the whole ones as
  // the cut takes them (take_releasing): the rank's rows taken then stay.
  take_or_keep_if_held(s.x0, g.x0, ids, 3);
  take_or_keep_if_held(s.volume, g.volume, ids, 1);
  take_or_keep_if_held(s.density, g.density, ids, 1);
  take_or_keep_if_held(s.horizon, g.horizon, ids, 1);
  take_or_keep_if_held(s.half_cell, g.half_cell, ids, 1);
  take_or_keep_if_held(s.material, g.material, ids, 1);
  take_or_keep_if_held(s.fixed_dof, g.fixed_dof, ids, 1);
  take_or_keep_if_held(s.weighted_volume, g.weighted_volume, ids, 1);
  take_or_keep_if_held(s.lps, g.lps, ids, 1);
  take_or_keep_if_held(s.calibration_factor, g.calibration_factor, ids, 1);
  take_or_keep_if_held(s.corr_moduli, g.corr_moduli, ids, kCorrModuli);
  take_or_keep_if_held(s.short_range_k, g.short_range_k, ids, 1);
  take_or_keep_if_held(s.spacing, g.spacing, ids, 1);
  s.family_volume = take(g.family_volume, ids, 1);  // the owned rows' (a distributed set-up's own)

  // The owned rows, partners renumbered (ghosts are sorted: a binary search each; a window
  // system's partners are its local indices: their internal ones first).
  const int64_t rb = offsets_row(g, b);
  const int64_t eb = g.offsets[rb], ee = g.offsets[rb + owned];
  s.offsets.resize(static_cast<size_t>(owned) + 1);
  for (int64_t i = 0; i <= owned; ++i) s.offsets[i] = g.offsets[rb + i] - eb;
  const std::vector<int32_t>& wg = g.window_global;
  auto internal = [&](int32_t j) { return wg.empty() ? j : wg[static_cast<size_t>(j)]; };
  if (partners) {
    for (int32_t& j : *partners) j = static_cast<int32_t>(L.local_index(internal(j)));
    s.neighbor = std::move(*partners);
  } else {
    s.neighbor.resize(static_cast<size_t>(ee - eb));
    for (int64_t k = eb; k < ee; ++k) s.neighbor[k - eb] = static_cast<int32_t>(L.local_index(internal(g.neighbor[k])));
  }
  s.xi_len = slice(g.xi_len, eb, ee);
  s.k_own = slice(g.k_own, eb, ee);
  s.k_dual = slice(g.k_dual, eb, ee);
  s.vol_own = slice(g.vol_own, eb, ee);
  s.own_count = slice(g.own_count, eb, ee);
  s.s0_own = slice(g.s0_own, eb, ee);
  s.s0_dual = slice(g.s0_dual, eb, ee);
  s.s_onset = slice(g.s_onset, eb, ee);
  s.contact_cell_edge = g.contact_cell_edge;
  s.symmetric_halves = g.symmetric_halves;
  s.dual_halves_shared = g.dual_halves_shared;

  // Loads and constraints on the owned particles, in the global lists' order (g's indices:
  // a window system's lists hold its window's particles, local).
  const int64_t lb = g.system_index(b);
  auto owned_local = [&](const std::vector<int32_t>& list) {
    std::vector<int32_t> out;
    for (const int32_t i : list)
      if (i >= lb && i < lb + owned) out.push_back(static_cast<int32_t>(i - lb));
    return out;
  };
  for (const auto& sl : g.surface_loads) {
    PdSystem::SurfaceLoad l{sl.spec, {}};
    for (PressureFacet f : sl.facets)
      if (f.particle >= lb && f.particle < lb + owned) {
        f.particle = static_cast<int32_t>(f.particle - lb);
        l.facets.push_back(f);
      }
    s.surface_loads.push_back(std::move(l));
  }
  s.facets = group_facets_by_particle(s);
  for (const auto& bl : g.body_loads)  // every particle: every owned one here
    s.body_loads.push_back({bl.spec, bl.every_particle ? std::vector<int32_t>{} : owned_local(bl.particles), bl.every_particle});
  for (const auto& c : g.constraints) {
    PdSystem::Constraint rc{c.spec, owned_local(c.particles), nullptr, {}, 0.0};
    attach_boundary_field(rc, c.field);  // values follow the rank's own particles
    s.constraints.push_back(std::move(rc));
  }
  copy_rank_state(s, g, L);
  return s;
}

}  // namespace

PdSystem restrict_to_rank(const PdSystem& g, const RankLayout& L) { return restrict_rank(g, L, nullptr); }

namespace {
// The arrays a distributed set-up's ranks other than 0 let go of in their global system `g`
// at the stable step's cut (release_global_at_stable_step; docs/parallel.md, Memory), each
// with the same array of the rank's system `s` and its values per particle: f(mine, global,
// width), `mine` null where no rank's system is given. Width 0: the rank's system takes none
// of it (only the global system's own passes read it: the general LPS loop's factors, the
// front's next arrival times). One list for the cut (take_releasing) and the release, so the
// two let go of the same arrays. The gas's arrays are empty without a gas load.
template <class F>
void for_each_released_at_stable_step(PdSystem* s, PdSystem& g, F&& f) {
  auto one = [&](auto member, size_t width) { f(s ? &(s->*member) : nullptr, g.*member, width); };
  auto gas = [&](auto member, size_t width) { f(s ? &(s->gas.*member) : nullptr, g.gas.*member, width); };
  // The displacements and velocities, the forces and the fields the estimate's last pass
  // fills (kForcePassFields), LPS's weighted volume.
  one(&PdSystem::u, 3);
  one(&PdSystem::v, 3);
  one(&PdSystem::force, 3);
  for (const auto& [field, width] : kForcePassFields) one(field, static_cast<size_t>(width));
  one(&PdSystem::weighted_volume, 1);
  // The reference arrays, which every family build read for a partner anywhere: the estimate
  // reads its own particles' from the rank's system (StableStepRanks::system), the largest
  // cell and the stiff region's scale over the ranks; rank 0 keeps them whole (its writers:
  // the probes, the instability message, the indenter, results.h5).
  one(&PdSystem::x0, 3);
  one(&PdSystem::volume, 1);
  one(&PdSystem::density, 1);
  one(&PdSystem::horizon, 1);
  one(&PdSystem::half_cell, 1);
  one(&PdSystem::material, 1);
  // The set-up values the estimate does not read: the calibration factors, the constrained
  // components, LPS's coefficients, correspondence's moduli, the short-range forces'
  // constants; and the general LPS loop's factors, which only the global system's own force
  // passes (the start-up checks) used.
  one(&PdSystem::calibration_factor, 1);
  one(&PdSystem::fixed_dof, 1);
  one(&PdSystem::lps, 1);
  one(&PdSystem::lps_factors, 0);
  one(&PdSystem::corr_moduli, kCorrModuli);
  one(&PdSystem::short_range_k, 1);
  one(&PdSystem::spacing, 1);
  // A gas load's per-particle arrays: the crack faces' factors and the vent areas, its front
  // (arrival times, their next copy, the pushes), the crack pass's positions and marks.
  gas(&GasState::kappa_volume, 2);
  gas(&GasState::vent_facet_area, 1);
  gas(&GasState::arrival, 1);
  gas(&GasState::arrival_next, 0);
  gas(&GasState::push, 3);
  gas(&GasState::position, 3);
  gas(&GasState::front_done, 1);
  gas(&GasState::attached, 1);
}

// The rank's rows (owned, then ghosts) of each array release_global_at_stable_step lets go
// of, into `s`, each global array freed as soon as its rows are copied.
void take_releasing(PdSystem& s, PdSystem& g, const RankLayout& L) {
  const RankIds ids = rank_ids(g, L);
  for_each_released_at_stable_step(&s, g, [&](auto* mine, auto& global, size_t width) {
    if (width > 0) *mine = take(global, ids, width);
    std::remove_reference_t<decltype(global)>().swap(global);
  });
}
}  // namespace

PdSystem restrict_to_rank_taking_bonds(PdSystem& g, const RankLayout& L) {
  const auto [eb, ee] = rank_entries(g, L);
  if (g.distributed_rows.empty() || eb != 0 || ee != static_cast<int64_t>(g.neighbor.size())) return restrict_to_rank(g, L);
  // The slices restrict_to_rank would copy are the whole arrays: take them, and restrict the
  // rest (an empty array slices as empty).
  std::vector<double> xi_len, k_own, k_dual, vol_own;
  std::vector<uint8_t> own_count;
  std::vector<float> s0_own, s0_dual, s_onset;
  std::vector<uint8_t> gas_halves;  // set-up data of the bonds; in_crack is state (restrict_gas)
  gas_halves.swap(g.gas.halves);
  xi_len.swap(g.xi_len);
  // Shared dual halves (pd_system.hpp k_dual_halves): the writers' dual moduli are the own ones.
  if (g.dual_halves_shared && root_gathers_bond_list(g.config)) k_own = g.k_own;
  else k_own.swap(g.k_own);
  s0_own.swap(g.s0_own);
  s0_dual.swap(g.s0_dual);
  // Under a rate law the onsets are state (raised as bonds begin to soften): the global
  // system keeps them, gathered whole on rank 0 (finish_distributed_setup) for its files.
  if (g.config.strength_rate != StrengthRateLaw::None) s_onset = g.s_onset;
  else s_onset.swap(g.s_onset);
  if (root_gathers_bond_list(g.config)) {  // rank 0's writers read them (finish_distributed_setup)
    k_dual = g.k_dual;  // empty where shared: g keeps k_own instead (above)
    vol_own = g.vol_own;
    own_count = g.own_count;
  } else {
    k_dual.swap(g.k_dual);
    vol_own.swap(g.vol_own);
    own_count.swap(g.own_count);
  }
  // The partners too, renumbered in place (a copy was 4 B per entry more at the peak), unless
  // rank 0's writers read the global ones (root_gathers_bond_list: then copied).
  std::vector<int32_t> partners;
  if (root_gathers_bond_list(g.config)) partners = g.neighbor;
  else partners.swap(g.neighbor);
  // The ranks other than 0 let go of the arrays release_global_at_stable_step names as each is
  // taken, before the rest is cut: the whole array and the rank's rows of it are not held
  // side by side for all of them at once (the cut's growth was the stable step's peak).
  PdSystem taken;
  if (!(L.rank == 0 && root_stages_whole_body())) take_releasing(taken, g, L);
  PdSystem s = restrict_rank(g, L, &partners, std::move(taken));
  s.xi_len = std::move(xi_len);
  s.k_own = std::move(k_own);
  s.k_dual = std::move(k_dual);
  s.vol_own = std::move(vol_own);
  s.own_count = std::move(own_count);
  s.s0_own = std::move(s0_own);
  s.s0_dual = std::move(s0_dual);
  s.s_onset = std::move(s_onset);
  s.gas.halves = std::move(gas_halves);
  return s;
}

void copy_rank_state(PdSystem& s, const PdSystem& g, const RankLayout& L) {
  const RankIds ids = rank_ids(g, L);
  s.config = g.config;  // the stable-step estimate turns fracture off in its copy
  take_or_keep(s.u, g.u, ids, 3, false);
  take_or_keep(s.v, g.v, ids, 3, false);
  take_or_keep(s.a, g.a, ids, 3, true);
  take_or_keep(s.force, g.force, ids, 3, false);
  take_or_keep(s.body, g.body, ids, 3, true);
  s.x = g.x.size() == 3 * ids.n || g.x.size() == 3 * ids.whole ? take(g.x, ids, 3) : std::vector<double>{};
  // The fields the set-up's last force pass fills (kForcePassFields): a distributed set-up's
  // ranks other than 0 hold them in the rank's system only (mpi_stable_step_forces). Those
  // every model has must be held by one of the two; the model's own (LPS's factors,
  // correspondence's tensors) may be held by neither (the model has none).
  take_or_keep(s.energy_density, g.energy_density, ids, 1, false);
  take_or_keep(s.dissipated, g.dissipated, ids, 1, false);
  take_or_keep(s.damage, g.damage, ids, 1, false);
  take_or_keep(s.max_stretch, g.max_stretch, ids, 1, false);
  take_or_keep(s.dilatation, g.dilatation, ids, 1, false);
  take_or_keep_if_held(s.lps_a, g.lps_a, ids, 1);
  take_or_keep_if_held(s.lps_b, g.lps_b, ids, 1);
  take_or_keep_if_held(s.corr_deformation, g.corr_deformation, ids, 9);
  take_or_keep_if_held(s.corr_force_tensor, g.corr_force_tensor, ids, 9);
  take_or_keep_if_held(s.corr_nonaffine, g.corr_nonaffine, ids, 1);
  s.min_stretch = take(g.min_stretch, ids, 1);
  s.min_stretch_next = take(g.min_stretch_next, ids, 1);
  const auto [eb, ee] = rank_entries(g, L);
  // The global system's bond state arrays (for_each_bond_state_array): take_entry_rows.
  take_entry_rows(s.state, g.state, g.bond_count(), eb, ee);
  take_entry_rows(s.bond_damage, g.bond_damage, g.bond_count(), eb, ee);
  if (g.config.strength_rate != StrengthRateLaw::None && !g.s_onset.empty()) {
    std::vector<float> onsets;
    take_entry_rows(onsets, g.s_onset, g.bond_count(), eb, ee);
    take_raised_onsets(s.s_onset, s.s0_own, onsets);  // and the ultimates raised with them
  }

  s.step = g.step;
  s.time = g.time;
  s.dt = g.dt;
  s.stable_dt = g.stable_dt;
  s.silling_askari_dt = g.silling_askari_dt;
  s.indenter_position[0] = g.indenter_position[0];
  s.indenter_position[1] = g.indenter_position[1];
  s.indenter_position[2] = g.indenter_position[2];
  // The accumulators are sums over ranks: rank 0 carries what came before (a restart).
  s.external_work = L.rank == 0 ? g.external_work : 0.0;
  s.dissipated_energy = L.rank == 0 ? g.dissipated_energy : 0.0;
  s.f32 = {};
  if (g.f32.active) float32_enable(s, g.f32.origin);
  if (g.gas.active) restrict_gas(s, g, L, ids);
}

namespace {

// The gas of the rank's particles: per particle over owned and ghosts (the front and the
// crack pass read the partners'), per entry the owned rows (in_crack from the global entry
// range: a distributed set-up's global system holds its own rows at first, every rank's on
// rank 0 once finish_distributed_setup gathered them; the other ranks keep their own), per
// facet particle the owned ones
// (one contiguous run of the global list: it is sorted by particle). The scalars are the
// global system's: every rank advances them alike from sums over every rank (mpi_backend.cpp).
void restrict_gas(PdSystem& s, const PdSystem& g, const RankLayout& L, const RankIds& ids) {
  const GasState& G = g.gas;
  GasState& r = s.gas;
  const auto [eb, ee] = rank_entries(g, L);
  const int64_t fb = first_facet_of(g, L.begin()), fe = first_facet_of(g, L.begin() + L.owned());
  // A distributed set-up's halves are the rank's rows already: they moved into this system
  // with the bonds (restrict_to_rank_taking_bonds) and stay when its state is brought up to
  // date; a whole system's are its rows' slice. The entered cracks are state: take_entry_rows.
  std::vector<uint8_t> halves = std::move(r.halves), in_crack = std::move(r.in_crack);
  take_entry_rows(halves, G.halves, g.bond_count(), eb, ee);
  take_entry_rows(in_crack, G.in_crack, g.bond_count(), eb, ee);
  // The per-particle arrays: a distributed set-up's ranks other than 0 let the global ones go
  // once the stable-step estimate cut this system (release_global_at_stable_step); this
  // system's own then stay (nothing between that cut and the loop's backend moves the gas),
  // as the state arrays' do (take_or_keep). A held global array (one process, rank 0, a
  // restart's read of the front): its rows.
  std::vector<double> kappa_volume = std::move(r.kappa_volume), vent_facet_area = std::move(r.vent_facet_area),
                      arrival = std::move(r.arrival), push = std::move(r.push), position = std::move(r.position);
  std::vector<uint8_t> front_done = std::move(r.front_done), attached = std::move(r.attached);
  r = GasState{};
  r.active = true;
  r.load = G.load;
  r.spec = G.spec;
  r.law = G.law;
  r.reference_volume = G.reference_volume;
  r.vent_area = G.vent_area;
  r.vent_crack_opening = G.vent_crack_opening;
  r.reference_density = G.reference_density;
  r.ambient = G.ambient;
  r.fixed_front_speed = G.fixed_front_speed;
  r.crack_entry = G.crack_entry;
  r.crack_pass_every = G.crack_pass_every;
  r.crack_pass_tolerance = G.crack_pass_tolerance;
  r.crack_pass_new_crack_at_once = G.crack_pass_new_crack_at_once;
  r.copy_scalars(G);
  r.wall_dv = slice(G.wall_dv, fb, fe);
  r.wall_left = slice(G.wall_left, fb, fe);
  r.wall_on = slice(G.wall_on, fb, fe);
  auto take_or_keep_gas = [&](auto& mine, const auto& global, auto& kept, size_t width) {
    mine = std::move(kept);
    take_or_keep(mine, global, ids, width, false);
  };
  take_or_keep_gas(r.kappa_volume, G.kappa_volume, kappa_volume, 2);
  take_or_keep_gas(r.vent_facet_area, G.vent_facet_area, vent_facet_area, 1);
  if (G.crack_entry) {
    take_or_keep_gas(r.arrival, G.arrival, arrival, 1);
    r.arrival_next = r.arrival;  // as read_checkpoint and setup_gas leave it
    take_or_keep_gas(r.push, G.push, push, 3);
    take_or_keep_gas(r.front_done, G.front_done, front_done, 1);
    take_or_keep_gas(r.attached, G.attached, attached, 1);
    take_or_keep_gas(r.position, G.position, position, 3);
    r.in_crack = std::move(in_crack);
    r.halves = std::move(halves);
  }
  r.block_sums.assign(static_cast<size_t>(gas_blocks(std::max<int64_t>(L.owned(), fe - fb))), GasSums{});
}

}  // namespace

namespace {
// Empties arrays and frees their memory, keeping the addresses of those that were held.
struct Release {
  std::vector<const void*> held;
  template <class T, class A>
  void operator()(std::vector<T, A>& a) {
    if (!a.empty()) held.push_back(&a);
    std::vector<T, A>().swap(a);
  }
};
}  // namespace

// The whole arrays release_global_for_loop lets go of on the ranks that do not write, each
// with whether rank 0 gathers into it (`f(array, named)`: named as held there where rank 0
// holds it though this system may not, with serial HDF5). `rank_system`: the rank's own system,
// whose model fields say which of the global system's rank 0 holds (null: those it holds).
template <class F>
void for_each_loop_state_array(PdSystem& g, F&& f, const PdSystem* rank_system = nullptr) {
  // What rank 0 gathers the state into for its files (MpiBackend::download, output).
  // Rank 0 holds these for every particle; a distributed set-up's other ranks never allocate
  // `a` and `body` and let `u` and `v` go at the stable step (setup_system,
  // mpi_stable_step_forces): named as held all the same. So do the forces and the fields
  // every model has (energy density, dissipated energy, damage, largest stretch, dilatation),
  // which they let go at the stable step too; the model's own fields (LPS's factors,
  // correspondence's tensors) are named where the rank's system holds them (rank 0 then holds
  // them whole).
  for (auto* a : {&g.u, &g.v, &g.a, &g.body, &g.force, &g.energy_density, &g.dissipated, &g.damage,
                  &g.max_stretch, &g.dilatation})
    f(*a, true);
  for (auto field : {&PdSystem::lps_a, &PdSystem::lps_b, &PdSystem::corr_deformation, &PdSystem::corr_force_tensor,
                     &PdSystem::corr_nonaffine})
    f(g.*field, rank_system && !(rank_system->*field).empty());
  // A gas load's front (its arrival times; between two crack passes the pushes), which rank 0
  // gathers for its checkpoint: named where rank 0 holds them (crack_entry; the pushes with
  // crack_pass_every > 1: download).
  const bool front = g.gas.active && g.gas.crack_entry;
  f(g.gas.arrival, front);
  f(g.gas.push, front && g.gas.crack_pass_every > 1);
  f(g.min_stretch, false);
  f(g.min_stretch_next, false);
#ifndef BRECCIA_PARALLEL_HDF5
  // The bond states: a distributed set-up left them on rank 0 alone (a restart read this
  // rank's rows here, which its system has taken). Rank 0 holds them whenever there are
  // bonds: this rank takes part in its gathers (MpiBackend::held).
  for_each_bond_state_array(g, [&](auto& a) { f(a, g.bond_count() > 0); });
#endif
  // What rank 0's writers alone read: the instability message's positions, the indenter's
  // volumes, the file order, the results' bond list.
  f(g.x0, false);
  f(g.volume, false);
  f(g.original_index, false);
#ifndef BRECCIA_PARALLEL_HDF5
  f(g.precrack_pairs, false);  // with parallel HDF5 every rank's broken bits leave out the pre-crack's
#endif
  f(g.neighbor, false);
  f(g.vol_own, false);
  f(g.own_count, false);
  f(g.k_dual, false);
}

void release_global_at_stable_step(PdSystem& g) {
  Release drop;
  for_each_released_at_stable_step(nullptr, g, [&](auto*, auto& global, size_t) { drop(global); });
}

std::vector<const void*> release_global_for_loop(PdSystem& g, bool root, const PdSystem* rank_system) {
  Release drop;
  // What the set-up read: each rank's system holds its particles' (owned and ghosts) rows.
  for (auto* a : {&g.density, &g.horizon, &g.half_cell, &g.weighted_volume, &g.calibration_factor, &g.corr_moduli,
                  &g.short_range_k, &g.spacing, &g.x, &g.u_before, &g.f_before})
    drop(*a);
  drop(g.material);
  drop(g.fixed_dof);
  drop(g.lps);
  drop(g.lps_factors);
  drop(g.internal_index);
  drop(g.known_file);  // (a window system's file -> internal index)
  drop(g.known_internal);
  g.contact_cells = ContactCells{};
  // The particle file's arrays (rank 0's results writer read them when it opened results.h5,
  // before the loop); its content id stays (checkpoint.h5 quotes it).
  ParticleModel& pm = g.particles;
  drop(pm.position_m);
  drop(pm.volume_m3);
  drop(pm.spacing_m);
  drop(pm.material_id);
  drop(pm.sets);
  drop(pm.surfaces);
  drop(pm.mesh_nodes_m);
  drop(pm.mesh_cells);
  drop(pm.held_rows);
  drop(pm.held_cells);
  drop(pm.held_nodes);
  // Loads' facets and constraints' particles: the ranks' systems hold their owned ones (the
  // body loads' lists stay: an empty one means every particle).
  for (PdSystem::SurfaceLoad& sl : g.surface_loads) drop(sl.facets);
  g.facets = FacetLayout{};
  for (PdSystem::Constraint& c : g.constraints) {
    drop(c.particles);
    drop(c.values);
  }
  // The gas's set-up and scratch arrays; its front, entered cracks and wall shares are state.
  GasState& gas = g.gas;
  for (auto* a : {&gas.arrival_next, &gas.kappa_volume, &gas.vent_facet_area, &gas.position,
                  &gas.wall_left})
    drop(*a);
  for (auto* a : {&gas.front_done, &gas.attached, &gas.halves, &gas.row_mark, &gas.chunk_live}) drop(*a);
  drop(gas.block_sums);
#ifdef BRECCIA_PARALLEL_HDF5
  // The bond states: each rank writes its own rows (checkpoint.h5) and forms its part of the
  // broken bits (results.h5) from its system, so no rank gathers them: a distributed set-up
  // left none here, a restart this rank's rows, which its system has taken. Not named as held.
  for_each_bond_state_array(g, [](auto& a) { std::remove_reference_t<decltype(a)>().swap(a); });
#endif
#ifdef BRECCIA_PARALLEL_HDF5
  const bool staging = false;  // rank 0 gathers nothing: it lets go as the others do
#else
  const bool staging = true;   // rank 0 writes every file from its gathered arrays
#endif
  if (!root || !staging) for_each_loop_state_array(g, [&](auto& a, bool named) {
      // With staging the arrays rank 0 gathers into are named as held (`named`: where this
      // system never held them or let them go earlier), else this rank would skip a gather
      // rank 0 waits in; without staging there is no gather.
      if (!staging) std::remove_reference_t<decltype(a)>().swap(a);
      else if (named && a.empty() && g.n > 0) drop.held.push_back(&a);
      else drop(a);
    }, rank_system);
  return drop.held;
}

size_t loop_state_bytes(const PdSystem& g) {
  size_t bytes = 0;
  for_each_loop_state_array(const_cast<PdSystem&>(g), [&](auto& a, bool) {
    bytes += a.capacity() * sizeof(typename std::remove_reference_t<decltype(a)>::value_type);
  });
  return bytes;
}

// What runs on the host in a distributed run and has no device path yet: the gas load's sums
// over ranks and its front (GasExchange, reduce_min_to_owners in solver/mpi/), and the
// short-range forces' contact search (which the CUDA backend lacks on one process too).
void check_cuda_ranks_support(const CaseConfig& config, const std::string& file) {
  for (size_t l = 0; l < config.loads.size(); ++l)
    if (config.loads[l].kind == LoadSpec::Kind::Gas)
      throw InputError(file, "loads[" + std::to_string(l) + "].type", "gas with --backend cuda under mpirun",
                       "--backend cpu (a distributed gas load's sums and front run on the CPU; docs/parallel.md)");
  if (config.short_range_forces)
    throw InputError(file, "model.short_range_forces", "true with --backend cuda under mpirun",
                     "--backend cpu (the CUDA backend has no contact search; docs/parallel.md)");
}

}  // namespace breccia::solver
