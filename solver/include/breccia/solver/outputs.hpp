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

class ResultsWriter {
public:
  // Creates out_dir/results.h5 (or reopens it on restart, dropping outputs after `step`).
  ResultsWriter(const PdSystem& sys, const std::string& out_dir, bool restart);
  void write(const PdSystem& sys);  // one output group at the current step
  int output_count() const { return count_; }

private:
  void write_xdmf(const PdSystem& sys) const;
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
void read_checkpoint(PdSystem& sys, const std::string& path);

}  // namespace breccia::solver
