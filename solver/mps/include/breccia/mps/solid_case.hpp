#pragma once
// The stress-based solid of a case file (model.formulation: stress): particles, material
// law, options, boundary sets, floor and initial state, all from the validated CaseSpec.
#include <optional>
#include <string>

#include "breccia/mps/case_spec.hpp"
#include "breccia/mps/solid.hpp"

namespace breccia::mps {

// content_id (optional): the particle file's content id, "" for a lattice.
Solid make_solid(const CaseSpec& spec, std::string* content_id = nullptr);

// What the CUDA launcher of the stress formulation (cuda_solid.hpp) does not run, as the
// case key to change, what the case asks and what the launcher takes; nullopt when it runs
// the case. Decided from the case alone, so it holds with or without a GPU.
struct DeviceRefusal {
  std::string field, got, expected;
};
std::optional<DeviceRefusal> solid_device_refusal(const CaseSpec& spec);

}  // namespace breccia::mps
