#pragma once
// The results.h5 layout every model writes (format 2, docs/formats.md): identity and
// provenance, the bond list once, broken bits per output group, and the XDMF sidecar. PD's
// ResultsWriter (outputs.cpp) and the MPS writer (solver/mps/src/results_output.cpp) both
// go through these functions, so that breccia-post and ParaView read one layout. No
// PdSystem here: the MPS side includes this without the PD physics headers.
#include <algorithm>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "breccia/common/h5.hpp"
#include "breccia/common/particle_file.hpp"

namespace breccia::solver {

// 2: bonds once in /bonds, one bit per bond and output (1 wrote broken pairs per output).
constexpr long long kResultsFormatVersion = 2;

// The run's bonds once, as post-processing reads them (results.h5 /bonds, docs/formats.md):
// each pair once from its lower file index, partners ascending. Built at start; an output
// then only needs one bit per bond.
struct HalfBondList {
  std::vector<int64_t> offsets;       // N + 1, file order
  std::vector<int64_t> neighbors;     // partners j > i, ascending within a row (file indices: int64)
  std::vector<int64_t> entry;         // bond b -> the solver's bond entry (PD: row of i, internal order; MPS: CSR index)
  std::vector<uint8_t> within_horizon;  // bits: |xi| <= max(horizon_i, horizon_j) (the fragment graph)
  std::vector<uint8_t> precrack;        // bits: removed at start by a pre-crack
};
// The same list from a bond CSR already in file order that holds each pair from both ends
// (an MPS neighbour list): pairs j > i, partners ascending, entry = the pair's index in that
// CSR. within_horizon and precrack are sized and clear; the caller sets what they mean.
template <class Offset, class Index>
HalfBondList half_bond_list_of(const std::vector<Offset>& offsets, const std::vector<Index>& neighbors);

// Root attributes of a fresh results.h5: format, version, provenance, output_count 0,
// complete 0.
struct ResultsIdentity {
  std::string particles_file;        // absolute path of the particles.h5 the run used
  std::string particles_content_id;  // its content_id
  int dimension = 3;
  double thickness_m = 1.0;
  std::string model;                 // pmb, lps, ..., mps
  std::string case_file;             // absolute path
};
void write_results_identity(const h5::File& f, const ResultsIdentity& id);

// A model built from the case file (a lattice, MPS bodies) has no particles.h5: it is written
// as out_dir/particles.h5 so that post-processing and its provenance check work the same for
// every run. Returns that path.
std::string write_particles_beside_results(const std::string& out_dir, const ParticleModel& model);

// /bonds/offsets, /bonds/neighbors, /bonds/within_horizon.
void write_results_bonds(const h5::File& f, const HalfBondList& bonds);

std::string results_output_group(int index);  // "/output/NNNNNN", numbered by output index

// Completes output group `index` after its fields: the broken bits and their count, step and
// time, then /@output_count = index + 1 and a flush (a reader never counts a partial group).
void finish_results_output(const h5::File& f, int index, long long step, double time_s,
                           const std::vector<uint8_t>& broken, int64_t broken_count);
// The same after the group's broken bits (its /broken dataset) are written: a distributed
// run's ranks write them by blocks (ResultsWriter::write_together).
void finish_results_output_attributes(const h5::File& f, int index, long long step, double time_s,
                                      int64_t broken_count);

// A per-particle dataset of every output group, as the XDMF sidecar shows it.
struct XdmfField {
  std::string name;
  int components = 1;    // 1 scalar, 3 vector, 6 symmetric tensor (xx yy zz xy yz zx)
  bool integer = false;  // int32 (fragment labels) rather than float64
};
// results.xdmf beside results.h5: a temporal collection of Polyvertex grids on
// /particles/position, one per output group.
void write_results_xdmf(const std::string& path, size_t particles, const std::vector<double>& times,
                        const std::vector<XdmfField>& fields);

template <class Offset, class Index>
HalfBondList half_bond_list_of(const std::vector<Offset>& offsets, const std::vector<Index>& neighbors) {
  const size_t n = offsets.empty() ? 0 : offsets.size() - 1;
  HalfBondList h;
  h.offsets.assign(n + 1, 0);
  for (size_t i = 0; i < n; ++i) {
    std::vector<std::pair<int64_t, int64_t>> row;
    for (Offset k = offsets[i]; k < offsets[i + 1]; ++k)
      if (static_cast<size_t>(neighbors[k]) > i) row.emplace_back(static_cast<int64_t>(neighbors[k]), static_cast<int64_t>(k));
    std::sort(row.begin(), row.end());
    for (const auto& [j, k] : row) {
      h.neighbors.push_back(j);
      h.entry.push_back(k);
    }
    h.offsets[i + 1] = static_cast<int64_t>(h.neighbors.size());
  }
  h.within_horizon.assign((h.neighbors.size() + 7) / 8, 0);
  h.precrack.assign(h.within_horizon.size(), 0);
  return h;
}

}  // namespace breccia::solver
