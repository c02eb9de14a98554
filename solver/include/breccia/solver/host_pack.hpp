#pragma once
// A pack of doubles for the host's hand-packed bond loops (pd_kernels.hpp, pmb_packed_row):
// GCC's vector extension (the arithmetic operators act lane by lane, each lane rounding as the
// scalar operation does), 2 lanes on the x86-64 baseline (SSE2), 4 where the build targets AVX
// (BRECCIA_NATIVE on such a host). The square root and the float-to-double widening, which the
// extension does not provide, are the instructions the scalar code compiles to, lane by lane
// (sqrtpd: correctly rounded; cvtps2pd: exact). Not compiled for the device, nor where the
// build targets no x86 SIMD (BRECCIA_HOST_PACK undefined: the loops that use it are skipped).
#if !defined(__CUDACC__) && defined(__SSE2__)
#include <immintrin.h>

#include <cmath>
#include <cstdint>
#include <cstring>

#define BRECCIA_HOST_PACK 1

namespace breccia::solver {

#if defined(__AVX__)
inline constexpr int kPackWidth = 4;
typedef double PackD __attribute__((vector_size(32)));
inline PackD sqrt_of(PackD v) { return reinterpret_cast<PackD>(_mm256_sqrt_pd(reinterpret_cast<__m256d>(v))); }
// kPackWidth floats from s, each widened to double.
inline PackD widen_floats(const float* s) { return reinterpret_cast<PackD>(_mm256_cvtps_pd(_mm_loadu_ps(s))); }
#else
inline constexpr int kPackWidth = 2;
typedef double PackD __attribute__((vector_size(16)));
inline PackD sqrt_of(PackD v) { return reinterpret_cast<PackD>(_mm_sqrt_pd(reinterpret_cast<__m128d>(v))); }
inline PackD widen_floats(const float* s) {
  double two;  // the two floats' bytes, loaded as one 8-byte value
  std::memcpy(&two, s, sizeof two);
  return reinterpret_cast<PackD>(_mm_cvtps_pd(_mm_castpd_ps(_mm_set_sd(two))));
}
#endif
// The lanes' comparison result (all bits set where true).
using PackMask = decltype(PackD{} > PackD{});

// kPackWidth consecutive doubles from s (any alignment).
inline PackD load_pack(const double* s) {
  PackD v;
  std::memcpy(&v, s, sizeof v);
  return v;
}

// a[stride * index[l] + c] for the kPackWidth lanes l: component c of xyz-interleaved
// coordinates (stride 3), or a per-particle value (stride 1, c 0) of the entries' neighbours.
// One initialiser: lanes stored one by one and loaded as a pack stall the load on the stores.
inline PackD gather_pack(const double* a, const int32_t* index, int stride, int c) {
#if defined(__AVX__)
  return PackD{a[stride * int64_t(index[0]) + c], a[stride * int64_t(index[1]) + c], a[stride * int64_t(index[2]) + c],
               a[stride * int64_t(index[3]) + c]};
#else
  return PackD{a[stride * int64_t(index[0]) + c], a[stride * int64_t(index[1]) + c]};
#endif
}

inline bool any_lane(PackMask m) {
  bool any = false;
  for (int l = 0; l < kPackWidth; ++l) any |= m[l] != 0;
  return any;
}

}  // namespace breccia::solver
#endif
