#pragma once
// history.csv of an MPS run (docs/mps.md) in breccia-post's vocabulary, so that the probe,
// spectrum and energy code reads MPS and PD runs alike (docs/postproc.md, "MPS runs"):
//  - probe columns <name>_<displacement|velocity>_<x|y|z> become probe_<name>_<u|v><x|y|z>;
//  - the energy columns (output.energy: true) are mapped onto post's balance terms
//    kinetic_J, strain_J, external_work_J, dissipated_J; what MPS does not record is said in
//    the notes, not invented.
// The MPS columns themselves are kept.
#include <string>
#include <utility>
#include <vector>

#include "breccia/postproc/history.hpp"

namespace breccia::postproc {

struct MpsHistoryMapping {
  History history;                                    // MPS columns + post's names
  bool energy = false;                                // the four balance terms were mapped
  std::vector<std::pair<std::string, std::string>> terms;  // post term -> its MPS expression
  std::vector<std::string> notes;                     // what has no MPS counterpart
};

MpsHistoryMapping map_mps_history(const History& mps);

}  // namespace breccia::postproc
