#pragma once
// Per-kernel GPU times of a run (`breccia-solve --kernel-times WARMUP`, CUDA backend): after
// WARMUP steps every launch of the step is bracketed by two CUDA events, and the elapsed times
// are summed per kernel name (docs/cuda.md, "Per-kernel times"). This header is the host side:
// the table the events are summed into and what summary.json reports, testable without a GPU.
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace breccia::solver {

struct KernelTime {
  std::string name;      // the launch's name (the step's phase, e.g. "bond forces")
  int64_t launches = 0;  // timed launches
  double seconds = 0.0;  // their summed GPU time, start event to stop event
};

struct KernelTimes {
  int64_t warmup_steps = 0;  // steps of this run before the timing began
  int64_t steps_timed = 0;   // steps whose launches were all timed
  std::vector<KernelTime> kernels;  // largest total first (ties by name)
  double seconds() const;           // the kernels' total
  // A time over the timed steps in microseconds per step (0 when no step was timed).
  double us_per_step(double seconds) const;
};

// Sums (name, seconds) per name; the names of a step are few (about ten), so rows are found
// by a linear search in the order they first appeared.
class KernelTimeTable {
public:
  void add(std::string_view name, double seconds);
  void step_done() { ++steps_; }
  KernelTimes times(int64_t warmup_steps) const;

private:
  std::vector<KernelTime> rows_;
  int64_t steps_ = 0;
};

// The table breccia-solve prints at the end of a timed run: per kernel its launches, total
// seconds, microseconds per timed step and share of all kernels' time, largest first.
std::string kernel_times_table(const KernelTimes& t);

}  // namespace breccia::solver
