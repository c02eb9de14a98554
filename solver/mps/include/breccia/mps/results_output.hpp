#pragma once
// results.h5 (+ results.xdmf) of an MPS run in the layout PD runs write (format 2,
// docs/formats.md), through the shared writer functions of breccia/solver/results_layout.hpp, so
// that breccia-post and ParaView read both. The MPS reading of the PD words:
//  - bond list (/bonds): the reference stencil, every pair closer than re (the MPS
//    "family"), each pair once from its lower index; within_horizon is set for every bond
//    (a stencil has no partial-volume bonds beyond it);
//  - pre-cracks (/precrack_bonds): the stencil bonds a frictional crack of the displacement
//    formulation removes at the start (its faces act through the crack pairs instead);
//  - broken bits per output: the bonds cut by separation-tensor fracture (stress
//    formulation); none otherwise;
//  - damage: the fraction of a particle's initial bonds that are cut (0 without fracture).
// The MPS fields (stress, eq_plastic_strain, fragment) are written beside PD's.
#include <array>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "breccia/common/h5.hpp"
#include "breccia/mps/case_spec.hpp"
#include "breccia/mps/neighbours.hpp"
#include "breccia/solver/results_layout.hpp"

namespace breccia::mps {

class Simulation;
class Solid;

class MpsResultsWriter {
public:
  // h5_path: where results.h5 is written (an OutputFile's temporary name); out_dir: the run
  // directory, which gets results.xdmf and, for a lattice or bodies specimen, particles.h5.
  // Writes the identity, particles, materials, pre-cracks and bond list.
  // content_id: that of the particle file the case read ("" for a lattice or bodies).
  MpsResultsWriter(const std::string& h5_path, const std::string& out_dir, const CaseSpec& spec,
                   const std::string& case_file, const std::string& content_id, const Simulation& sim);
  MpsResultsWriter(const std::string& h5_path, const std::string& out_dir, const CaseSpec& spec,
                   const std::string& case_file, const std::string& content_id, const Solid& sim);
  ~MpsResultsWriter();

  // One output group at the model's current step.
  void write(const Simulation& sim);
  void write(const Solid& sim);
  // Root attribute complete = 1 (the run ended normally).
  void mark_complete();
  // What writes results.xdmf for the outputs so far (a copy of their times and fields): the
  // caller runs it once results.h5 has its final name, so that a run stopped on the way
  // leaves no results.xdmf pointing at a file that is not there (or at an earlier run's).
  std::function<void()> xdmf_writer() const;
  int output_count() const { return static_cast<int>(times_.size()); }
  const solver::HalfBondList& bonds() const { return bonds_; }

private:
  // Everything before the first output; `reference` is the stencil the bond list is made of,
  // `current` the run's bonds at the start (pairs of reference missing there: pre-cracks).
  void open(const std::string& h5_path, const CaseSpec& spec, const std::string& case_file,
            const std::string& content_id, int dimension, double thickness_m, const std::vector<double>& position_m,
            const std::vector<double>& volume_m3, double spacing_m, const BondList& reference, const BondList& current);
  void write_common(long long step, double time_s, const std::array<const std::vector<double>*, 3>& u,
                    const std::array<const std::vector<double>*, 3>& v, const std::vector<double>& damage,
                    const std::vector<uint8_t>& broken, int64_t broken_count);

  std::string out_dir_;
  std::unique_ptr<h5::File> file_;
  size_t n_ = 0;
  size_t reference_entries_ = 0;  // entries (both directions) of the reference CSR
  solver::HalfBondList bonds_;
  std::vector<double> times_;
  std::vector<solver::XdmfField> fields_;
};

}  // namespace breccia::mps
