#pragma once
// The state of one PD run, as structure-of-arrays owned by one object. Particles are held
// in Morton order internally (locality); `original_index` maps back to particles.h5 order,
// in which every output is written.
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <optional>
#include <vector>

#include "breccia/common/families.hpp"
#include "breccia/common/huge_pages.hpp"
#include "breccia/common/particle_file.hpp"
#include "breccia/solver/case_config.hpp"
#include "breccia/solver/contact_cells.hpp"
#include "breccia/solver/float32_state.hpp"
#include "breccia/solver/gas.hpp"
#include "breccia/solver/load_kernels.hpp"
#include "breccia/solver/pd_kernels.hpp"

namespace breccia::solver {

struct BoundaryField;  // boundary_field.hpp

struct PressureFacet {  // a boundary facet carrying pressure or traction
  int32_t particle;     // internal index
  double area;          // m2
  double normal[3];     // outward unit normal
};

// The bond arrays' bytes per entry: neighbor (int32), xi_len, k_own (doubles), the own halves'
// volumes (own_count, a byte, where the partial volumes were counted: model.partial_volume
// sampled; else vol_own, a double), s0_own (a float), state (a byte), and the dual halves
// k_dual and s0_dual (a double, a float) unless set-up shares them (PdSystem::
// dual_halves_shared). Softening's two floats are not counted.
constexpr size_t bond_entry_bytes(bool dual_halves_shared, bool own_volumes_counted) {
  return sizeof(int32_t) + 2 * sizeof(double) + (own_volumes_counted ? sizeof(uint8_t) : sizeof(double)) + sizeof(float) +
         1 + (dual_halves_shared ? 0 : sizeof(double) + sizeof(float));
}
// Are the own halves' volumes kept as sample counts (PdSystem::own_count)? Where the partial
// volume is the sampled one (the default): beta = count / total then, for every entry.
inline bool own_volumes_counted(const CaseConfig& c) { return c.partial_volume == PartialVolume::Sampled; }

// An LPS-type model (correspondence shares LPS's bond data) with fracture in 2D scales each end's
// critical stretch by its own factor, so an entry's two halves differ even with one horizon and
// set-up keeps them apart. Set-up's decision (setup.cpp) and the planner's memory estimate
// (tools/plan) both read this.
inline bool model_separates_dual_halves(const CaseConfig& c, int dimension) {
  const bool lps_type = c.model == PdModel::LPS || c.model == PdModel::Correspondence;
  return lps_type && c.fracture && dimension == 2;
}

struct PdSystem {
  CaseConfig config;
  ParticleModel particles;  // as read (file order)
  int dimension = 3;
  double thickness = 1.0;
  size_t n = 0;
  std::vector<int64_t> original_index;  // internal -> file index (a global id: files past 2^31 particles)
  std::vector<int32_t> internal_index;  // file -> internal index (whole; empty on a window system: known_file)
  // A window system's file -> internal index (distributed_setup.hpp plan_window_system): its
  // window's particles and those rank 0's plan names (the surfaces' facet particles, the
  // traction layers'), ascending by file index. Empty with internal_index.
  std::vector<int64_t> known_file;
  std::vector<int32_t> known_internal;
  // A distributed set-up's window system (distributed_setup.hpp; the ranks other than 0): its
  // n particles are the rank's geometric window alone, local particle k being the whole body's
  // internal particle window_global[k] (ascending, so the rank's rows are one local range), and
  // every per-particle array is sized to the window; body_n is the whole body's count. Empty:
  // the system holds the whole body (one process, rank 0), local index = internal index.
  std::vector<int32_t> window_global;
  size_t body_n = 0;
  // The whole body's particle count (n, unless a window system).
  size_t whole_n() const { return window_global.empty() ? n : body_n; }
  // The system's index of the whole body's internal particle `i` (a window system: the first
  // local index at or after it, so a range of internal indices maps to a local range).
  int64_t system_index(int64_t i) const;
  // The system's index of file particle f: internal_index, or a window system's local index
  // of it (-1: not in the window).
  int32_t system_of_file(int64_t f) const;
  // The whole body's internal index of file particle f (a window system: of a known one;
  // std::logic_error for another).
  int32_t internal_of_file(int64_t f) const;
  // A window system's per-facet-particle arrays (the gas's wall shares) hold its window's
  // facet particles (facets.particle); the whole body's facet particles, internal indices
  // ascending, are these (a checkpoint's rows). Empty: facets.particle is the whole list.
  std::vector<int32_t> whole_facet_particles;

