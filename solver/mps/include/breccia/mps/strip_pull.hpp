#pragma once
// The pull of a 2D strip by its two end columns (docs/atlas.md "MPS in tension"; the atlas's
// MPS tension study and the clumping detector's tests drive it alike): two particle columns at
// each end move as rigid grips, u_x = -/+ e(t) L / 2, with the strain ramped smoothly,
// e(t) = strain (s - sin(2 pi s) / (2 pi)), s = min(1, t / ramp), so that the velocity
// starts and stops at zero, then held.
#include <vector>

#include "breccia/mps/solid.hpp"

namespace breccia::mps {

struct StripPull {
  std::vector<int> left, right;  // the driven columns (reference x within 2 spacings of an end)
  double length_m = 0.0;
  double strain = 0.0;
  double ramp_s = 0.0;
};

// The grips of a strip [0, length] x ... with particle spacing `spacing` (reference positions).
StripPull strip_pull(const Solid& solid, double length_m, double spacing_m, double strain, double ramp_s);

// Sets the grips' displacement and velocity at the solid's current time (call after each step).
void drive_strip_pull(Solid& solid, const StripPull& pull);

}  // namespace breccia::mps
