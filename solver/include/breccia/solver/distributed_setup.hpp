#pragma once
// The distributed set-up (docs/parallel.md, Memory): under mpirun each rank builds the bonds
// of the particles it owns only, so the bond arrays, the set-up's and the run's largest,
// fall as 1/ranks. The per-particle arrays (positions, volumes, materials, horizons, the
// state: a few hundred bytes each) are the rank's geometric window's on the ranks other than
// 0 (plan_window_system: a window system, built from the particle file's rows of its window
// alone, read by hyperslabs), the whole body's on rank 0 (the planner, which reads the whole
// file: its writers' staging); the row offsets likewise: the ranks other than 0 keep their
// entry ranges alone (cut_partition: every rank cuts from its slice; PdSystem::distributed_entries;
// rank 0 the whole offsets with a serial HDF5 alone); the bond
// states (1 B per entry, with softening, a rate law or a gas load up to 10 B) are each rank's own rows,
// in its system, with parallel HDF5; without it whole on rank 0 too, its writers' staging
// (for_each_bond_state_array).
//
// How: the family sizes are counted from the positions alone (family_sizes, partition.hpp),
// which gives the partition (and a serial HDF5's rank 0 the whole row offsets) before any family exists.
// The set-up then runs as on one process on a system whose rows outside the rank's range are
// empty (a window system: the rank's rows and the window's other particles, local indices;
// else the whole body): every per-entry loop covers the rank's rows, and the few values a row reads from
// other rows or every particle (listed at each call in setup.cpp) come through
// DistributedSetup::concat (a sum or a list over every rank) or, for a value its owner
// computed per particle, exchange_owned (to the rank's geometric window only). Every value is computed by the same code as on one process, so
// the run is byte-identical to it. The rank's own system (rank_system.hpp) is cut from this
// one by the stable-step estimate as before, and the bonds move into it rather than being
// copied (restrict_to_rank_taking_bonds); finish_distributed_setup then leaves the global
// system what the time loop and the files need.
#include <algorithm>
#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <cstring>
#include <exception>
#include <stdexcept>
#include <string>
#include <vector>

#include "breccia/common/cell_list.hpp"
#include "breccia/common/error.hpp"
#include "breccia/common/families.hpp"
#include "breccia/solver/partition.hpp"
#include "breccia/solver/pd_system.hpp"

