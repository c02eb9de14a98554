#pragma once
// The stress-based solid of a case file (model.formulation: stress): particles, material
// law, options, boundary sets, floor and initial state, all from the validated CaseSpec.
#include <string>

#include "breccia/mps/case_spec.hpp"
#include "breccia/mps/solid.hpp"

namespace breccia::mps {

// content_id (optional): the particle file's content id, "" for a lattice.
Solid make_solid(const CaseSpec& spec, std::string* content_id = nullptr);

}  // namespace breccia::mps
