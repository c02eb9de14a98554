#pragma once
// Run-time detector of particle clumping in the stress-based MPS solid (docs/mps.md,
// docs/atlas.md "MPS in tension"). SPH-type particle methods under tension can pair
// particles up (the tensile instability) or, without hourglass control, let the zero-energy
// modes of a particle-wise gradient grow: in both, neighbours move in a way the particle's
// own deformation gradient F does not explain. The measure is, over the nearest-neighbour
// bonds (reference length below 1.5 spacings), the current length against |F_i r_ij|: it is
// exactly 1 for any homogeneous deformation, tension or compression, and falls when
// neighbours clump together. Only bonds shorter than their reference length count: particles
// moved as one rigid block (driven or held ends) next to a stretching region keep their
// bonds' length while F_i, fitted over a stencil reaching into the stretch, predicts more;
// they read 1 / (1 + strain) without being clumped (docs/atlas.md "MPS in tension").
// Bonds between two crack-face particles (each with a cut nearest-neighbour bond) are not
// measured either: F fitted on a one-sided stencil does not follow a flank sliding and
// closing ahead of a crack tip, and the fracture model detaches a face particle that inverts
// or keeps a remnant stencil (docs/mps.md "Clumping detector"). Bonds from an intact particle
// to a face particle are measured, so pairing next to a crack is still caught.
#include <cstdint>

#include "breccia/mps/solid.hpp"

namespace breccia::mps {

// A neighbour at less than this share of the distance its particle's F predicts.
inline constexpr double kMinNeighbourDistanceRatio = 0.5;
// How often Solid::step runs the check (steps): the measure costs one pass over the bonds
// (a step costs several); the atlas saw clumping grow from 0.5 to 0.1 within ~10-20 steps.
inline constexpr long long kClumpingCheckEvery = 10;

struct Clumping {
  double min_ratio = 1.0;        // min over shortened nearest-neighbour bonds of |x_j - x_i| / |F_i r_ij|
  long long worst_particle = -1;
  long long clumped_bonds = 0;   // bonds below kMinNeighbourDistanceRatio
  long long skipped_face_bonds = 0;  // bonds between two crack-face particles below it (not counted)
};

Clumping measure_clumping(const Solid& solid);

// Throws RunError naming the time, the worst particle and the keys that help
// (model.hourglass, model.pressure_force, refinement) when a bond is below the limit.
void require_no_clumping(const Solid& solid);

}  // namespace breccia::mps