namespace breccia::solver {

// How the owners' values of a per-particle array reach the ranks whose geometric window
// (partition.hpp) holds them (exchange_owned): the window's particles outside the rank's
// rows (`halo`, ascending, so grouped by owner in rank order) come from their owners, and
// the rank sends the particles of its rows that the other ranks' windows hold (`send`, each
// destination's ascending, destinations in rank order). Formed once from the windows alone
// (window_exchange: each rank tells each owner which of its particles its window holds), as
// the contact exchange forms its lists from the ranks' boxes.
struct WindowExchange {
  std::vector<int32_t> halo;         // global internal indices, ascending
  std::vector<int64_t> halo_counts;  // per owner rank (ranks entries)
  std::vector<int32_t> send;         // global internal indices of this rank's rows, per destination
  std::vector<int64_t> send_counts;  // per destination rank (ranks entries)
};

// Which rows this rank builds. inactive: all of them (one process).
struct DistributedRows {
  bool active = false;
  int64_t begin = 0, end = 0;          // the rank's rows (internal order)
  // The whole system's row offsets (n + 1), from the family sizes: rank 0 alone without
  // parallel HDF5 (root_keeps_offsets: its writers', I/O staging); empty on the other ranks.
  std::vector<int64_t> full_offsets;
  std::vector<int64_t> entry_begin;    // every rank's: each rank's first bond entry, then the total (ranks + 1)
  GeometricWindow window;              // the rows' geometric window (active only): every partner
  WindowExchange exchange;             // the owners' values to that window (active only)
  // The set-up system is the window (plan_window_system; PdSystem::window_global): its particles are
  // window.index in local indices, the rows [window.row_begin, window.row_end). False: it holds
  // the whole body (one process; rank 0, the writers' rank), the rows [begin, end).
  bool windowed = false;
  // The rank's rows in the set-up system's indices (where a pass loops over them).
  int64_t local_begin() const { return windowed ? window.row_begin : begin; }
  int64_t local_end() const { return windowed ? window.row_end : end; }
};

// Whether this rank's set-up runs on a window system (plan_window_system): every rank, but
// rank 0 where it stages the whole body for its writers (root_stages_whole_body: serial HDF5;
// the same code on a window that is everything).
bool setup_on_window(const DistributedSetup& d);

// The mesh cells of the surfaces' facets (ascending, unique; none without a mesh): what a
// reader of some of the file's rows also reads (near_surface_set's and the pre-cracks'
// triangles).
std::vector<int64_t> facet_cells(const ParticleModel& m);

// How many of `halo` (ascending global indices outside the rank's rows) each rank owns under
// the partition `part_begin` (ranks + 1 offsets): the counts exchange_owned receives.
std::vector<int64_t> count_by_owner(const std::vector<int64_t>& part_begin, const std::vector<int32_t>& halo);

// The rank's WindowExchange for `window` (its rows [part_begin[rank], part_begin[rank + 1])
// then its halo): collective (one all-to-all of the halo's indices to their owners).
WindowExchange window_exchange(const DistributedSetup& d, const std::vector<int64_t>& part_begin,
                               const GeometricWindow& window);

// Throws std::logic_error, naming the row and the partner (global internal indices), when a
// partner of one of the rank's rows [rows.begin, rows.end) (`offsets`, `neighbor`: the whole
// system's rows, global partners) is not in rows.window: exchange_owned fills the window's
// particles alone, so a pass would read a partner's value that never arrived. Inactive rows:
// nothing to check. One bit test per entry (the window marked over its span of indices).
void require_partners_in_window(const DistributedRows& rows, const std::vector<int64_t>& offsets,
                                const std::vector<int32_t>& neighbor);

// A run of the internal order a rank holds while the partition is planned: particles
// [first, first + p.size()) with what the windows and the family count read of them.
struct PlanParticle {
  int64_t file = 0;
  double x[3] = {0.0, 0.0, 0.0};
  double horizon = 0.0, half_cell = 0.0;
};
struct RankRun {
  int64_t first = 0;
  std::vector<PlanParticle> p;
};
// One process and a staged rank 0 (root_stages_whole_body: it holds the whole body, read
// from the whole particle file, its writers' staging), once the internal order and horizons are set: counts the
// family sizes, cuts the partition (s.distributed_rows) and returns the rank's rows (inactive
// on one process). Every rank plans from its slice of the internal order (`slice`: its
// family_slice's particles, from the Morton sort): it forms its slice's geometric window from
// the ranks' slices (form_window) and counts the slice's family sizes on it (every partner,
// not the body); every rank cuts from its slice's sizes (cut_partition); every rank then forms
// its rows' window from the runs moved to the partition's ranges. Collective; throws
// InputError for more ranks than particles.
DistributedRows plan_distributed_rows(PdSystem& s, const DistributedSetup& d, RankRun slice = {});

// The ranks of a distributed set-up but a staged rank 0 (setup_on_window): the window system built from the particle file's
// rows of its window, never the whole body. s: s.n the body's count, s.dimension, s.config,
// s.particles the file's lists (read_particle_lists). Plans with the other ranks from its
// slice (as plan_distributed_rows), then reads its rows' window's rows into s.particles (held_rows; the surfaces'
// facet cells of the mesh, held_cells): s.x0, volume, density, material, half_cell, horizon,
// original_index are the window's in its order (values: a held row's material, density,
// cell and horizon, as the whole body's set-up sets them), s.window_global its internal
// indices, s.body_n the body's count, s.n the window's; the sets hold their members among
// the rows (whole_count: the whole set's), as `read` leaves them. Collective with
// plan_distributed_rows.
// ReadFileRows: the file rows `rows` (ascending) into `into` (held_rows), each of its sets'
// members among them (whole_count: the whole set's), and the mesh cells `cells`.
using ReadFileRows = std::function<void(const std::vector<int64_t>& rows, const std::vector<int64_t>& cells, ParticleModel& into)>;
struct RowValues {
  double horizon = 0.0, half_cell = 0.0, density = 0.0;
  int32_t material = 0;
};
using ValuesOfRow = std::function<RowValues(const ParticleModel& m, size_t held_row)>;
DistributedRows plan_window_system(PdSystem& s, const DistributedSetup& d, const ReadFileRows& read,
                                   const ValuesOfRow& values, RankRun slice);

// A traction's boundary layer (setup.cpp layer_of_surface): its depth, every particle of it
// (file indices, ascending) and their volume summed in file order.
struct SurfaceLayer {
  double depth = 0.0;
  double volume = 0.0;
  std::vector<int64_t> particles;
};

// The families of the rank's rows (every row on one process, build_families), the other rows
// empty: the same rows, partners and order as the whole build's. A distributed set-up builds
// them on the rows' geometric window (geometric_window, partition.hpp: the rows, then every
// particle within the pair's reach of one of them), which holds every partner, so the search's cell
// lists and copies hold the window's particles, not the whole body's; the partners are then
// mapped back to the whole system's indices (the window is ascending, so each row stays sorted).
// window_particles (if given): the particles the search held (one process: all of them).
Families build_own_families(const PdSystem& s, const DistributedRows& rows, const std::vector<double>& pad,
                            int64_t* window_particles = nullptr);

// The particles whose family sizes `rank` of `ranks` counts for plan_distributed_rows:
// [n rank / ranks, n (rank + 1) / ranks), equal in count to within one, contiguous and
// in rank order, so their concatenation is [0, n). Not the partition (which is cut from
// these sizes): an equal share of the counting, cut before any size is known.
struct FamilySlice {
  int64_t begin = 0, end = 0;
};
FamilySlice family_slice(int64_t n, int rank, int ranks);

// The distributed Morton order (docs/parallel.md, Memory, item 2): each rank holds an equal
// block of the particle file's rows (morton_blocks: file_block), their Morton keys taken in the
// whole body's bounding box (body_bounding_box: every rank's box folded in rank order, so the
// same doubles as bounding_box over the file) with morton_key, as morton_order takes them.
// distributed_morton_sort sorts the items by (key, file row) across the ranks (a sample sort:
// regular samples, ranks - 1 splitters, one all-to-all): morton_order's stable order exactly,
// ties going by file row. Each rank returns one contiguous run of that order (ranks in order;
// `first`: its first internal index), the items' positions and spacings travelling with them.
struct MortonItem {
  uint64_t key = 0;
  int64_t file = 0;
  double x[3] = {0.0, 0.0, 0.0};
  double spacing = 0.0;
};
struct MortonBlock {
  std::vector<MortonItem> items;  // internal indices first .. first + items.size() - 1
  int64_t first = 0, n = 0;       // n: the body's count
};
FamilySlice file_block(int64_t n, int rank, int ranks);  // [n rank / ranks, n (rank + 1) / ranks)
BoundingBox body_bounding_box(const DistributedSetup& d, std::span<const double> block_positions);
MortonBlock distributed_morton_sort(const DistributedSetup& d, std::vector<MortonItem> mine);

// The runs moved so that rank r holds [begin[r], begin[r + 1]) (collective: one all-to-all).
RankRun move_run(const DistributedSetup& d, RankRun run, const std::vector<int64_t>& begin);
// The body's reach classes (partition.hpp ReachFigures) from the ranks' runs (two folds).
ReachFigures body_reach_figures(const DistributedSetup& d, const RankRun& run, int dimension);
// The geometric window (partition.hpp geometric_window) of the rank's run as its rows, formed
// from the ranks' runs (each rank's run: one contiguous run of the order, in rank order):
// the ranks' marks summarised by blocks of cells (MarksSummary) to every rank, each rank
// sends every other its particles that may be near that rank's rows, and the rank keeps
// those near them (WindowMarks::near, geometric_window's own test): the same window, its
// particles (`p`, in the window's order) with it. Collective.
struct FormedWindow {
  GeometricWindow window;
  std::vector<PlanParticle> p;
};
FormedWindow form_window(const DistributedSetup& d, const RankRun& rows, int dimension, const ReachFigures& body,
                         int64_t body_n);

// The k-th smallest (0-based) of every rank's values together, as std::nth_element places it
// in one array (setup.cpp median: k = n / 2): a bisection over the doubles' order (64 rounds
// of one count per rank). Collective; k below the total count.
double distributed_order_statistic(const DistributedSetup& d, const std::vector<double>& mine, int64_t k);

// Each rank's refusal of its part of the input (`mine`: an InputError, or null), the first in
// rank order thrown on every rank as that InputError (its message whole), so that rank 0
// prints the message once and no rank goes on alone. The ranks read the file's rows in blocks
// in rank order (file_block), so the first refusal is the first row's a whole read meets.
// Any other exception is rethrown on its own rank (its abort stops the others). Collective.
void refuse_together(const DistributedSetup& d, std::exception_ptr mine);
// The same for a rank's check: runs `check`, and its InputError (if any) is every rank's.
template <class Check>
void refuse_together(const DistributedSetup& d, Check&& check) {
  std::exception_ptr mine;
  try {
    check();
  } catch (const InputError&) {
    mine = std::current_exception();
  }
  refuse_together(d, mine);
}

// Every rank's elements of `mine`, concatenated in rank order, on every rank.
template <class T>
std::vector<T> concat_over_ranks(const DistributedSetup& d, const std::vector<T>& mine) {
  const std::vector<char> bytes = d.concat(mine.data(), mine.size(), sizeof(T), true);
  std::vector<T> out(bytes.size() / sizeof(T));
  if (!bytes.empty()) std::memcpy(static_cast<void*>(out.data()), bytes.data(), bytes.size());
  return out;
}

// The owners' values of a per-particle array of `width` values each (computed there from
// their own rows) into this rank's window's other particles (rows.exchange): the ghosts'
// values a later pass reads, e.g. LPS's weighted volume. The particles outside the window
// keep what this rank holds for them (nothing reads them: require_partners_in_window).
// Collective; an empty array (the feature is off, on every rank alike) stays empty.
// A window system's array (rows.windowed) is addressed by local index: the halo is the
// window's particles outside its rows, in order, and a row i is at i - begin + row_begin.
template <class T>
void exchange_owned(const DistributedSetup& d, const DistributedRows& rows, std::vector<T>& a, size_t width) {
  if (a.empty() || !rows.active) return;
  const WindowExchange& x = rows.exchange;
  const size_t bytes = width * sizeof(T);
  const int64_t row_shift = rows.windowed ? rows.window.row_begin - rows.begin : 0;
  const int64_t rows_held = rows.window.row_end - rows.window.row_begin;
  auto halo_at = [&](size_t q) {
    if (!rows.windowed) return static_cast<int64_t>(x.halo[q]);
    const int64_t k = static_cast<int64_t>(q);
    return k < rows.window.row_begin ? k : k + rows_held;
  };
  std::vector<T> out(width * x.send.size());
  for (size_t q = 0; q < x.send.size(); ++q)
    std::copy_n(a.begin() + static_cast<int64_t>(width) * (x.send[q] + row_shift), width,
                out.begin() + static_cast<int64_t>(width * q));
  std::vector<int64_t> received;
  const std::vector<char> in = d.exchange(out.data(), x.send_counts, bytes, received);
  if (received != x.halo_counts || in.size() != bytes * x.halo.size() || a.size() % width != 0)
    throw std::logic_error("distributed set-up: an exchange of owners' values differs from the window's halo");
  for (size_t q = 0; q < x.halo.size(); ++q)
    std::memcpy(static_cast<void*>(a.data() + width * static_cast<size_t>(halo_at(q))), in.data() + bytes * q, bytes);
}

// Per material: the sum of the first `dims` of each marked particle's 3 `values`, taken in
// particle index order, and how many values were summed (the surface correction's bulk
// targets over the complete families). A distributed set-up marks its own rows only: every
// rank's marked values are concatenated in rank order first, so the sums run in one
// process's order, bit for bit. Collective when rows are active.
struct MaterialSums {
  std::vector<double> sum;
  std::vector<int> count;
};
MaterialSums sum_marked_by_material(const DistributedSetup& d, const DistributedRows& rows,
                                    const std::vector<uint8_t>& marked, const std::vector<int32_t>& material,
                                    const std::vector<double>& values, int dims, size_t materials);

// The per-particle fields the stable-step estimate's last force pass fills (at the real
// displacement, fracture on), with their values per particle. Under the distributed set-up
// that pass runs on the ranks' systems, which keep them (their ghosts' from the owners, by the
// halo exchange), and rank 0 gathers them whole into its global system for its writers
// (mpi_stable_step_forces); the other ranks' global systems hold none (they let them go when
// the rank's system was cut: release_global_at_stable_step), so every rank starts from one
// process's fields. LPS's dilatation and fast-path factors, and correspondence's
// deformation gradient, force tensor (sigma K^-1) and non-affine energy, are empty when the
// model has none (on every rank alike).
struct ForcePassField {
  std::vector<double> PdSystem::*field;
  int64_t width;
};
inline constexpr ForcePassField kForcePassFields[] = {
    {&PdSystem::energy_density, 1}, {&PdSystem::damage, 1},           {&PdSystem::max_stretch, 1},
    {&PdSystem::dissipated, 1},     {&PdSystem::dilatation, 1},       {&PdSystem::lps_a, 1},
    {&PdSystem::lps_b, 1},          {&PdSystem::corr_deformation, 9}, {&PdSystem::corr_force_tensor, 9},
    {&PdSystem::corr_nonaffine, 1}};

// The global system's per-entry state arrays: the bond states, softening's bond damage, a
// rate law's onsets, a gas load's entered cracks `in_crack` (those the case holds: alike on
// every rank). After a distributed set-up every rank's own rows are in its system
// (copy_rank_state keeps those) and the global system's are empty: with parallel HDF5 on
// every rank (each writes its rows, the broken bits come from each rank's rows); without it
// rank 0 holds them whole (its writers read them: the first output group, the broken bits,
// the files) and the other ranks take part in its gathers (release_global_for_loop names
// them as held). A restart's read_checkpoint reads each rank's rows (rank 0's whole where
// it stages them), which copy_rank_state takes.
template <class F>
void for_each_bond_state_array(PdSystem& s, F&& f) {
  f(s.state);
  if (s.config.softening) f(s.bond_damage);
  if (s.config.strength_rate != StrengthRateLaw::None) f(s.s_onset);
  if (s.gas.active && s.gas.crack_entry) f(s.gas.in_crack);
}

// Whether rank 0 gathers the results' bond list at the end of a distributed set-up (the
// partners, and the two half-bond factors its writer's broken bits read: 20 B per entry) and
// keeps it for its writer: only a build without parallel HDF5, whose rank 0 writes every file
// alone. With parallel HDF5 each rank writes its own rows of the list and of the broken bits
// (mpi_backend.cpp), so the set-up keeps no copy of them.
inline bool root_gathers_bond_list(const CaseConfig& c) {
#ifdef BRECCIA_PARALLEL_HDF5
  (void)c;
  return false;
#else
  return c.write_results;
#endif
}

// Whether rank 0 of a distributed set-up builds the whole body's system beside its block
// (its writers' staging): only a build without parallel HDF5, whose rank 0 writes every file
// alone. With parallel HDF5 every rank builds its rows' window system (setup_on_window).
inline bool root_stages_whole_body() {
#ifdef BRECCIA_PARALLEL_HDF5
  return false;
#else
  return true;
#endif
}

// Whether rank 0 keeps the whole row offsets (DistributedRows::full_offsets) for its writers:
// only without parallel HDF5 (its writers' staging, as root_gathers_bond_list's).
inline bool root_keeps_offsets(const CaseConfig& c) {
#ifdef BRECCIA_PARALLEL_HDF5
  (void)c;
  return false;
#else
  (void)c;
  return true;
#endif
}

// The global system as the time loop and the writers need it, its bonds now in the ranks'
// own systems: the whole row offsets on every rank, the bond state arrays
// (for_each_bond_state_array) on rank 0 without parallel HDF5, on none with it; where
// root_gathers_bond_list, rank 0 also gathers the partners and the two half-bond volumes and
// moduli the results' bond list reads (outputs.cpp); every other per-entry array is dropped.
void finish_distributed_setup(PdSystem& s, const DistributedRows& rows, const DistributedSetup& d);

}  // namespace breccia::solver
