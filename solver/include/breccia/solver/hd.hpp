#pragma once
// BRECCIA_HD marks physics functions callable from host code and CUDA kernels alike:
// the physics is written once and both backends call it (docs/architecture.md).
#if defined(__CUDACC__)
#define BRECCIA_HD __host__ __device__ inline
#else
#define BRECCIA_HD inline
#endif

// BRECCIA_SIMD / BRECCIA_SIMD_COUNT(n): the host bond loops' `omp simd` hints (the second with an
// integer count summed over lanes, exact in any order). nvcc's host pass compiles the same
// headers without OpenMP, so there the hints are left out rather than warned about.
#define BRECCIA_PRAGMA(text) _Pragma(#text)
#if defined(__CUDACC__)
#define BRECCIA_SIMD
#define BRECCIA_SIMD_COUNT(n)
#else
#define BRECCIA_SIMD BRECCIA_PRAGMA(omp simd)
#define BRECCIA_SIMD_COUNT(n) BRECCIA_PRAGMA(omp simd reduction(+ : n))
#endif

// BRECCIA_UNROLL4: unroll the next loop (4 iterations at most) fully, on the host and the device,
// so that an index it runs over is a constant in each copy (registers, not memory).
#if defined(__CUDA_ARCH__)
#define BRECCIA_UNROLL4 BRECCIA_PRAGMA(unroll 4)
#elif defined(__CUDACC__)
#define BRECCIA_UNROLL4  // nvcc's host pass: the CPU build's loops are GCC's own
#else
#define BRECCIA_UNROLL4 BRECCIA_PRAGMA(GCC unroll 4)
#endif
