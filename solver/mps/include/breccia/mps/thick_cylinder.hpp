#pragma once
// Thick-walled cylinder under internal pressure, plane strain, with the stress-based solid:
// the verification problem behind tests/mps/test_solid.cpp (Lame, Hill) and the atlas rows
// (docs/atlas.md). A full ring of particles on concentric circles (a polar arrangement
// follows both surfaces, which a square lattice would staircase); the pressure is ramped
// over four breathing periods with damping at half the critical value, then held, so the
// end state is static.
#include <vector>

#include "breccia/mps/solid.hpp"

namespace breccia::mps {

struct ThickCylinder {
  double young_pa = 210e9, poisson = 0.3, density_kg_m3 = 7800;
  double yield_pa = 0.0;  // > 0: elastic-perfectly plastic (von Mises)
  double inner_m = 0.1, outer_m = 0.2;
  int rings = 10;         // circles of particles through the wall
  double pressure_pa = 50e6;
  PressureForce pressure_force = PressureForce::Conservative;
};

// Per circle of particles: radius, mean polar stresses, the largest deviation of a single
// particle from the circle's mean (scatter of the irregular stencils), share of plastic particles.
struct RingProfile {
  std::vector<double> radius, sigma_r, sigma_theta, scatter, plastic_share;
  double residual_kinetic_fraction = 0.0;  // kinetic energy / stress work at the end
  long long particles = 0, bonds = 0, steps = 0;
};

RingProfile load_thick_cylinder(const ThickCylinder& c);

// Lame (elastic) stresses at radius r: sigma_r, sigma_theta.
void lame_stresses(const ThickCylinder& c, double r, double& sigma_r, double& sigma_theta);

}  // namespace breccia::mps
