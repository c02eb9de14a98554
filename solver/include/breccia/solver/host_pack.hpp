#pragma once
// Packs of doubles for the host's hand-packed bond loops (pd_kernels.hpp, pmb_packed_row):
// GCC's vector extension (the arithmetic operators act lane by lane, each lane rounding as the
// scalar operation does), in two widths: PackD2, 2 lanes (SSE2, every x86-64), and PackD4,
// 4 lanes (AVX). The square root and the float-to-double widening, which the extension does not
// provide, are the instructions the scalar code compiles to, lane by lane (sqrtpd: correctly
// rounded; cvtps2pd: exact). Neither width has a fused multiply-add (AVX without FMA cannot
// contract), so both give every lane the scalar loop's bits.
//
// Which width runs (on_host_pack): a build that targets AVX (BRECCIA_NATIVE on such a host)
// runs PackD4 everywhere; the portable build compiles the PackD4 rows as well, in functions of
// their own compiled for AVX (BRECCIA_TARGET_AVX, everything they call inlined into them), and
// runs them where the CPU has AVX (host_runs_avx, asked once), PackD2 elsewhere. On this
// project's CPU a 256-bit square root or division takes the time of a 128-bit one, and those
// bound the PMB loop (docs/performance-log.md, "The packed rows 4 wide, four partial sums").
// Not compiled for the device, nor where the build targets no x86 SIMD (BRECCIA_HOST_PACK
// undefined: the loops that use it are skipped).
#if !defined(__CUDACC__) && defined(__SSE2__)
#include <immintrin.h>

#include <cmath>
#include <cstdint>
#include <cstring>

#define BRECCIA_HOST_PACK 1
// The AVX rows' functions: compiled for AVX in any build; always_inline helpers are inlined
// into them (a helper without the attribute may be inlined into an AVX function, never the
// reverse), so no 256-bit value crosses a call between code of the two targets.
#define BRECCIA_TARGET_AVX __attribute__((target("avx")))
#define BRECCIA_PACK_INLINE inline __attribute__((always_inline))

// GCC warns that a 32-byte vector returned without AVX enabled changes the ABI (-Wpsabi): the
// helpers below are always inlined, into AVX functions for PackD4, so no such value crosses a call.
// The note is silenced for the rest of the including file, not popped at this header's end: GCC
// emits it when it writes the instantiations out, at the end of the translation unit.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace breccia::solver {

typedef double PackD2 __attribute__((vector_size(16)));
typedef double PackD4 __attribute__((vector_size(32)));
// The lanes of a pack, and the lanes' comparison result (all bits set where true).
template <class P>
inline constexpr int kPackLanes = static_cast<int>(sizeof(P) / sizeof(double));
template <class P>
using PackMaskOf = decltype(P{} > P{});
// A width as a value (on_host_pack's argument): no vector crosses the call.
template <class P>
struct PackKind {
  using type = P;
};

BRECCIA_PACK_INLINE PackD2 sqrt_of(PackD2 v) { return reinterpret_cast<PackD2>(_mm_sqrt_pd(reinterpret_cast<__m128d>(v))); }
BRECCIA_TARGET_AVX inline PackD4 sqrt_of(PackD4 v) {
  return reinterpret_cast<PackD4>(_mm256_sqrt_pd(reinterpret_cast<__m256d>(v)));
}
// The lanes' floats from s, each widened to double (the second argument picks the width).
BRECCIA_PACK_INLINE PackD2 widen_floats(const float* s, PackD2) {
  double two;  // the two floats' bytes, loaded as one 8-byte value
  std::memcpy(&two, s, sizeof two);
  return reinterpret_cast<PackD2>(_mm_cvtps_pd(_mm_castpd_ps(_mm_set_sd(two))));
}
BRECCIA_TARGET_AVX inline PackD4 widen_floats(const float* s, PackD4) {
  return reinterpret_cast<PackD4>(_mm256_cvtps_pd(_mm_loadu_ps(s)));
}

// The lanes' consecutive doubles from s (any alignment).
template <class P>
BRECCIA_PACK_INLINE P load_pack(const double* s) {
  P v;
  std::memcpy(&v, s, sizeof v);
  return v;
}

// a[stride * index[l] + c] for the lanes l: component c of xyz-interleaved coordinates
// (stride 3), or a per-particle value (stride 1, c 0) of the entries' neighbours. One
// initialiser: lanes stored one by one and loaded as a pack stall the load on the stores.
template <class P>
BRECCIA_PACK_INLINE P gather_pack(const double* a, const int32_t* index, int stride, int c) {
  if constexpr (kPackLanes<P> == 4)
    return P{a[stride * int64_t(index[0]) + c], a[stride * int64_t(index[1]) + c], a[stride * int64_t(index[2]) + c],
             a[stride * int64_t(index[3]) + c]};
  else
    return P{a[stride * int64_t(index[0]) + c], a[stride * int64_t(index[1]) + c]};
}

template <class M>
BRECCIA_PACK_INLINE bool any_lane(M m) {
  bool any = false;
  for (int l = 0; l < static_cast<int>(sizeof(M) / sizeof(m[0])); ++l) any |= m[l] != 0;
  return any;
}

// Does this CPU run AVX (and its operating system keep the 256-bit registers)? Asked once.
inline bool host_runs_avx() {
#if defined(__AVX__)
  return true;
#else
  static const bool avx = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx") != 0;
  }();
  return avx;
#endif
}

// row(PackKind<P>{}) with the widest pack this CPU runs: PackD4 through an AVX function (the
// row, and all it calls, inlined into it: `flatten`) where host_runs_avx, else PackD2.
template <class Row>
BRECCIA_TARGET_AVX __attribute__((flatten)) inline auto on_avx_pack(const Row& row) {
  return row(PackKind<PackD4>{});
}
template <class Row>
inline auto on_host_pack(const Row& row) {
#if defined(__AVX__)
  return row(PackKind<PackD4>{});
#else
  if (host_runs_avx()) return on_avx_pack(row);
  return row(PackKind<PackD2>{});
#endif
}

}  // namespace breccia::solver

#endif
