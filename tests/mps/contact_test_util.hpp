#pragma once
// What the contact tests (test_contact.cpp, test_contact_particles.cpp) share: a soft law for
// quick gravity-driven runs, the energy total their balances check, and the straight-line
// fit that reads a sliding body's deceleration.
#include "breccia/mps/solid.hpp"

namespace breccia::mps::test {

// E = 1 MPa, nu = 0.3: c_L = 37 m/s, so g-driven runs take few steps.
inline SolidLaw soft_law() {
  const double e = 1e6, nu = 0.3;
  SolidLaw law;
  law.lame_lambda_pa = e * nu / ((1 + nu) * (1 - 2 * nu));
  law.shear_modulus_pa = e / (2 * (1 + nu));
  return law;
}

// Kinetic + stored (stress work, hourglass, contact) + potential + what friction dissipated:
// constant when the run conserves energy.
inline double total_energy(const Solid& s) {
  return s.kinetic_energy_j() + s.stress_work_j() + s.hourglass_energy_j() + s.contact_energy_j() + s.gravity_energy_j() +
         s.friction_dissipation_j();
}

// Least-squares straight line through (t, v) samples: the friction tests read a sliding
// body's deceleration as minus the slope of its velocity over the sliding phase.
struct LineFit {
  double st = 0, sv = 0, stt = 0, stv = 0, count = 0;
  void add(double t, double v) {
    st += t;
    sv += v;
    stt += t * t;
    stv += t * v;
    count += 1;
  }
  double slope() const { return (count * stv - st * sv) / (count * stt - st * st); }
};

}  // namespace breccia::mps::test
