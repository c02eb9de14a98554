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

#ifdef BRECCIA_PARALLEL_HDF5
  // A distributed run's output group, written by every rank of comm together (collective
  // I/O, nothing gathered but the bond states the broken bits read): each rank gives rows
  // [file_first, file_first + file_count) of the file-order fields (`rows[f]`: results_fields'
  // f-th), the root (the one rank whose `writer` is not null) the bond states in `sys`. The
  // group is the one write() makes of the gathered state. Collective.
  static void write_together(const PdSystem& sys, ResultsWriter* writer, const std::string& out_dir,
                             size_t file_first, size_t file_count, const std::vector<std::vector<double>>& rows,
                             MPI_Comm comm);
#endif

private:
  void write_xdmf(const PdSystem& sys) const;
  void count_output(const PdSystem& sys);  // after an output group: its time, the XDMF
  std::string dir_;
  std::unique_ptr<h5::File> file_;
  int count_ = 0;
  std::vector<double> times_;
  HalfBondList bonds_;
};

class HistoryWriter {
public:
  HistoryWriter(const PdSystem& sys, const std::string& out_dir, bool append);
  ~HistoryWriter();
  void write(const PdSystem& sys, const Energies& e);

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
void read_checkpoint(PdSystem& sys, const std::string& path);

}  // namespace breccia::solver
