#pragma once
// Crack faces with Coulomb friction ([MPS harmonics] eqs 9-10, docs/references.md), 2D in-plane.
// A crack is a segment; continuum bonds crossing it are removed, and each particle on the
// + side facing a particle on the - side (mirror images across the segment) forms a pair.
//
// Superposition with a static pre-stress: the faces are clamped by a uniform compressive
// normal stress sigma0 (normal_stress), in equilibrium with a static field that is not
// simulated; the dynamic problem carries only the perturbation. The total normal force of a
// pair is N = N0 - kn g_n (N0 = sigma0 * face area, g_n the dynamic normal opening). The
// force applied to the particles is the perturbation N - N0, so a closed, sticking crack
// transmits the wave like the continuum, and the friction limit uses the total N.
#include <cstdint>
#include <string>
#include <vector>

#include "breccia/mps/case_spec.hpp"
#include "breccia/mps/kernels.hpp"
#include "breccia/mps/neighbours.hpp"

namespace breccia::mps {

struct FrictionLaw {
  double static_mu = 0.0;
  double kinetic_mu = 0.0;
  double shear_stiffness_n_m = 0.0;   // ks
  double normal_stiffness_n_m = 0.0;  // kn (no interpenetration: penalty spring)
  double preload_n = 0.0;             // N0 = sigma0 * face area
  bool clapping = false;              // faces may open: N = max(0, N0 - kn g_n)
  bool restick_continuous = false;    // see friction_pair_force
};

struct PairState {
  std::int8_t slipping = 0;  // 0 stick, 1 slip
  std::int8_t open = 0;
  double stick_reference_m = 0.0;  // tangential relative displacement at the first step of stick
  double friction_direction = 0.0; // sign of the friction force on the + particle while slipping
  double shear_force_n = 0.0;      // last tangential force on the + particle
  double normal_force_n = 0.0;     // last total (static + dynamic) compressive normal force
};

struct PairForce {
  double normal_n = 0.0;   // dynamic force on the + particle along the crack normal
  double tangent_n = 0.0;  // force on the + particle along the crack tangent
};

// One pair, one step. gap_n, slide_s: dynamic relative displacement (+ minus -) along the
// normal and tangent; slide_velocity: relative tangential velocity.
// Transitions (eq 9): stick -> slip when |Fs| >= mu_s |Fn| (here: >, see below); slip -> stick when the relative
// tangential velocity changes sign, i.e. no longer opposes the friction force.
// Forces (eq 10): stick Fs = -ks (slide - slide_c) (spring from the stick reference);
// slip |Fs| = mu_k |Fn| opposing the sliding. At re-stick the paper resets the reference, so
// the spring force restarts from zero; restick_continuous instead keeps the friction force
// continuous (reference shifted by Fs/ks), the rigid-plastic interface of the 1D theory.
BRECCIA_HD inline PairForce friction_pair_force(const FrictionLaw& law, double gap_n, double slide_s,
                                                double slide_velocity, PairState& st) {
  double normal = law.preload_n - law.normal_stiffness_n_m * gap_n;
  st.open = 0;
  if (law.clapping && normal <= 0.0) {
    normal = 0.0;
    st.open = 1;
  }
  PairForce f;
  f.normal_n = normal - law.preload_n;
  st.normal_force_n = normal;
  if (st.open) {  // separated faces carry no friction; re-contact starts in stick
    st.slipping = 0;
    st.stick_reference_m = slide_s;
    st.shear_force_n = 0.0;
    return f;
  }
  const double limit_static = law.static_mu * (normal < 0 ? -normal : normal);
  const double limit_kinetic = law.kinetic_mu * (normal < 0 ? -normal : normal);
  if (st.slipping && slide_velocity * st.friction_direction > 0.0) {
    st.slipping = 0;
    st.stick_reference_m = law.restick_continuous ? slide_s + st.shear_force_n / law.shear_stiffness_n_m : slide_s;
  }
  if (!st.slipping) {
    const double spring = -law.shear_stiffness_n_m * (slide_s - st.stick_reference_m);
    // Strictly above the limit: a continuous re-stick starts the spring at mu_k |Fn|, which
    // for mu_k = mu_s sits exactly on the limit and must not flip straight back to slip.
    if ((spring < 0 ? -spring : spring) <= limit_static) {
      f.tangent_n = spring;
      st.shear_force_n = spring;
      return f;
    }
    st.slipping = 1;
    st.friction_direction = spring > 0 ? 1.0 : -1.0;
  }
  f.tangent_n = st.friction_direction * limit_kinetic;
  st.shear_force_n = f.tangent_n;
  return f;
}

// Non-owning view of the pairs (below) for the per-pair function: raw pointers, so the CPU
// loop and the CUDA pair kernel share it. law: per crack; state: per pair, updated.
struct CrackPairsView {
  long long count = 0;
  const int* plus = nullptr;
  const int* minus = nullptr;
  const int* crack = nullptr;
  const double* normal_x = nullptr;
  const double* normal_y = nullptr;
  const double* tangent_x = nullptr;
  const double* tangent_y = nullptr;
  const FrictionLaw* law = nullptr;
  PairState* state = nullptr;
};

// Friction force of pair p on its + particle (x, y; the - particle receives the opposite),
// from the relative displacement and velocity of the two particles; advances `st`, the
// pair's state (a copy of it when the caller only probes the force).
BRECCIA_HD inline void crack_pair_force_at(long long p, const CrackPairsView& c, VectorField u, VectorField v,
                                           PairState& st, double force[2]) {
  const int i = c.plus[p], j = c.minus[p];
  const double nx = c.normal_x[p], ny = c.normal_y[p], sx = c.tangent_x[p], sy = c.tangent_y[p];
  const double gx = u.x[i] - u.x[j], gy = u.y[i] - u.y[j];
  const double vs = (v.x[i] - v.x[j]) * sx + (v.y[i] - v.y[j]) * sy;
  const PairForce f = friction_pair_force(c.law[c.crack[p]], gx * nx + gy * ny, gx * sx + gy * sy, vs, st);
  force[0] = f.normal_n * nx + f.tangent_n * sx;
  force[1] = f.normal_n * ny + f.tangent_n * sy;
}

// Add a pair force to the acceleration of one of its particles (mass = rho V): +force on the
// + particle, -force on the - particle. A particle in several pairs must receive them in pair
// order on every backend for the sums to round alike.
BRECCIA_HD inline void add_pair_acceleration(double& ax, double& ay, const double force[2], double mass, bool plus_side) {
  if (plus_side) {
    ax += force[0] / mass;
    ay += force[1] / mass;
  } else {
    ax -= force[0] / mass;
    ay -= force[1] / mass;
  }
}

// All pairs of all cracks, structure of arrays.
struct CrackPairs {
  std::vector<int> plus, minus;  // particle indices; + side is left of start->end
  std::vector<int> crack;        // crack index per pair
  std::vector<double> normal_x, normal_y, tangent_x, tangent_y;
  std::vector<FrictionLaw> law;  // per crack
  std::vector<std::string> name; // per crack
  std::vector<PairState> state;  // per pair
  size_t size() const { return plus.size(); }
  CrackPairsView view() {
    return {static_cast<long long>(size()), plus.data(), minus.data(), crack.data(), normal_x.data(), normal_y.data(),
            tangent_x.data(), tangent_y.data(), law.data(), state.data()};
  }
};

// Each particle's pairs, in pair order (CSR over the particles that belong to a pair): a
// launcher that adds the pair forces per particle (one thread each, no atomics) adds them in
// the order of the CPU loop over pairs, so a particle in several pairs (cracks one row apart)
// sums them alike on both backends.
struct PairIncidence {
  std::vector<int> particle;            // particles in at least one pair, by first appearance
  std::vector<long long> offset{0};     // entries of particle[q]: [offset[q], offset[q+1])
  std::vector<int> pair;                // pair index, ascending within a particle
  std::vector<unsigned char> plus_side; // 1: the particle is that pair's + particle
};
PairIncidence pair_incidence(const CrackPairs& pairs);

// Build the pairs of every crack of the case and remove the continuum bonds crossing the
// crack segments. Throws InputError when a crack finds no particle pairs (outside the body)
// or passes through particle centres.
CrackPairs build_crack_pairs(const CaseSpec& spec, const std::vector<double>& position_m, double spacing_m,
                             double face_depth_m, const Periodicity& periodic, BondList& bonds);

}  // namespace breccia::mps
