#pragma once
// Progress lines for long stages: stage, count, rate, ETA; at most one line per interval.
#include <chrono>
#include <cstdio>
#include <string>

namespace breccia {

class Progress {
public:
  Progress(std::string stage, long long total, double interval_s = 2.0, std::FILE* out = stderr);
  // Report that `done` items are finished; `extra` is appended (e.g. "t=1.2e-5 s"). The rate
  // and the ETA printed are those since the previous line.
  void update(long long done, const std::string& extra = "");
  void finish(const std::string& extra = "");
  double elapsed_s() const;

private:
  std::string stage_;
  long long total_;
  double interval_s_;
  std::FILE* out_;
  std::chrono::steady_clock::time_point start_, last_;
  long long last_done_ = 0;  // `done` at the last line printed
};

}  // namespace breccia
