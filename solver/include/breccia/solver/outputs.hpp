#pragma once
// Files a PD run writes (docs/formats.md): results.h5 + results.xdmf (fields in particles.h5
// order), history.csv, summary.json, checkpoint.h5; and the results.h5 layout (identity, bond
// list, broken bits per output, XDMF sidecar) that the MPS runs write through the same functions.
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "breccia/common/h5.hpp"
#include "breccia/solver/results_layout.hpp"
#include "breccia/solver/pd_system.hpp"

namespace breccia::solver {

// The PD run's bond list (results_layout.hpp) from its internal-order families.
HalfBondList half_bond_list(const PdSystem& sys);

// Bit b (byte b / 8, bit b % 8, least significant first) set when bond b of `list` is broken
// by fracture (pre-cracks excluded): the same bonds as broken_pairs.
std::vector<uint8_t> broken_bits(const PdSystem& sys, const HalfBondList& list, int64_t* broken_count);

// The same bits per rank, without the whole bond state or bond list on any rank: a rank's
// owned rows [0, owned) of `rows` (its system: partners local, `original_index` over owned
// and ghosts) each add, per partner of higher file index, its place in the file's bond list,
// its row's first place `row_first[i]` (HalfBondList::offsets at its file index) plus its rank
// among those partners by file index. half_bond_counts gives each owned row's count of such
// partners (internal order; placed at their file indices and prefix-summed over every rank's
// rows they are the list's offsets: half_bond_list, and the ranks' blocks of them in
// mpi_backend.cpp's file_bond_offsets); broken_bond_positions the places of its broken bonds
// (fracture_broken, pre-crack pairs excluded, as broken_bits), from which the ranks form the
// bits together (mpi_backend.cpp).
std::vector<int64_t> half_bond_counts(const PdSystem& rows, size_t owned);
std::vector<int64_t> broken_bond_positions(const PdSystem& rows, size_t owned, const std::vector<int64_t>& row_first,
                                           const std::vector<std::pair<int64_t, int64_t>>& precrack_pairs);

// A rank's rows of the file's bond list (results.h5 /bonds, the list half_bond_list makes),
// from its system's owned rows [0, owned) (partners local; original_index, x0 and horizon over
// owned and ghosts), so that no rank holds another's: its rows in file-index order, each row's
// partners of higher file index at their places in the list, row_first[i] (as for
// broken_bond_positions) plus their rank by file index.
struct FileBondRows {
  std::vector<int64_t> neighbors;       // the rows' partners (file indices), run after run
  std::vector<h5::RowRun> runs;         // their places in the list: ascending, adjacent rows merged
  std::vector<int64_t> beyond_horizon;  // places whose within_horizon bit is clear (the pad bonds)
};
FileBondRows file_bond_rows(const PdSystem& rows, size_t owned, const std::vector<int64_t>& row_first);

// A per-particle field of an output group: its dataset, its components per particle and the
// system's array it comes from (internal order).
struct ResultsField {
  const char* name;
  int components;
  std::vector<double> PdSystem::*values;
};
// What every output writes (displacement, velocity, damage) and the case's `output.fields`.
std::vector<ResultsField> results_fields(const PdSystem& sys);

class ResultsWriter {
public:
  // Creates out_dir/results.h5 (or reopens it on restart, dropping outputs after `step`).
  ResultsWriter(const PdSystem& sys, const std::string& out_dir, bool restart);
  void write(const PdSystem& sys);  // one output group at the current step
  int output_count() const { return count_; }
  // The root attribute `complete` to 1: the run reached its end (0 until then, and for a run
  // stopped early, unstable or interrupted).
  void mark_complete();