  // per particle (internal order)
  std::vector<double> x0, u, v, a, force, body;  // 3N
  std::vector<double> x;                         // 3N current positions x0 + u (kept by cpu_step)
  std::vector<double> volume, density, horizon, half_cell;
  std::vector<int32_t> material;
  std::vector<uint8_t> fixed_dof;
  std::vector<double> energy_density, dissipated, damage, max_stretch, dilatation, weighted_volume;
  std::vector<double> lps_a, lps_b;  // fast LPS path factors (pd_kernels.hpp)
  std::vector<LpsForceFactors<double>> lps_factors;  // N: the general LPS loop's (PdViewT::lps_factors)
  std::vector<LpsCoefficients> lps;
  std::vector<double> calibration_factor;  // PMB: classical / discrete energy (docs/theory.md)
  // Correspondence (correspondence_kernels.hpp): 5 moduli, F (9), sigma K^-1 - G h F (9), non-affine energy
  std::vector<double> corr_moduli, corr_deformation, corr_force_tensor, corr_nonaffine;

  // bonds (CSR over full families)
  std::vector<int64_t> offsets;
  std::vector<int32_t> neighbor;
  std::vector<double> xi_len, k_own, k_dual;
  // The own halves' volumes beta_own V_j (damage weights, family volumes): read them through
  // own_volume / own_half_exists (and PdView's, pd_kernels.hpp), never the arrays directly.
  // Where set-up counted the partial volumes (own_volumes_counted: model.partial_volume
  // sampled) own_count holds each entry's own sample count (at most 216, a byte) and vol_own
  // stays empty: the volume is formed where read, count / total x V_j (counted_own_volume,
  // pd_physics.hpp), the set-up's expression, the same bits; 7 B per entry fewer. With the
  // analytic partial volume (lammps) vol_own holds them and own_count stays empty.
  std::vector<double> vol_own;
  std::vector<uint8_t> own_count;
  std::vector<float> s0_own, s0_dual;
  std::vector<uint8_t> state;
  // Where every entry's dual half equals its own half bit for bit (one horizon and equal
  // partial volumes both ways; setup_system decides before the bond arrays exist), k_dual and
  // s0_dual stay empty and the dual halves are the own ones: 12 B per entry fewer. Read the
  // dual halves through these (and PdView's k_dual / s0_dual, which point at the own arrays
  // then), never k_dual / s0_dual directly. The strength-rate law writes raised ultimates
  // into s0_own alone: a softening entry never reads s0_dual (soften, pd_kernels.hpp), so
  // sharing the array changes nothing it reads.
  bool dual_halves_shared = false;
  const std::vector<double>& k_dual_halves() const { return dual_halves_shared ? k_own : k_dual; }
  const std::vector<float>& s0_dual_halves() const { return dual_halves_shared ? s0_own : s0_dual; }
  // The float copy's dual moduli (model.precision: float32; float32_state.hpp), the same way.
  const std::vector<float>& f32_k_dual_halves() const { return dual_halves_shared ? f32.k_own : f32.k_dual; }
  // The bond arrays' bytes per entry (summary.json's bytes_per_particle; softening's two
  // arrays not counted): neighbor, xi_len, k_own, own_count or vol_own, s0_own, state, and the
  // dual halves.
  size_t bytes_per_bond_entry() const { return bond_entry_bytes(dual_halves_shared, own_volumes_counted(config)); }
  // The fraction of each count in own_count, count / total (pd_physics.hpp).
  const double* own_count_fractions() const { return partial_volume_sample_fractions(dimension); }
  // Entry k's own half's volume beta_own V_j (vol_own's note): stored, or formed from its count.
  double own_volume(int64_t k) const {
    return own_count.empty() ? vol_own[k] : counted_own_volume(own_count[k], own_count_fractions(), volume[neighbor[k]]);
  }
  // Points a host view (double, or the float copy's with `stored` its float vol_own) at the own
  // halves' volumes (pd_kernels.hpp own_volume): the counts where held, vol_own then null; else
  // the stored volumes. Both host views take it, so they cannot disagree on which one serves.
  template <class Real>
  void point_at_own_volumes(PdViewT<Real>& p, const Real* stored) const {
    p.vol_own = own_count.empty() ? stored : nullptr;
    p.own_count = own_count.empty() ? nullptr : own_count.data();
    p.volume_exact = volume.data();
    p.sample_fraction = own_count_fractions();
  }
  // Entry k's own half exists (beta_own > 0): its count is nonzero, or its stored volume positive.
  bool own_half_exists(int64_t k) const { return own_count.empty() ? vol_own[k] > 0.0 : own_count[k] != 0; }
  // Each particle's family volume, the own halves' volumes of its row summed once in row order
  // from 0 (family_volumes below: pd_kernels.hpp summed_family_volume, the sum every diagnostic
  // pass formed per entry, so the same bits), filled by setup_system once the bond arrays are
  // final; a rank's system takes its particles' (rank_system.cpp). The diagnostic passes read it
  // (PdView::family_volume), and the set-up's completeness tests add the particle's own cell
  // (volume[i] + family_volume[i]). Empty: the passes sum it over their rows themselves.
  std::vector<double> family_volume;
  // model.compressive_enhancement: each particle's smallest bond stretch at the last force
  // pass and the one being written (pd_kernels.hpp, stretch_shift); empty without it.
  std::vector<float> min_stretch, min_stretch_next;
  // Softening bonds (materials[].tensile_strength): each entry's onset stretch s_t (s0_own and
  // s0_dual then hold the ultimate stretch s_u) and its damage d in [0, 1]; empty without.
  // bond_damage starts as untouched zero pages (huge_pages.hpp ZeroedVector): pages of entries
  // never damaged are never allocated.
  std::vector<float> s_onset;
  ZeroedVector<float> bond_damage;
  // model.short_range_forces: per particle 15 c / delta and spacing (short_range_kernel).
  std::vector<double> short_range_k, spacing;
  ContactCells contact_cells;      // scratch: the pairs outside the families (contact_cells.hpp)
  std::vector<double> u_before, f_before;  // scratch of the step's work trapezoid (step.hpp)
  double contact_cell_edge = 0.0;  // 1.35 x the largest spacing
  std::vector<std::pair<int64_t, int64_t>> precrack_pairs;  // file indices, i < j

