#pragma once
// The particle model of a `specimen: {lattice: ...}` box: what the set-up runs on, and what
// a run writes beside its results as particles.h5 (ResultsWriter), whose rank 0 may hold only
// its window's rows of it (a distributed set-up) and so makes the whole model here again.
#include <cstdint>
#include <vector>

#include "breccia/common/particle_file.hpp"
#include "breccia/solver/case_config.hpp"

namespace breccia::solver {

// Square/cubic lattice at cell centres, the same layout breccia-place writes.
// `rows` (if given, ascending): the per-particle arrays hold those rows alone (held_rows;
// none for an empty list: the lists alone) and no content id is computed (the whole
// body's: rank 0's, BodyPlan).
ParticleModel lattice_model(const LatticeSpec& l, const std::vector<int64_t>* rows = nullptr);

}  // namespace breccia::solver
