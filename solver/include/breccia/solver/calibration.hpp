#pragma once
// From engineering constants to peridynamic coefficients: micro-modulus, critical stretch,
// LPS coefficients. The continuum calibration integrals are written with the influence
// function's moments J_k = int_0^1 omega(q) q^k dq (docs/theory.md has the derivations).
#include <cmath>
#include <vector>

#include "breccia/solver/pd_physics.hpp"

namespace breccia::solver {

struct ElasticInput {
  int dimension = 3;
  Planar planar = Planar::None;
  double youngs_modulus = 0.0;
  double poisson_ratio = 0.25;
  double thickness = 1.0;  // 2D only
};

double influence_moment(Influence kind, int k);  // J_k

// Bulk modulus of the d-dimensional problem: K (3D), E/(2(1-nu)) plane stress,
// E/(2(1+nu)(1-2nu)) = lambda + mu plane strain.
double dimensional_bulk_modulus(const ElasticInput& in);
double shear_modulus(const ElasticInput& in);
// The Poisson ratio bond-based PD is tied to: 1/4 (3D, plane strain), 1/3 (plane stress).
double pmb_poisson_ratio(int dimension, Planar planar);

// Full (one-sided, textbook) PMB micro-modulus c0 such that the PD strain energy under
// isotropic expansion equals the classical one: c0 = 2 d^2 K_d / int_H omega |xi| dV.
double pmb_micromodulus(const ElasticInput& in, Influence kind, double horizon);
// Critical stretch from G0: energy of all bonds crossing a unit plane = G0.
double pmb_critical_stretch(const ElasticInput& in, Influence kind, double horizon, double fracture_energy);
// LPS critical stretch: the deviatoric pair energy of the crossing bonds equals G0
// (the dilatation term is not a pair energy; docs/theory.md states the approximation).
double lps_critical_stretch(const ElasticInput& in, Influence kind, double horizon, double fracture_energy);
// lps_critical_stretch with the material's and the influence function's factors taken once:
// the set-up asks it for every bond of a Weibull-drawn G0 (two calls each, 2 x 30 million on
// the full concrete case), and each call looked the moments up again. The same expression,
// the same operations in the same order: the same bits.
class LpsCriticalStretch {
 public:
  LpsCriticalStretch(const ElasticInput& in, Influence kind);
  // 3D: sqrt(G0 4 J4 / (15 mu delta J5)); 2D: sqrt(G0 pi J3 / (8 mu delta J4)).
  double operator()(double horizon, double fracture_energy) const {
    return std::sqrt(fracture_energy * energy_factor_ * energy_moment_ / (shear_factor_ * horizon * shear_moment_));
  }

 private:
  double energy_factor_, energy_moment_, shear_factor_, shear_moment_;
};
// Softening bonds (docs/theory.md "Quasi-brittle bonds"): the stretch at which a bond starts
// to soften, the uniaxial-stress strain at the tensile strength, sigma_t / E' (E' = E, in
// plane strain E / (1 - nu^2)).
double softening_onset_stretch(const ElasticInput& in, double tensile_strength);
// Peak uniaxial-stress of the model (PMB, or LPS for LPS and correspondence) at one material
// point strained homogeneously, its bonds following the bilinear law from `onset` to
// `ultimate`: the first maximum of sigma_xx as the strain grows (bonds of other orientations
// still load while the aligned ones soften, so it exceeds E' x onset). Continuum angular
// quadrature; linear in onset at a fixed ultimate / onset.
double homogeneous_tension_peak(const ElasticInput& in, PdModel model, double onset, double ultimate);
// The same point shortened in uniaxial stress: the peak compressive stress |sigma_xx| (> 0),
// its bonds softening in tension as above and, with crush_ratio > 0, crushing in compression
// at crush_ratio x onset to crush_ratio x ultimate (pd_kernels.hpp soften, one damage for both
// signs). Without crushing the lateral bonds' tension sets it (docs/theory.md "Crushing").
double homogeneous_compression_peak(const ElasticInput& in, PdModel model, double onset, double ultimate,
                                    double crush_ratio);
// The same point over a given family of bond directions instead of the isotropic continuum's:
// each bond's n_x^2 (the load along x) and its weight (LPS: omega beta V_j |xi|^2, the weight
// m sums). The lateral strain makes the mean lateral stress zero; for a lattice family (its
// y and z directions alike) that is uniaxial stress. Tells what the discrete family of a
// particle gives against the continuum (docs/theory.md "Crushing").
struct HomogeneousFamily {
  std::vector<double> axial2, weight;
};
double homogeneous_compression_peak(const ElasticInput& in, PdModel model, const HomogeneousFamily& family,
                                    double onset, double ultimate, double crush_ratio);
// The onset stretch whose homogeneous peak (above) is the tensile strength, the ultimate
// stretch being brittle_stretch^2 / onset (G0 kept): the law's calibration. Returns the
// uncalibrated sigma_t / E' when brittle_stretch is below it (the horizon is too large).
double calibrated_onset_stretch(const ElasticInput& in, PdModel model, double tensile_strength, double brittle_stretch);
LpsCoefficients lps_coefficients(const ElasticInput& in);

// Classical strain energy density for a small strain tensor eps (3x3 row-major, plane
// problems use the 2x2 block), used by tests and by the energy surface correction.
double classical_energy_density(const ElasticInput& in, const double eps[9]);

}  // namespace breccia::solver