  // loads and constraints
  struct SurfaceLoad {
    const LoadSpec* spec;
    std::vector<PressureFacet> facets;
  };
  std::vector<SurfaceLoad> surface_loads;
  FacetLayout facets;  // the surface loads' facets grouped by particle (what the step reads)
  struct BodyLoad {
    const LoadSpec* spec;
    std::vector<int32_t> particles;  // internal (the set's particles this system holds)
    // No set named: every particle. Not read off an empty list: a set may hold no particle
    // of a rank's system (or none at all), and then the load acts on none of them.
    bool every_particle = false;
  };
  std::vector<BodyLoad> body_loads;
  struct Constraint {
    const BoundarySpec* spec;
    std::vector<int32_t> particles;  // internal
    // A boundary by expression (boundary_field.hpp): its ramped value per particle of the
    // set, 3 per entry, refreshed on the host when it changes; empty for a constant value.
    std::shared_ptr<const BoundaryField> field;
    std::vector<double> values;
    double values_time = 0.0;  // the time `values` were evaluated at (NaN: never; attach_boundary_field)
  };
  std::vector<Constraint> constraints;
  GasState gas;  // loads[].type: gas (gas.hpp); inactive without one

  // time and energy bookkeeping
  long long step = 0;
  double time = 0.0;
  double dt = 0.0;
  double stable_dt = 0.0;         // 2 / omega_max by Lanczos (sharp; setup_system)
  double silling_askari_dt = 0.0; // Silling & Askari 2005 bound (PMB), for reference
  int stable_step_passes = 0;     // force passes the stable-step estimate took
  size_t stable_step_particles = 0;  // particles free in that estimate (stable_step_region)
  double external_work = 0.0;
  double dissipated_energy = 0.0;
  double indenter_position[3] = {0, 0, 0};
  bool symmetric_halves = false;  // one constant horizon (set-up decides)
  bool diagnostics = true;        // compute damage/energy in the next force pass
  // Wall time of each set-up phase, in order (setup_system; summary.json, progress line).
  std::vector<std::pair<std::string, double>> setup_phases;
  // The same phases' process CPU time (all threads; std::clock, as the loop's loop_cpu_s):
  // on a shared machine the ratio of set-up to step is measured in CPU time too.
  std::vector<double> setup_phases_cpu;
  Float32State f32;               // model.precision: float32 (float32_state.hpp); inactive otherwise
  // A distributed set-up's partition (ranks + 1 row offsets, cut before any family existed;
  // distributed_setup.hpp): the ranks' layouts take it. Empty: every rank built everything.
  std::vector<int64_t> distributed_rows;
  // Its bond entries' ranges, once the set-up finished (finish_distributed_setup): each rank's
  // rows' first entry, then the total (ranks + 1). The ranks other than 0 keep no row offsets
  // here (`offsets` empty: their rows' are their own systems'); rank 0 the whole ones with a
  // serial HDF5 (root_keeps_offsets), none with parallel HDF5.
  std::vector<int64_t> distributed_entries;
  // The longest row offsets each rank held from the partition's cut on (the set-up system's,
  // the cut's, the ones kept for the run), rank 0 first (summary.json's offsets_rows_per_rank).
  std::vector<int64_t> setup_offsets_rows;
  // The rows of results.h5's /bonds/offsets each rank of a distributed run with parallel HDF5
  // held (its block and its own rows' first places: mpi_backend.cpp file_bond_offsets), rank
  // 0 first (summary.json's file_offsets_rows_per_rank). Empty elsewhere: one process, or rank
  // 0 with a serial HDF5, holds the whole list (half_bond_list).
  std::vector<int64_t> file_offsets_rows;
  // The most bytes of an output group's broken bits each rank held (its block of the dataset:
  // mpi_backend.cpp broken_bits_together), rank 0 first (summary.json's
  // broken_bits_bytes_per_rank). Empty where one process or rank 0 forms the whole bits.
  std::vector<int64_t> broken_bits_bytes;
  // The bond entries the set-up built (setup_system): the candidate families' entries (the
  // family search's, its largest arrays) and the kept ones (the bond arrays'). Under mpirun,
  // one value per rank, rank 0 first (finish_distributed_setup gathers them): each rank's own
  // rows alone, so they sum to one process's (summary.json's setup_entries_per_rank).
  std::vector<int64_t> setup_candidate_entries, setup_kept_entries;
  // The particles each rank's set-up system held (its per-particle arrays' length: the
  // window's on the ranks other than 0, PdSystem::window_global; one process and rank 0: the
  // body's), one value per rank the same way (summary.json's setup_system_particles_per_rank).
  std::vector<int64_t> setup_system_particles;
  // The most rows of the particle file each rank's set-up read and held at once: one process
  // and rank 0 every row (the whole file), the ranks other than 0 the larger of their block
  // for the Morton sort and their rows' window (plan_window_system), one value per rank the same way
  // (summary.json's setup_file_rows_per_rank).
  std::vector<int64_t> setup_file_rows;
  // The particles the family search held (its cell lists, its copies): the rows' geometric
  // window (build_own_families; one process: every particle), one value per rank the same way
  // (summary.json's setup_window_particles_per_rank).
  std::vector<int64_t> setup_window_particles;
  // The per-particle rows of a checkpoint each rank read (read_checkpoint: one process and rank
  // 0 with a serial HDF5 every row; a distributed set-up's other ranks their owned rows), rank
  // 0 first once the time loop's backend gathered them (summary.json's restart_rows_per_rank).
  std::vector<int64_t> restart_rows;
  // A checkpoint was read into such a system: the derived fields (damage, energies) of the
  // restored state are still to be computed, by the ranks' systems (read_checkpoint).
  bool derived_fields_pending = false;

