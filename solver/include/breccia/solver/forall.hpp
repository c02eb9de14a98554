#pragma once
// The CPU launcher: one kernel body, run over [0, n) with OpenMP threads.
#include <cstdint>

namespace breccia::solver {

template <class Body>
void for_each_particle(int64_t n, Body&& body) {
#pragma omp parallel for schedule(static)
  for (int64_t i = 0; i < n; ++i) body(i);
}

}  // namespace breccia::solver
