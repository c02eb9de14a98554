#pragma once
// Point sets for the bond families' tests (test_family_build.cpp, and the device's against the
// host's in tests/solver_cuda/test_cuda_families.cpp): positions, horizons and pads.
#include <cmath>
#include <random>
#include <vector>

namespace breccia::testing {

struct Cloud {
  std::vector<double> x, horizon, pad;
};

// A cubic lattice of n^3 points at spacing dx, horizon 3.015 dx (the bench lattice's) and a
// pad of half a cell diagonal (the partial-volume rule's reach on a lattice).
inline Cloud lattice(int n, double dx) {
  Cloud c;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        c.x.insert(c.x.end(), {i * dx, j * dx, k * dx});
        c.horizon.push_back(3.015 * dx);
        c.pad.push_back(0.5 * std::sqrt(3.0) * dx);
      }
  return c;
}

// Jittered points whose spacing grows 6x along x (horizon 3 spacings, pad up to half of
// one): horizons over more than two octaves, so several reach classes and their grids.
inline Cloud graded(size_t target) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.25, 0.25);
  Cloud c;
  const double s0 = 1.0 / std::cbrt(static_cast<double>(target)) / 2.5;
  for (double x = 0.0; x < 1.0;) {
    const double s = s0 * (1.0 + 5.0 * x);
    for (double y = 0.0; y < 0.5; y += s)
      for (double z = 0.0; z < 0.5; z += s) {
        c.x.insert(c.x.end(), {x + u(rng) * s, y + u(rng) * s, z + u(rng) * s});
        c.horizon.push_back(3.0 * s);
        c.pad.push_back((0.25 + u(rng)) * s);
      }
    x += s;
  }
  return c;
}

}  // namespace breccia::testing
