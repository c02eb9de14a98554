#include "breccia/common/progress.hpp"

namespace breccia {

Progress::Progress(std::string stage, long long total, double interval_s, std::FILE* out)
    : stage_(std::move(stage)), total_(total), interval_s_(interval_s), out_(out),
      start_(std::chrono::steady_clock::now()), last_(start_) {}

double Progress::elapsed_s() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void Progress::update(long long done, const std::string& extra) {
  const auto now = std::chrono::steady_clock::now();
  if (std::chrono::duration<double>(now - last_).count() < interval_s_) return;
  // The rate since the previous line (the first: since the start), not the mean since the
  // start: a run whose items get cheaper or dearer as it goes (a blast's steps, 10x cheaper
  // once its bonds have broken) would otherwise keep an ETA several times off.
  const double since = std::chrono::duration<double>(now - last_).count();
  const double rate = since > 0 ? (done - last_done_) / since : 0.0;
  last_ = now;
  last_done_ = done;
  const double t = elapsed_s();
  const double eta = (rate > 0 && total_ > 0) ? (total_ - done) / rate : 0.0;
  std::fprintf(out_, "[%s] %lld/%lld (%.1f%%)  %.3g /s  elapsed %.1f s  ETA %.1f s  %s\n",
               stage_.c_str(), done, total_, total_ > 0 ? 100.0 * done / total_ : 0.0, rate, t, eta,
               extra.c_str());
  std::fflush(out_);
}

void Progress::finish(const std::string& extra) {
  const double t = elapsed_s();
  std::fprintf(out_, "[%s] done: %lld in %.2f s (%.3g /s) %s\n", stage_.c_str(), total_, t,
               t > 0 ? total_ / t : 0.0, extra.c_str());
  std::fflush(out_);
}

}  // namespace breccia
