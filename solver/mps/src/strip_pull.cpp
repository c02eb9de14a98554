#include "breccia/mps/strip_pull.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace breccia::mps {

StripPull strip_pull(const Solid& solid, double length_m, double spacing_m, double strain, double ramp_s) {
  StripPull p;
  p.length_m = length_m;
  p.strain = strain;
  p.ramp_s = ramp_s;
  const std::vector<double>& pos = solid.position_m();
  for (size_t i = 0; i < solid.size(); ++i) {
    if (pos[3 * i] < 2 * spacing_m) p.left.push_back(static_cast<int>(i));
    if (pos[3 * i] > length_m - 2 * spacing_m) p.right.push_back(static_cast<int>(i));
  }
  return p;
}

void drive_strip_pull(Solid& solid, const StripPull& p) {
  constexpr double pi = std::numbers::pi;
  const double t = solid.time_s(), s = std::min(1.0, t / p.ramp_s);
  const double e = p.strain * (s - std::sin(2 * pi * s) / (2 * pi));  // smooth start and stop
  const double de = t < p.ramp_s ? p.strain * (1 - std::cos(2 * pi * s)) / p.ramp_s : 0.0;
  for (int i : p.left) {
    solid.displacement(0)[i] = -0.5 * e * p.length_m;
    solid.velocity(0)[i] = -0.5 * de * p.length_m;
  }
  for (int i : p.right) {
    solid.displacement(0)[i] = 0.5 * e * p.length_m;
    solid.velocity(0)[i] = 0.5 * de * p.length_m;
  }
}

}  // namespace breccia::mps
