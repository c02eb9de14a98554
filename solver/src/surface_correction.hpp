#pragma once
// The energy surface correction's pieces shared by PMB (setup.cpp) and LPS
// (surface_correction.cpp): Le & Bobaru 2018, in the directional form of Madenci & Oterkus
// 2014 (docs/theory.md, "Surface correction").
#include <cmath>
#include <cstdint>
#include <vector>

#include "breccia/solver/calibration.hpp"
#include "breccia/solver/distributed_setup.hpp"
#include "breccia/solver/pd_system.hpp"

namespace breccia::solver {

// The factor of entry k (particle i's bond to neighbour j): per axis the mean of its two ends'
// axis factors (3 per particle), combined over the bond's direction n as an ellipsoid,
// 1 / sqrt(sum_a n_a^2 / g_a^2). The same for (i, j) and (j, i), so forces stay antisymmetric.
inline double ellipsoid_bond_factor(const PdSystem& s, const std::vector<double>& axis_factor, size_t i, int64_t k) {
  const int32_t j = s.neighbor[k];
  double inv2 = 0.0;
  for (int a = 0; a < s.dimension; ++a) {
    const double na = (s.x0[3 * j + a] - s.x0[3 * i + a]) / s.xi_len[k];
    const double g = 0.5 * (axis_factor[3 * i + a] + axis_factor[3 * j + a]);
    inv2 += na * na / (g * g);
  }
  return 1.0 / std::sqrt(inv2);
}

// Both halves of every entry's coefficient (k_own, k_dual) times its ellipsoidal factor: the
// last step of either correction, once its axis factors are settled.
void scale_bonds_by_axis_factors(PdSystem& s, const std::vector<double>& axis_factor);

// LPS's energy surface correction (model.surface_correction: energy with type: lps). LPS
// normalises each family by its own weighted volume m, so a factor common to a family's bonds
// cancels in its weights: a truncated family errs in their shape (its bonds along a face are
// over-represented, so it is too stiff along the face), and its magnitude is set by its own
// coefficients. Each particle gets a factor per axis, shaping its bonds' weights omega beta
// (k_own, k_dual, multiplied by the ellipsoidal blend of the two ends' factors), and a scale
// of its LPS coefficients (returned, one per particle), chosen so that its LPS energy under
// unit uniaxial strain along each axis is the bulk value. m, the dilatation and the critical
// stretches are then computed from the corrected weights as before (run it before them).
// A distributed set-up (rows active) computes its own rows and takes the ghosts' factors and
// the complete families' energies from every rank (distributed_setup.hpp): one process's bits.
std::vector<double> lps_surface_correction(PdSystem& s, const std::vector<ElasticInput>& elastic,
                                           const DistributedSetup& dist, const DistributedRows& rows);

}  // namespace breccia::solver
