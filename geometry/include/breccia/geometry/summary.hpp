#pragma once
// Human-readable summary of a particle model: counts, volumes per material, sets,
// surfaces (facets and total area), spacing range.
#include <string>

#include "breccia/common/particle_file.hpp"

namespace breccia::geometry {

std::string summarize(const ParticleModel& model);

}  // namespace breccia::geometry
