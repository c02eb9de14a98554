#pragma once
// The one launch of a BRECCIA_HD functor over [0, n), one GPU thread per index: every phase of
// the step (CudaExec, cuda_backend.cu) and the bond families' set-up kernels (cuda_families.cu)
// go through it. Only .cu files include this.
#include <cuda_runtime.h>

#include <cstdint>

#include "breccia/solver/cuda_memory.cuh"

namespace breccia::cuda {

constexpr int kLaunchBlock = 256;  // threads per block

template <class F>
__global__ void forall_cuda(int64_t n, F f) {
  const int64_t i = static_cast<int64_t>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (i < n) f(i);
}

// f(i) for every i in [0, n), in no particular order; the launch checked under `name`.
template <class F>
void for_each(int64_t n, const F& f, const char* name, bool synchronize) {
  if (n == 0) return;  // a grid of zero blocks is a launch error
  forall_cuda<F><<<(n + kLaunchBlock - 1) / kLaunchBlock, kLaunchBlock>>>(n, f);
  check_launch(name, synchronize);
}

}  // namespace breccia::cuda
