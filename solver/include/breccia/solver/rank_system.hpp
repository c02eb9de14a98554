#pragma once
// One rank's share of a distributed PD run (docs/parallel.md): the particles it owns (a
// contiguous range of the internal Morton order, partition.hpp) followed by its ghosts (the
// off-rank partners its families read, in ascending internal order), as a PdSystem of its
// own. The step of step.hpp runs on it unchanged: loops cover the n owned particles, the
// bond loops read partners through local indices, and the ghosts' displacement (and the
// LPS / correspondence fields between their passes, and the compressive enhancement's
// minimum stretches) arrive by halo exchange instead of being computed. Every per-particle
// value an owned particle computes is therefore the serial run's, bit for bit.
//
// No MPI here: the layout and the restriction are plain data, so they are tested without it
// (tests/solver/test_partition.cpp, RankSystem.*); the exchange itself is in solver/mpi/.
#include <cstdint>
#include <string>
#include <vector>

#include "breccia/solver/partition.hpp"
#include "breccia/solver/pd_system.hpp"

namespace breccia::solver {

struct RankLayout {
  Partition part;
  Halo halo;
  int rank = 0;
  int64_t begin() const { return part.begin[rank]; }
  int64_t owned() const { return part.owned(rank); }
  int64_t ghosts() const { return static_cast<int64_t>(halo.ghosts.size()); }
  // The local index of global internal index j (owned or ghost); -1 if neither.
  int64_t local_index(int64_t j) const;
};

// The Morton-range partition of `global`'s families into `ranks` and the halo of `rank`.
// Throws InputError when there are more ranks than particles.
RankLayout rank_layout(const PdSystem& global, int ranks, int rank);

// The rank's PdSystem: owned particles then ghosts for every per-particle array, the owned
// rows of the bond families with partners renumbered to local indices, the constraints'
// and loads' particles restricted to the owned ones (in the same order, so a particle's
// facets are summed as in the serial run), and the float state when the run is float32
// (with the global body's origin, so the float coordinates are the serial run's).
// Load specs still point into `global.config`: the global system must outlive it.
PdSystem restrict_to_rank(const PdSystem& global, const RankLayout& layout);

// restrict_to_rank for a distributed set-up's global system (distributed_setup.hpp), whose
// only rows are this rank's (on the ranks other than 0 a window system, PdSystem::
// window_global, read by local index): the per-entry coefficients move from it into the rank's system
// instead of being copied (the peak of set-up memory); what rank 0's results writer reads of
// the bond list (partners, own_count or vol_own, k_dual) is copied where it gathers them
// (root_gathers_bond_list: serial HDF5 with results written). Any other system: restrict_to_rank.
PdSystem restrict_to_rank_taking_bonds(PdSystem& global, const RankLayout& layout);

// The state part of restrict_to_rank again (displacements, velocities, forces, bond states,
// damage, the LPS / correspondence / compressive fields, step, time, dt, the accumulators,
// the float state): what the set-up sets after its stable-step estimate and a checkpoint
// restores. A rank system built for the estimate is brought up to date with it rather than
// built again. A window system's (PdSystem::window_global) arrays are read by local index,
// whole arrays (a restart's read) by internal index, told apart by their length.
void copy_rank_state(PdSystem& local, const PdSystem& global, const RankLayout& layout);

// What a distributed set-up's ranks other than 0 let go of in their global system (their
// window's arrays: plan_window_system) once the
// stable-step estimate has cut the rank's system from it (mpi_stable_step_forces), before the
// estimate's peak: the displacements and velocities, the forces and the fields the estimate's
// last pass fills (kForcePassFields: energy density, dissipated energy, damage, largest
// stretch, dilatation, and the model's own), LPS's weighted volume, the reference arrays
// (positions, volumes, densities, horizons, cells, materials: the estimate reads its own
// particles' from the rank's system, StableStepRanks::system), the set-up values the
// estimate does not read (calibration factors, constrained components, LPS's coefficients and
// general-loop factors, correspondence's moduli, the short-range constants) and a gas load's
// per-particle arrays. The cut (restrict_to_rank_taking_bonds) already lets each go as it
// takes the rank's rows of it (one list for both: rank_system.cpp); this lets go of what is
// left. The rank's system
// holds its particles' values from then on (copy_rank_state keeps them); rank 0 keeps the
// whole arrays, which its writers read and its gathers fill (release_global_for_loop names
// them as held on the other ranks).
void release_global_at_stable_step(PdSystem& global);

// The global system of a distributed run once every rank's system has been cut from it and
// brought up to date (by the time loop's or dynamic relaxation's backend, solver/mpi/): the
// rank's own system holds what its steps need, so the global one keeps only what the time
// loop and the writers read (docs/parallel.md, Memory). On every rank it lets go of what the
// set-up alone read (densities, horizons, cells, materials, constraints' and loads' particle
// lists, the facet lists, the particle file's arrays and file -> internal indices, the model's coefficients, the gas's
// set-up arrays); on the ranks that do not write (`root` false) also of the arrays rank 0
// gathers the state into for its files (displacements to bond states, the gas's front and
// entered cracks) and of what only rank 0's writers read (reference positions, volumes,
// file indices). What stays: the scalars, the row offsets (the entry ranges, the bond
// count), the configuration, the particle model's content id, the gas's scalars and its per-
// facet shares. Returns the arrays released that were held: a gather into them on rank 0
// (solver/mpi/) still takes every rank's part, though only rank 0 holds the target. On the
// ranks that do not write, an array a distributed set-up never held or let go before (the
// state arrays and the fields of the stable step's last pass: mpi_stable_step_forces) is
// named as held all the same where rank 0 holds it: the model's own fields (LPS's factors,
// correspondence's tensors) where `rank_system`, the rank's own system, holds them.
// With parallel HDF5 rank 0 writes no file alone and gathers nothing (every rank writes its
// rows; the history's particles and the instability message come from their owners:
// MpiBackend::history_particles, instability), so it lets go of those arrays as the others
// do, and none is named as held.
std::vector<const void*> release_global_for_loop(PdSystem& global, bool root, const PdSystem* rank_system = nullptr);

// The bytes (capacity) of the whole per-particle and per-entry arrays release_global_for_loop
// lets go of on the ranks that do not write: the state, the fields, the gas's front, the bond
// states and partners, the reference positions, volumes and file indices. summary.json's
// loop_whole_bytes_rank0: what rank 0's global system holds of them after its loop.
size_t loop_state_bytes(const PdSystem& global);

// A distributed run on the CUDA backend (one GPU per rank, docs/parallel.md) runs what the
// CUDA step runs on one process, less what a distributed run adds on the host: throws
// InputError naming the first key of `config` it does not run (`file`: the case file's name).
void check_cuda_ranks_support(const CaseConfig& config, const std::string& file);

// The index in global.facets (sorted by particle) of the first facet particle at or after
// internal index `particle`: a rank's facet particles are [first_facet_of(begin),
// first_facet_of(begin + owned)).
int64_t first_facet_of(const PdSystem& global, int64_t particle);

}  // namespace breccia::solver
