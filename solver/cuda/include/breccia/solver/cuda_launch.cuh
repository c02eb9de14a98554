#pragma once
// The one launch of a BRECCIA_HD functor over [0, n), one GPU thread per index: every phase of
// the step (CudaExec, cuda_backend.cu) and the bond families' set-up kernels (cuda_families.cu)
// go through it. Only .cu files include this.
#include <cuda_runtime.h>

#include <cstdint>

#include "breccia/solver/cuda_memory.cuh"

namespace breccia::cuda {

constexpr int kLaunchBlock = 256;  // threads per block

// Launch bounds: a functor that declares `kMinBlocksPerSm` (the bond force passes: step.hpp,
// sell_kernels.hpp) runs in forall_cuda_bounded, which asks for that many blocks of kLaunchBlock
// resident per SM, so the compiler keeps it within 65,536 / (kLaunchBlock x kMinBlocksPerSm)
// registers. Without it the PMB and dual-horizon force kernels took 130-154 registers (one block
// of 256 per SM, 8 warps of 64); with 2 no fast path spills (scripts/cuda_registers.sh,
// docs/cuda.md "Registers"). The other kernels keep no bound: with one, even (256, 1), the
// compiler gave the small ones up to twice the registers they take without. Not yet timed on a GPU.
// (__launch_bounds__ must sit on the kernel's own declaration, so the two kernels share their
// body through this.)
template <class F>
__device__ __forceinline__ void call_at_thread_index(int64_t n, const F& f) {
  const int64_t i = static_cast<int64_t>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (i < n) f(i);
}
template <class F>
__global__ void forall_cuda(int64_t n, F f) {
  call_at_thread_index(n, f);
}
template <class F>
__global__ void __launch_bounds__(kLaunchBlock, F::kMinBlocksPerSm) forall_cuda_bounded(int64_t n, F f) {
  call_at_thread_index(n, f);
}

// f(i) for every i in [0, n), in no particular order; the launch checked under `name`.
template <class F>
void for_each(int64_t n, const F& f, const char* name, bool synchronize) {
  if (n == 0) return;  // a grid of zero blocks is a launch error
  const int64_t blocks = (n + kLaunchBlock - 1) / kLaunchBlock;
  if constexpr (requires { F::kMinBlocksPerSm; }) forall_cuda_bounded<F><<<blocks, kLaunchBlock>>>(n, f);
  else forall_cuda<F><<<blocks, kLaunchBlock>>>(n, f);
  check_launch(name, synchronize);
}

}  // namespace breccia::cuda
