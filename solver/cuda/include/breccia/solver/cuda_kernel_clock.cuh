#pragma once
// Per-kernel GPU times with CUDA events (breccia-solve --kernel-times WARMUP; docs/cuda.md,
// "Per-kernel times"). Each timed launch is bracketed by a start and a stop event on the
// default stream; the pairs are resolved in batches of kPairs (one cudaEventSynchronize per
// batch, none per step), and their elapsed times summed per launch name into a
// KernelTimeTable. Only .cu files include this.
#include <cuda_runtime.h>

#include <cstdint>
#include <optional>
#include <vector>

#include "breccia/solver/cuda_memory.cuh"
#include "breccia/solver/kernel_times.hpp"

namespace breccia::cuda {

class KernelClock {
public:
  static constexpr int kPairs = 256;  // events resolved per batch: a few dozen steps' launches

  KernelClock() = default;
  KernelClock(const KernelClock&) = delete;
  KernelClock& operator=(const KernelClock&) = delete;
  ~KernelClock() {
    for (cudaEvent_t e : start_) cudaEventDestroy(e);
    for (cudaEvent_t e : stop_) cudaEventDestroy(e);
  }

  // Time every launch from `warmup_steps` steps on (counted by step_begins from now).
  void start(int64_t warmup_steps) {
    if (start_.empty()) {
      start_.resize(kPairs);
      stop_.resize(kPairs);
      for (int k = 0; k < kPairs; ++k) {
        check(cudaEventCreate(&start_[k]), "cudaEventCreate (kernel times)");
        check(cudaEventCreate(&stop_[k]), "cudaEventCreate (kernel times)");
      }
      name_.resize(kPairs, nullptr);
    }
    on_ = true;
    warmup_ = warmup_steps;
    steps_seen_ = 0;
    recording_ = false;
  }
  // A step's launches are timed once the warm-up is over; whole steps only.
  void step_begins() {
    recording_ = on_ && steps_seen_ >= warmup_;
    ++steps_seen_;
  }
  void step_ends() {
    if (recording_) table_.step_done();
  }
  // Around one launch (or a reduction's two) named `name` (a string literal: kept by pointer).
  void before() {
    if (recording_) check(cudaEventRecord(start_[pending_]), "cudaEventRecord (kernel times)");
  }
  void after(const char* name) {
    if (!recording_) return;
    check(cudaEventRecord(stop_[pending_]), "cudaEventRecord (kernel times)");
    name_[pending_] = name;
    if (++pending_ == kPairs) resolve();
  }
  std::optional<solver::KernelTimes> times() {
    if (!on_) return std::nullopt;
    resolve();
    return table_.times(warmup_);
  }

private:
  void resolve() {
    if (pending_ == 0) return;
    check(cudaEventSynchronize(stop_[pending_ - 1]), "cudaEventSynchronize (kernel times)");
    for (int k = 0; k < pending_; ++k) {
      float ms = 0.0f;
      check(cudaEventElapsedTime(&ms, start_[k], stop_[k]), "cudaEventElapsedTime (kernel times)");
      table_.add(name_[k], 1e-3 * ms);
    }
    pending_ = 0;
  }

  bool on_ = false, recording_ = false;
  int64_t warmup_ = 0, steps_seen_ = 0;
  std::vector<cudaEvent_t> start_, stop_;
  std::vector<const char*> name_;
  int pending_ = 0;
  solver::KernelTimeTable table_;
};

}  // namespace breccia::cuda
