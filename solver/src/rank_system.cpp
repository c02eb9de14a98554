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

// Rows `ids` of a per-particle array of `width` values each; an array that is not held
// (empty: the feature is off) stays empty.
template <class T>
std::vector<T> take(const std::vector<T>& global, const std::vector<int32_t>& ids, size_t width, size_t n) {
  if (global.empty()) return {};
  if (global.size() != width * n)
    throw std::logic_error("restrict_to_rank: a per-particle array of unexpected size");
  std::vector<T> out(width * ids.size());
  for (size_t q = 0; q < ids.size(); ++q)
    std::copy_n(global.begin() + static_cast<int64_t>(width) * ids[q], width, out.begin() + static_cast<int64_t>(width * q));
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
void take_or_keep(std::vector<T>& local, const std::vector<T>& global, const std::vector<int32_t>& ids, size_t width,
                  size_t n, bool zero_at_setup) {
  if (!global.empty() || n == 0) {
    local = take(global, ids, width, n);
    return;
  }
  const size_t rows = width * ids.size();
  if (local.size() == rows) return;
  if (!zero_at_setup)
    throw std::logic_error("copy_rank_state: a state array held by neither the global system nor the rank's");
  local.assign(rows, T{});
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
  L.halo = build_halo(L.part, rank, g.offsets, g.neighbor);
  return L;
}

namespace {
void restrict_gas(PdSystem& s, const PdSystem& g, const RankLayout& L, const std::vector<int32_t>& ids);
}  // namespace

int64_t first_facet_of(const PdSystem& g, int64_t particle) {
  const std::vector<int32_t>& fp = g.facets.particle;  // ascending (group_facets_by_particle)
  return std::lower_bound(fp.begin(), fp.end(), static_cast<int32_t>(particle)) - fp.begin();
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

// restrict_to_rank; `partners`: the owned rows' partners, renumbered to local indices in
// place and kept (restrict_to_rank_taking_bonds), or null: copied from g's and renumbered.
PdSystem restrict_rank(const PdSystem& g, const RankLayout& L, std::vector<int32_t>* partners) {
  PdSystem s;
  s.config = g.config;
  s.dimension = g.dimension;
  s.thickness = g.thickness;
  const int64_t b = L.begin(), owned = L.owned();
  s.n = static_cast<size_t>(owned);
  const std::vector<int32_t> ids = local_to_global(L);
  const size_t n = g.n;
  // What the set-up fixes before its stable-step estimate: geometry, materials, families and
  // their coefficients, loads and constraints. The state follows (copy_rank_state).
  s.original_index = take(g.original_index, ids, 1, n);
  s.x0 = take(g.x0, ids, 3, n);
  s.volume = take(g.volume, ids, 1, n);
  s.density = take(g.density, ids, 1, n);
  s.horizon = take(g.horizon, ids, 1, n);
  s.half_cell = take(g.half_cell, ids, 1, n);
  s.material = take(g.material, ids, 1, n);
  s.fixed_dof = take(g.fixed_dof, ids, 1, n);
  s.weighted_volume = take(g.weighted_volume, ids, 1, n);
  s.lps = take(g.lps, ids, 1, n);
  s.calibration_factor = take(g.calibration_factor, ids, 1, n);
  s.corr_moduli = take(g.corr_moduli, ids, kCorrModuli, n);
  s.short_range_k = take(g.short_range_k, ids, 1, n);
  s.spacing = take(g.spacing, ids, 1, n);

  // The owned rows, partners renumbered (ghosts are sorted: a binary search each).
  const int64_t eb = g.offsets[b], ee = g.offsets[b + owned];
  s.offsets.resize(static_cast<size_t>(owned) + 1);
  for (int64_t i = 0; i <= owned; ++i) s.offsets[i] = g.offsets[b + i] - eb;
  if (partners) {
    for (int32_t& j : *partners) j = static_cast<int32_t>(L.local_index(j));
    s.neighbor = std::move(*partners);
  } else {
    s.neighbor.resize(static_cast<size_t>(ee - eb));
    for (int64_t k = eb; k < ee; ++k) s.neighbor[k - eb] = static_cast<int32_t>(L.local_index(g.neighbor[k]));
  }
  s.xi_len = slice(g.xi_len, eb, ee);
  s.k_own = slice(g.k_own, eb, ee);
  s.k_dual = slice(g.k_dual, eb, ee);
  s.vol_own = slice(g.vol_own, eb, ee);
  s.s0_own = slice(g.s0_own, eb, ee);
  s.s0_dual = slice(g.s0_dual, eb, ee);
  s.s_onset = slice(g.s_onset, eb, ee);
  s.contact_cell_edge = g.contact_cell_edge;
  s.symmetric_halves = g.symmetric_halves;
  s.dual_halves_shared = g.dual_halves_shared;

  // Loads and constraints on the owned particles, in the global lists' order.
  auto owned_local = [&](const std::vector<int32_t>& list) {
    std::vector<int32_t> out;
    for (const int32_t i : list)
      if (i >= b && i < b + owned) out.push_back(static_cast<int32_t>(i - b));
    return out;
  };
  for (const auto& sl : g.surface_loads) {
    PdSystem::SurfaceLoad l{sl.spec, {}};
    for (PressureFacet f : sl.facets)
      if (f.particle >= b && f.particle < b + owned) {
        f.particle = static_cast<int32_t>(f.particle - b);
        l.facets.push_back(f);
      }
    s.surface_loads.push_back(std::move(l));
  }
  s.facets = group_facets_by_particle(s);
  for (const auto& bl : g.body_loads)  // empty: every particle, which is every owned one here
    s.body_loads.push_back({bl.spec, bl.particles.empty() ? std::vector<int32_t>{} : owned_local(bl.particles)});
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

PdSystem restrict_to_rank_taking_bonds(PdSystem& g, const RankLayout& L) {
  const int64_t eb = g.offsets[L.begin()], ee = g.offsets[L.begin() + L.owned()];
  if (g.distributed_rows.empty() || eb != 0 || ee != static_cast<int64_t>(g.neighbor.size())) return restrict_to_rank(g, L);
  // The slices restrict_to_rank would copy are the whole arrays: take them, and restrict the
  // rest (an empty array slices as empty).
  std::vector<double> xi_len, k_own, k_dual, vol_own;
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
  } else {
    k_dual.swap(g.k_dual);
    vol_own.swap(g.vol_own);
  }
  // The partners too, renumbered in place (a copy was 4 B per entry more at the peak), unless
  // rank 0's writers read the global ones (root_gathers_bond_list: then copied).
  std::vector<int32_t> partners;
  if (root_gathers_bond_list(g.config)) partners = g.neighbor;
  else partners.swap(g.neighbor);
  PdSystem s = restrict_rank(g, L, &partners);
  s.xi_len = std::move(xi_len);
  s.k_own = std::move(k_own);
  s.k_dual = std::move(k_dual);
  s.vol_own = std::move(vol_own);
  s.s0_own = std::move(s0_own);
  s.s0_dual = std::move(s0_dual);
  s.s_onset = std::move(s_onset);
  s.gas.halves = std::move(gas_halves);
  return s;
}

void copy_rank_state(PdSystem& s, const PdSystem& g, const RankLayout& L) {
  const std::vector<int32_t> ids = local_to_global(L);
  const size_t n = g.n;
  s.config = g.config;  // the stable-step estimate turns fracture off in its copy
  take_or_keep(s.u, g.u, ids, 3, n, false);
  take_or_keep(s.v, g.v, ids, 3, n, false);
  take_or_keep(s.a, g.a, ids, 3, n, true);
  s.force = take(g.force, ids, 3, n);
  take_or_keep(s.body, g.body, ids, 3, n, true);
  s.x = g.x.size() == 3 * n ? take(g.x, ids, 3, n) : std::vector<double>{};
  s.energy_density = take(g.energy_density, ids, 1, n);
  s.dissipated = take(g.dissipated, ids, 1, n);
  s.damage = take(g.damage, ids, 1, n);
  s.max_stretch = take(g.max_stretch, ids, 1, n);
  s.dilatation = take(g.dilatation, ids, 1, n);
  s.lps_a = take(g.lps_a, ids, 1, n);
  s.lps_b = take(g.lps_b, ids, 1, n);
  s.corr_deformation = take(g.corr_deformation, ids, 9, n);
  s.corr_force_tensor = take(g.corr_force_tensor, ids, 9, n);
  s.corr_nonaffine = take(g.corr_nonaffine, ids, 1, n);
  s.min_stretch = take(g.min_stretch, ids, 1, n);
  s.min_stretch_next = take(g.min_stretch_next, ids, 1, n);
  const int64_t eb = g.offsets[L.begin()], ee = g.offsets[L.begin() + L.owned()];
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
void restrict_gas(PdSystem& s, const PdSystem& g, const RankLayout& L, const std::vector<int32_t>& ids) {
  const GasState& G = g.gas;
  GasState& r = s.gas;
  const size_t n = g.n;
  const int64_t eb = g.offsets[L.begin()], ee = g.offsets[L.begin() + L.owned()];
  const int64_t fb = first_facet_of(g, L.begin()), fe = first_facet_of(g, L.begin() + L.owned());
  // A distributed set-up's halves are the rank's rows already: they moved into this system
  // with the bonds (restrict_to_rank_taking_bonds) and stay when its state is brought up to
  // date; a whole system's are its rows' slice. The entered cracks are state: take_entry_rows.
  std::vector<uint8_t> halves = std::move(r.halves), in_crack = std::move(r.in_crack);
  take_entry_rows(halves, G.halves, g.bond_count(), eb, ee);
  take_entry_rows(in_crack, G.in_crack, g.bond_count(), eb, ee);
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
  r.kappa_volume = take(G.kappa_volume, ids, 2, n);
  r.vent_facet_area = take(G.vent_facet_area, ids, 1, n);
  if (G.crack_entry) {
    r.arrival = take(G.arrival, ids, 1, n);
    r.arrival_next = r.arrival;  // as read_checkpoint and setup_gas leave it
    r.push = take(G.push, ids, 3, n);
    r.front_done = take(G.front_done, ids, 1, n);
    r.attached = take(G.attached, ids, 1, n);
    r.position = take(G.position, ids, 3, n);
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
  template <class T>
  void operator()(std::vector<T>& a) {
    if (!a.empty()) held.push_back(&a);
    std::vector<T>().swap(a);
  }
};
}  // namespace

std::vector<const void*> release_global_for_loop(PdSystem& g, bool root) {
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
  for (auto* a : {&gas.front_done, &gas.attached, &gas.halves}) drop(*a);
  drop(gas.block_sums);
#ifdef BRECCIA_PARALLEL_HDF5
  // The bond states: each rank writes its own rows (checkpoint.h5) and forms its part of the
  // broken bits (results.h5) from its system, so no rank gathers them: a distributed set-up
  // left none here, a restart this rank's rows, which its system has taken. Not named as held.
  for_each_bond_state_array(g, [](auto& a) { std::remove_reference_t<decltype(a)>().swap(a); });
#endif
  if (!root) {
    // What rank 0 gathers the state into for its files (MpiBackend::download, output).
    // Rank 0 holds these for every particle; a distributed set-up's other ranks never allocate
    // `a` and `body` and let `u` and `v` go at the stable step (setup_system,
    // mpi_stable_step_forces): named as held all the same, else this rank would skip a gather
    // rank 0 waits in.
    for (auto* a : {&g.u, &g.v, &g.a, &g.body}) {
      if (a->empty() && g.n > 0) drop.held.push_back(a);
      drop(*a);
    }
    for (auto* a : {&g.force, &g.energy_density, &g.dissipated, &g.damage, &g.max_stretch, &g.dilatation,
                    &g.lps_a, &g.lps_b, &g.corr_deformation, &g.corr_force_tensor, &g.corr_nonaffine, &g.gas.arrival,
                    &g.gas.push})
      drop(*a);
    for (auto* a : {&g.min_stretch, &g.min_stretch_next}) drop(*a);
#ifndef BRECCIA_PARALLEL_HDF5
    // The bond states: a distributed set-up left them on rank 0 alone (a restart read this
    // rank's rows here, which its system has taken). Rank 0 holds them whenever there are
    // bonds: this rank takes part in its gathers (MpiBackend::held).
    for_each_bond_state_array(g, [&](auto& a) {
      if (g.bond_count() > 0) drop.held.push_back(&a);
      drop(a);
    });
#endif
    // What rank 0's writers alone read: the instability message's positions, the indenter's
    // volumes, the file order, the results' bond list.
    drop(g.x0);
    drop(g.volume);
    drop(g.original_index);
#ifndef BRECCIA_PARALLEL_HDF5
    drop(g.precrack_pairs);  // with parallel HDF5 every rank's broken bits leave out the pre-crack's
#endif
    drop(g.neighbor);
    drop(g.vol_own);
    drop(g.k_dual);
  }
  return drop.held;
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
