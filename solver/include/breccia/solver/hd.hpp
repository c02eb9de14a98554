#pragma once
// BRECCIA_HD marks physics functions callable from host code and CUDA kernels alike:
// the physics is written once and both backends call it (docs/architecture.md).
#if defined(__CUDACC__)
#define BRECCIA_HD __host__ __device__ inline
#else
#define BRECCIA_HD inline
#endif
