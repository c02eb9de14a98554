#pragma once
// The number of time steps that reach an end time: ceil(end / dt), less a hair so that an end
// that is a whole number of steps in decimal is not one step more. Shared by PD and MPS.

#include <algorithm>
#include <cmath>
#include <string>

#include "breccia/common/error.hpp"
#include "breccia/common/units.hpp"

namespace breccia {

// More steps than any run makes (10^12: weeks at a microsecond a step) is a unit slip in the
// end time or the step ("1e-300 s"); refused by name, before anything is written, rather
// than a count that overflows and runs no step.
inline long long steps_to_reach(double end_s, double dt_s, const std::string& file, const std::string& field) {
  constexpr double kMostSteps = 1e12;
  const double n = std::ceil(end_s / dt_s - 1e-9);
  if (!(n <= kMostSteps))
    throw InputError(file, field, short_number(end_s) + " s in steps of " + short_number(dt_s) + " s",
                     "at most 10^12 steps (a unit slip in the end time or the step?)");
  return static_cast<long long>(std::max(n, 0.0));
}

}  // namespace breccia
