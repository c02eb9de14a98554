#include "breccia/solver/kernel_times.hpp"

#include <algorithm>
#include <cstdio>

namespace breccia::solver {

double KernelTimes::seconds() const {
  double total = 0.0;
  for (const KernelTime& k : kernels) total += k.seconds;
  return total;
}

double KernelTimes::us_per_step(double seconds) const {
  return steps_timed > 0 ? 1e6 * seconds / static_cast<double>(steps_timed) : 0.0;
}

void KernelTimeTable::add(std::string_view name, double seconds) {
  auto row = std::find_if(rows_.begin(), rows_.end(), [&](const KernelTime& k) { return k.name == name; });
  if (row == rows_.end()) {
    rows_.push_back({std::string(name), 0, 0.0});
    row = rows_.end() - 1;
  }
  ++row->launches;
  row->seconds += seconds;
}

KernelTimes KernelTimeTable::times(int64_t warmup_steps) const {
  KernelTimes t;
  t.warmup_steps = warmup_steps;
  t.steps_timed = steps_;
  t.kernels = rows_;
  std::sort(t.kernels.begin(), t.kernels.end(), [](const KernelTime& a, const KernelTime& b) {
    return a.seconds != b.seconds ? a.seconds > b.seconds : a.name < b.name;
  });
  return t;
}

std::string kernel_times_table(const KernelTimes& t) {
  std::string out;
  char line[256];
  std::snprintf(line, sizeof line, "kernel times (CUDA events; %lld steps timed after %lld warm-up steps):\n",
                static_cast<long long>(t.steps_timed), static_cast<long long>(t.warmup_steps));
  out += line;
  std::snprintf(line, sizeof line, "  %-32s %10s %12s %12s %8s\n", "kernel", "launches", "total s", "us/step", "share");
  out += line;
  const double total = t.seconds();
  for (const KernelTime& k : t.kernels) {
    std::snprintf(line, sizeof line, "  %-32.32s %10lld %12.6f %12.2f %7.1f%%\n", k.name.c_str(),
                  static_cast<long long>(k.launches), k.seconds, t.us_per_step(k.seconds),
                  total > 0 ? 100.0 * k.seconds / total : 0.0);
    out += line;
  }
  std::snprintf(line, sizeof line, "  %-32s %10s %12.6f %12.2f\n", "all kernels", "", total, t.us_per_step(total));
  out += line;
  return out;
}

}  // namespace breccia::solver