  // A distributed run whose global system holds no partners (parallel HDF5: the ranks hold
  // their rows) leaves the bond list to the ranks: a new file waits for them
  // (write_bonds_together), and a restart's file is checked against the count of the list
  // they form (check_bond_count; the writer cannot count it alone).
  bool bonds_pending() const { return bonds_pending_; }
  // Likewise /particles/* with parallel HDF5 (no rank holds the whole arrays): a new file
  // waits for the ranks (write_particles_together).
  bool particles_pending() const { return particles_pending_; }
  void check_bond_count(int64_t bonds);  // throws InputError on a restart's other list; once
  int64_t bond_list_size() const { return static_cast<int64_t>(bonds_.neighbors.size()); }  // where it holds the list

#ifdef BRECCIA_PARALLEL_HDF5
  // A distributed run's output group, written by every rank of comm together (collective
  // I/O, nothing gathered): each rank gives rows [file_first, file_first + file_count) of the
  // file-order fields (`rows[f]`: results_fields' f-th) and bytes [broken_first, broken_first
  // + size) of the broken bits (`broken_block`, of broken_bytes in all: formed from every
  // rank's broken_bond_positions); every rank the same count. The root is the one rank whose
  // `writer` is not null. The group is the one write() makes of the gathered state. Collective.
  static void write_together(const PdSystem& sys, ResultsWriter* writer, const std::string& out_dir,
                             size_t file_first, size_t file_count, const std::vector<std::vector<double>>& rows,
                             const std::vector<uint8_t>& broken_block, size_t broken_first, size_t broken_bytes,
                             long long broken_count, MPI_Comm comm);
  // /bonds/* of a new file whose writer left them to the ranks (bonds_pending), written by
  // every rank of comm together: its block of /bonds/offsets (`offsets_block`, rows from
  // offsets_first of the offsets_rows = n + 1), its own rows of /bonds/neighbors
  // (file_bond_rows; bonds_total bonds in all) and bytes [within_first, within_first + size)
  // of /bonds/within_horizon. The datasets are the ones write_results_bonds writes of the
  // whole list. Collective; the root is the one rank whose `writer` is not null.
  static void write_bonds_together(ResultsWriter* writer, const std::string& out_dir,
                                   const std::vector<int64_t>& offsets_block, size_t offsets_first,
                                   size_t offsets_rows, int64_t bonds_total, const FileBondRows& mine,
                                   const std::vector<uint8_t>& within_horizon, size_t within_first, MPI_Comm comm);
  // /particles/* of a new file whose writer left them to the ranks (particles_pending),
  // written by every rank of comm together: rows [file_first, file_first + file_count) of the
  // whole_n file rows of the reference positions (3 per row), volumes, densities, horizons and
  // material indices (`rows`, in that order; the material indices as doubles, exact). The
  // datasets are the ones the constructor writes of the whole arrays. Collective; the root is
  // the one rank whose `writer` is not null.
  static void write_particles_together(ResultsWriter* writer, const std::string& out_dir, size_t file_first,
                                       size_t file_count, const std::vector<std::vector<double>>& rows, size_t whole_n,
                                       MPI_Comm comm);
#endif

private:
  void write_xdmf(const PdSystem& sys) const;
  void count_output(const PdSystem& sys);  // after an output group: its time, the XDMF
  std::string dir_;
  std::unique_ptr<h5::File> file_;
  int count_ = 0;
  std::vector<double> times_;
  HalfBondList bonds_;  // empty where the ranks hold the list (bonds_pending, check_bond_count)
  bool bonds_pending_ = false;    // a new file without /bonds yet
  bool particles_pending_ = false;  // a new file without /particles yet
  int64_t unchecked_bonds_ = -1;  // a restart's file: its list's length, not yet checked
};

// The particle of [0, count) of `x0` nearest `position`, the first of equally near ones, with
// its squared distance: a probe's particle (HistoryWriter; a distributed run takes the
// smallest (distance, index) over its ranks' owned particles, the same particle).
std::pair<double, int64_t> nearest_particle(const double* x0, size_t count, const Vec3& position);

// One particle's share of the indenter's reaction: the force the indenter exerts on it
// (indenter_force) times its volume.
struct IndenterTerm {
  int64_t particle;  // `first` + its index in the system
  double f[3];
};
// The terms of particles [0, count) of `s` (x0, u, volume) in contact with the indenter, in
// index order (the others' are zero).
std::vector<IndenterTerm> indenter_terms(const PdSystem& s, size_t count, int64_t first);
// The force the particles exert on the indenter (LAMMPS fix indent's vector): minus the sum of
// the terms, added in index order, so one process at any thread count and every rank count
// (whose ranks send rank 0 their terms in rank order: index order) give the same bits.
void indenter_reaction(const std::vector<IndenterTerm>& terms, double out[3]);

class HistoryWriter {
public:
  HistoryWriter(const PdSystem& sys, const std::string& out_dir, bool append);
  ~HistoryWriter();
  // `particles`: the probes' values and the indenter's reaction where the system does not hold
  // them whole (a distributed run's rank 0: StepBackend::history_particles); null: from `sys`.
  void write(const PdSystem& sys, const Energies& e, const HistoryParticles* particles = nullptr);

private:
  std::FILE* file_ = nullptr;
  std::vector<std::pair<int32_t, int>> probes_;  // internal particle, 0 displacement / 1 velocity
};

// Broken pairs (i < j, file order) over all bonds: fracture only, pre-cracks excluded.
std::vector<int64_t> broken_pairs(const PdSystem& sys);

void write_checkpoint(const PdSystem& sys, const std::string& path);

// One process's share of checkpoint.h5: its rows of the per-particle arrays (internal order,
// particles [particle_first, particle_first + particle_count)) and of the per-entry arrays
// (entries [entry_first, entry_first + entry_count)), held from index 0 by `rows`. The whole
// file: rows = the system itself, every particle and entry.
struct CheckpointRows {
  const PdSystem* rows = nullptr;
  size_t particle_first = 0, particle_count = 0, entry_first = 0, entry_count = 0;
  size_t facet_first = 0, facet_count = 0;  // the surface loads' facet particles (the gas's wall)
};

#ifdef BRECCIA_PARALLEL_HDF5
// checkpoint.h5 written by every rank of comm together (parallel HDF5, collective I/O): the
// run's scalars from `sys` (every rank holds them alike), each rank's rows from `mine`; the
// file is the one write_checkpoint writes of the gathered state. Collective; root renames it.
void write_checkpoint(const PdSystem& sys, const std::string& path, const CheckpointRows& mine, MPI_Comm comm,
                      bool root);
#endif
// A distributed set-up's system (distributed_rows set) reads the per-entry arrays (bond
// states, bond damage, onsets, the gas's entered cracks) of rank `rank`'s rows only, a
// hyperslab of the file's entries (internal order: a rank's rows are one run), except where
// rank 0 stages them whole for its writers (a build without parallel HDF5); the ranks'
// systems take them (copy_rank_state). One process: everything.
void read_checkpoint(PdSystem& sys, const std::string& path, int rank = 0);

// What a force pass at a restored (checkpointed) state must leave as the checkpoint has it:
// the forces and the dissipated energy, and with a rate law the bond states, damage, onsets
// and ultimates (the pass sees the full step's velocities, not the half step's the straight
// run's pass saw: a bond near its dynamic onset could soften here and not there). Taken
// before the pass, put back after (read_checkpoint; a distributed run's ranks, mpi_backend.cpp).
class CheckpointedPassState {
public:
  explicit CheckpointedPassState(const PdSystem& sys);
  void restore(PdSystem& sys);

private:
  double dissipated_ = 0.0;
  std::vector<double> force_;
  bool keep_bonds_ = false;
  std::vector<uint8_t> state_;
  decltype(PdSystem::bond_damage) damage_;
  std::vector<float> onset_, ultimate_;
};

}  // namespace breccia::solver
