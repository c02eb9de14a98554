// The bond passes of the OpenMP backend (BondForces, Dilatation: the step's costliest loops)
// with the widest vectors the host has, in a portable build. The same kernels (pd_kernels.hpp)
// are compiled twice here: for the x86-64 baseline (SSE2: two doubles per square root and
// division) and, behind a run-time check of the CPU, for AVX2 (four), which the fast loops'
// packed stages and the LPS passes run at the same time per instruction on the development
// machine (docs/performance.md). `flatten` inlines the whole kernel into the AVX2 copy, so
// every loop inside it is compiled for AVX2.
//
// Same results bit for bit: a square root, a division, a product and a sum are correctly
// rounded whatever the vector width, every sum keeps its order (pd_kernels.hpp, kBondChunk),
// and the AVX2 copy has no fused multiply-add (target "avx2" does not enable FMA, so GCC
// cannot contract a*b + c; checked with objdump: no vfmadd in these functions). The CUDA
// build never compiles this file; BRECCIA_NATIVE builds already target the host's vectors.
#include "breccia/solver/exec_openmp.hpp"

namespace breccia::solver {
namespace {

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__AVX2__)
#define BRECCIA_WIDE_ROWS 1
template <class F>
__attribute__((target("avx2"), flatten)) void row_avx2(const F& f, int64_t i) {
  f(i);
}
bool host_has_avx2() {
  static const bool has = __builtin_cpu_supports("avx2");
  return has;
}
#endif

template <class F>
void rows(int64_t n, const F& f) {
#if defined(BRECCIA_WIDE_ROWS)
  if (host_has_avx2()) {
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < n; ++i) row_avx2(f, i);
    return;
  }
#endif
#pragma omp parallel for schedule(static)
  for (int64_t i = 0; i < n; ++i) f(i);
}

}  // namespace

void wide_rows(int64_t n, const BondForces<double>& f) { rows(n, f); }
void wide_rows(int64_t n, const BondForces<float>& f) { rows(n, f); }
void wide_rows(int64_t n, const Dilatation<double>& f) { rows(n, f); }
void wide_rows(int64_t n, const Dilatation<float>& f) { rows(n, f); }

}  // namespace breccia::solver
