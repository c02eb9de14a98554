#pragma once
// Particles of several bodies (specimen.bodies): each shape becomes its own particles, a
// particle set named after the body (usable in boundary: set: NAME), and a body id that
// keeps bonds inside one body (solid.hpp) and turns contact on between bodies (contact.hpp).
#include "breccia/mps/case_spec.hpp"
#include "breccia/mps/particles.hpp"

namespace breccia::mps {

// Throws InputError (specimen.bodies.shapes[k]) for bodies that overlap at the start:
// particles of two bodies closer than the contact distance.
ParticleCloud build_bodies_cloud(const CaseSpec& spec);

}  // namespace breccia::mps
