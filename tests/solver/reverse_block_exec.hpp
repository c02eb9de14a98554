#pragma once
// An execution space for step.hpp that launches every loop in reverse order and sums in
// blocks, as a GPU's threads may run and its reductions do, and takes the gas load's device
// path (gas.hpp GasBuffers: a thread per particle, then the blocks folded). A step it drives
// must equal the OpenMP backend's bit for bit: what the CUDA backend's agreement rests on,
// checked without a GPU (test_step_emulation.cpp, test_gas.cpp).
#include <algorithm>
#include <cstdint>
#include <vector>

#include "breccia/solver/exec_openmp.hpp"
#include "breccia/solver/step.hpp"

namespace breccia::solver::testing {

class ReverseBlockExec {
public:
  explicit ReverseBlockExec(PdSystem& sys) : host_(sys) {}
  template <class F>
  void for_each(int64_t n, const F& f, const char*) const {
    for (int64_t i = n - 1; i >= 0; --i) f(i);
  }
  // Partial sums over grid-stride blocks of 256, folded in block order (the device's pattern).
  template <class Load, class Finish>
  void reduce(int64_t n, const Load& load, const Finish& finish, const char*) const {
    using Value = typename Load::Value;
    constexpr int64_t kBlocks = 7, kThreads = 256;
    Value total = Load::identity();
    for (int64_t b = 0; b < kBlocks; ++b) {
      Value block = Load::identity();
      for (int64_t t = 0; t < kThreads; ++t)
        for (int64_t k = b * kThreads + t; k < n; k += kBlocks * kThreads) block = Load::combine(block, load(k));
      total = Load::combine(total, block);
    }
    finish(total);
  }
  template <class Real>
  void commit_min_stretch(StepArrays<Real>& a) const { host_.commit_min_stretch(a); }
  template <class Real>
  void contact(const StepArrays<Real>& a) const { host_.contact(a); }
  // The gas's per-particle terms into a buffer of this space's own, as the CUDA backend does.
  GasBuffers gas_buffers(GasState& gas) const {
    GasBuffers b = host_gas_buffers(gas);
    particle_sums_.resize(std::max(gas.kappa_volume.size() / 2, gas.wall_dv.size()));
    b.particle_sums = particle_sums_.data();
    return b;
  }
  const GasSums* gas_block_sums_on_host(GasState&, const GasSums* sums, int64_t) const { return sums; }

private:
  OpenMpExec host_;
  mutable std::vector<GasSums> particle_sums_;
};

}  // namespace breccia::solver::testing
