#pragma once
// Contact of a case (contact.particles, contact.rigid_bodies, per-body initial velocities)
// set up on a constructed solid; called by make_solid (solid_case.cpp).
#include <vector>

#include "breccia/mps/case_spec.hpp"
#include "breccia/mps/solid.hpp"

namespace breccia::mps {

// body_id: per particle (empty: one body). Throws InputError for a rigid polygon that
// holds particles at the start (contact.rigid_bodies[k].vertices).
void configure_contact(const CaseSpec& spec, const std::vector<int>& body_id, Solid& solid);

}  // namespace breccia::mps