  PdView view();
  // The bond entries of the whole system: the CSR's, since a distributed set-up's global
  // system keeps the offsets (rank 0) or the entry ranges (the others) but not the partners
  // (distributed_setup.hpp).
  size_t bond_count() const {
    if (offsets.empty() && !distributed_entries.empty()) return static_cast<size_t>(distributed_entries.back());
    return offsets.empty() ? neighbor.size() : static_cast<size_t>(offsets.back());
  }
  // Any load at all? Without one the body force stays zero and a step skips the loads.
  bool loads_vary() const { return !surface_loads.empty() || !body_loads.empty() || config.indenter.enabled; }
  // A boundary moves its particles (velocity or displacement; fixed ones hold them at rest).
  bool prescribes_motion() const {
    for (const Constraint& c : constraints)
      if (c.spec->kind != BoundarySpec::Kind::Fixed) return true;
    return false;
  }
  double total_mass() const;
};

// How the stable-step estimate's force passes run: fill sys.force from sys.u (a distributed
// run shares them between its ranks, solver/mpi/); empty: cpu_compute_forces. The factory
// builds one for a system once its families are set up (and it is dropped after the
// estimate, with whatever it holds).
using ForcePass = std::function<void(PdSystem&)>;
using ForcePassFactory = std::function<ForcePass(PdSystem&)>;

// The stable-step estimate of a distributed run (solver/mpi/), each rank holding its own share
// of the Lanczos vectors: the rank's particles [begin, end) (one contiguous range of the
// internal order), its system's displacement and force arrays (owned particles first, in that
// order: 3 values each), `pass` fills the owned forces from the owned displacements (the
// ghosts' come from their owners), and `chain` sums over every rank in one process's order:
// rank r continues the sum `f` from rank r - 1's result (rank 0 from 0), and every rank
// gets the last rank's, so a sum over the whole system has one process's bits at any rank
// count (a maximum too: `f` takes the larger). `system`: the rank's system, its owned
// particles first (particle i at i - begin), whose reference arrays (positions, volumes,
// densities, horizons, cells, materials) the estimate reads for its own particles: the
// global system's ranks other than 0 let theirs go at the cut (release_global_at_stable_step).
// Empty (pass unset): one process, the vectors whole.
struct StableStepRanks {
  int64_t begin = 0, end = 0;
  // The whole body's particles (a window system holds its window alone, PdSystem::window_global);
  // 0: the global system's n.
  int64_t particles = 0;
  double* u = nullptr;
  const double* force = nullptr;
  const PdSystem* system = nullptr;
  std::function<void(PdSystem& global)> pass;
  std::function<double(const std::function<double(double)>& f)> chain;
};

// A distributed set-up's collectives (solver/mpi/). concat: every rank's `count` elements of
// `element_bytes` at `data`, concatenated in rank order, returned on every rank (everyone)
// or on rank 0 only (the others get nothing). exchange: an all-to-all, `counts[r]` elements
// (consecutive at `data`, in rank order) to each rank r; returns what arrives, in source
// rank order, and each source's count in `received` (ranks entries). With them each rank
// builds the bonds of the particles it owns only (distributed_setup.hpp); inactive on one
// process.
struct DistributedSetup {
  int rank = 0, ranks = 1;
  std::function<std::vector<char>(const void* data, size_t count, size_t element_bytes, bool everyone)> concat;
  std::function<std::vector<char>(const void* data, const std::vector<int64_t>& counts, size_t element_bytes,
                                  std::vector<int64_t>& received)>
      exchange;
  bool active() const { return ranks > 1 && static_cast<bool>(concat); }
};

// What a distributed run changes in the set-up (solver/mpi/); empty: one process.
struct SetupHooks {
  ForcePassFactory stable_step_forces;
  // Once stable_step_forces has built its pass: the ranks' shares of the estimate's vectors
  // (StableStepRanks). Empty: the vectors whole on every rank.
  std::function<StableStepRanks()> stable_step_ranks;
  DistributedSetup distributed;
  // Builds the bond families in build_families' place (its arguments, its result bit for
  // bit): the CUDA backend's device build (cuda_families.hpp). Empty: build_families.
  std::function<Families(std::span<const double> position, std::span<const double> horizon_m,
                         std::span<const double> pad_m, int64_t row_begin, int64_t row_end)>
      families;
  // Store k_dual and s0_dual even where they equal the own halves (tests compare the two
  // layouts; pd_system.hpp k_dual_halves). False: shared where set-up finds them equal.
  bool store_dual_halves = false;
};

// Each of the view's p.n particles' family volume summed over its CSR row
// (pd_kernels.hpp summed_family_volume; p.family_volume is not read), threaded over particles:
// PdSystem::family_volume from the double view, Float32State::family_volume from the float one.
template <class Real>
std::vector<double> family_volumes(const PdViewT<Real>& p);

// Build everything from a case file: particles (file or lattice), families, coefficients,
// pre-cracks, loads, constraints, initial conditions, stable step. Throws InputError.
PdSystem setup_system(const CaseConfig& config, const SetupHooks& hooks = {});
// The gas load surface_loads[load_index] (gas.hpp): reference volume, vents, crack factors.
// Called once the facets are grouped. Throws InputError naming `field`.
void setup_gas(PdSystem& s, int load_index, const std::string& field);
// The surface loads' facets grouped by particle (setup_system keeps them in PdSystem::facets).
FacetLayout group_facets_by_particle(const PdSystem& s);

// One velocity-Verlet step of size sys.dt on the CPU (OpenMP).
void cpu_step(PdSystem& sys);
// Internal forces (and LPS dilatation) at the current displacement; fills energy/damage.
void cpu_compute_forces(PdSystem& sys);
// What every step (and ADR iteration) starts with: the compressive enhancement's minimum
// stretches of the last step's force pass become the ones this step's pass reads (a swap).
// Not done per force pass: a pass repeated at the same configuration (a restart, an
// interruption) must read what the step's own pass read, and so break nothing new.
void commit_min_stretch(PdSystem& sys);
// The short-range forces between particles outside each other's family (model.
// short_range_forces; the family pairs are short_range_kernel's): the pairs a cell grid on
// the current positions finds (x_now: 3N, double). Host only. `members`: the grid holds
// these particles only, listed in the order a cell is walked, out of `indices` that p and
// x_now address (ContactCells::build; a distributed run's owned and nearby particles), and
// `key` the global index of each (ContactCellsView::key); the forces are those of p's first
// p.n particles.
void short_range_contact(PdSystem& sys, const PdViewT<double>& p, const double* x_now,
                         std::span<const int32_t> members = {}, int64_t indices = 0, const int32_t* key = nullptr);
void short_range_contact(PdSystem& sys, const PdViewT<float>& p, const double* x_now,
                         std::span<const int32_t> members = {}, int64_t indices = 0, const int32_t* key = nullptr);
// External force density at time t (pressure, traction, body force, indenter).
void compute_external(PdSystem& sys, double t);
// Impose prescribed displacement/velocity at time t on constrained components.
void apply_constraints(PdSystem& sys, double t, double dt);

struct Energies {
  double kinetic = 0.0, strain = 0.0, max_damage = 0.0;
  long long broken_half_bonds = 0;
  bool finite = true;
  int64_t bad_particle = -1;  // internal index of a non-finite particle
  // A gas load with crack entry: the particles its front has reached (history.csv's
  // gas_wetted_particles), counted by a distributed run's ranks over their own particles and
  // summed; -1: not counted here (the history counts the system's arrival times).
  long long gas_wetted = -1;
};
Energies measure(const PdSystem& sys);

// A particle a message names (an instability's): its file index and reference position.
struct NamedParticle {
  int64_t file_index = 0;
  double x0[3] = {0.0, 0.0, 0.0};
};

// What a history line reads of single particles (history.csv): each probe's displacement or
// velocity (3 values per probe, the case's order) and the indenter's reaction. One process's
// history writer takes them from its system; a distributed run's owners send them to rank 0.
struct HistoryParticles {
  std::vector<double> probes;
  double indenter[3] = {0.0, 0.0, 0.0};
};

// Largest angular frequency of the linearised system (times a 2% margin) by power iteration
// (uses the force kernel on a tiny displacement, so it is exact for the discretisation at
// hand); the reference the Lanczos estimate below is checked against. `forces`: how each
// iteration's force pass runs (ForcePass); the result does not depend on it.
double estimate_max_frequency(PdSystem& sys, int iterations = 60, const ForcePass& forces = {});
// The same by Lanczos in the mass inner product: at most `max_passes` force passes, fewer
// once converged (sys.stable_step_passes says how many): 19 instead of 60 on the full
// concrete case, within 0.4% of the power iteration on five models (docs/performance-log.md).
// The set-up's stable step (setup_system): its dt is up to 0.4% smaller than the power
// iteration's, as its Ritz value approaches omega_max^2 from below faster.
// On a graded body it works on the stiff region (stable_step_region with `region_ratio`; 0:
// the whole system), the rest held at rest. The set-up's 0.35 (was 1/4): on the full concrete
// case 27,051 particles instead of 50,198, passes 0.2 CPU s instead of 0.34, dt 0.21% larger.
// On a PMB lattice the estimate starts mostly from the plane wave of stable_step_start_wave
// (below), the random start kept at a third of its amplitude so that no mode is missed: 9
// passes instead of 20 at 41^3, its Ritz value above the random start's (docs/performance-log.md).
// `wave`: that wave, found by the caller (a distributed set-up's ranks agree on it first);
// null: found here from the system's rows.
inline constexpr double kStableStepRegionRatio = 0.35;
struct StableStepStartWave;
// `ranks` (a distributed run, StableStepRanks): each rank holds the vectors of its own
// particles only, its sums chained over the ranks; the same bits as one process's.
double estimate_max_frequency_lanczos(PdSystem& sys, int max_passes = 60, const ForcePass& forces = {},
                                      double region_ratio = kStableStepRegionRatio,
                                      const StableStepStartWave* wave = nullptr, const StableStepRanks* ranks = nullptr);
// The particles the Lanczos estimate moves: 1 where the local frequency scale
// E / (rho delta^2) is at least `ratio` of the largest; empty (the whole system) where that
// is half the particles or more, or ratio <= 0.
std::vector<uint8_t> stable_step_region(const PdSystem& sys, double ratio);
// The plane wave u = p cos(k . x) whose load on a bulk particle of a PMB lattice is largest
// (stable_step_start_wave.cpp): searched over k on the row with the largest Silling-Askari
// sum (`score`, `row`: the first such row). found: false but on a PMB lattice (one spacing,
// one horizon) whose system holds rows. `row_sums` (optional): each row's sum of
// (k_own + k_dual) / xi_len in entry order, as the set-up's Silling-Askari bound sums it (the
// same bits): given, the rows are not summed again. `lattice`: whether the whole body has one
// spacing and one horizon, where the caller knows it (a window system's own particles may all
// share one cell and one horizon on a graded body: its set-up passes the body's verdict);
// unset, judged from sys's particles (a system that holds the whole body).
struct StableStepStartWave {
  bool found = false;
  double score = 0.0;
  int64_t row = -1;
  double k[3] = {0.0, 0.0, 0.0}, p[3] = {0.0, 0.0, 0.0};
};
StableStepStartWave stable_step_start_wave(const PdSystem& sys, const std::vector<double>* row_sums = nullptr,
                                           std::optional<bool> lattice = std::nullopt);

}  // namespace breccia::solver
