#pragma once
// The particle model of a `specimen: {lattice: ...}` box: what the set-up runs on, and what
// a run writes beside its results as particles.h5 (ResultsWriter), whose rank 0 may hold only
// its window's rows of it (a distributed set-up) and so makes the whole model here again.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "breccia/common/particle_file.hpp"
#include "breccia/solver/case_config.hpp"

namespace breccia::solver {

// Square/cubic lattice at cell centres, the same layout breccia-place writes.
// `rows` (if given, ascending): the per-particle arrays hold those rows alone (held_rows;
// none for an empty list: the lists alone) and no content id is computed (the whole
// body's: lattice_content_id).
ParticleModel lattice_model(const LatticeSpec& l, const std::vector<int64_t>* rows = nullptr);
// The whole lattice's content id (compute_content_id of lattice_model's), its points made one
// at a time: a distributed set-up's ranks hold their rows of it alone.
std::string lattice_content_id(const LatticeSpec& l);
// Points per axis of a `specimen: {lattice: ...}` box (1 on the axes it does not have).
std::array<int64_t, 3> lattice_point_counts(const LatticeSpec& lattice);

}  // namespace breccia::solver
