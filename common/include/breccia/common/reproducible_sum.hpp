#pragma once
// Sums whose result does not depend on the order of the terms, nor on how they are split
// between threads or processes: the pre-rounding of Demmel & Nguyen ("Parallel reproducible
// summation", IEEE Trans. Computers 64(7), 2015), in its simplest form.
//
// With m the largest |x| of all terms and N their count, each term is split over K levels:
// at level l it is rounded to a multiple of the grid u_l = ulp(M_l) by q = (M_l + x) - M_l,
// with M_l >= N m 2^-(l-1)(53-b) chosen so that any sum of N such multiples stays below 2 M_l:
// every partial sum is then exact, whatever the order, and so is the sum of the ranks'
// partial sums. The remainders x - q (exact) feed the next level. Three levels leave an
// error below N u_3, about 2^-100 N^3 m: far below the double rounding of a plain sum.
//
// Used where a global sum steers the state, so that a run on P ranks takes the decisions
// of one process bit for bit: dynamic relaxation's damping and residual (run.cpp).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <functional>
#include <vector>

namespace breccia {

// `reduce_max(values, count)` and `reduce_sum(values, count)` combine in place over the
// processes (empty: one process). `term(k, q)` gives term k of this process's `count`
// terms of sum q, for each of `quantities` sums; the sums come back in `out`.
inline void reproducible_sums(size_t count, int quantities, const std::function<double(size_t, int)>& term,
                              std::vector<double>& out, const std::function<void(double*, int)>& reduce_max = {},
                              const std::function<void(double*, int)>& reduce_sum = {}) {
  constexpr int kLevels = 3;
  out.assign(static_cast<size_t>(quantities), 0.0);
  // Largest magnitude per quantity, and the total count (a double: exact below 2^53).
  std::vector<double> head(static_cast<size_t>(quantities), 0.0);
  for (size_t k = 0; k < count; ++k)
    for (int q = 0; q < quantities; ++q) head[q] = std::max(head[q], std::fabs(term(k, q)));
  std::vector<double> n_total{static_cast<double>(count)};
  if (reduce_max) reduce_max(head.data(), quantities);
  if (reduce_sum) reduce_sum(n_total.data(), 1);
  const double n = std::max(1.0, n_total[0]);
  const int bits_n = static_cast<int>(std::ceil(std::log2(n))) + 1;
  // Level boundaries M_{q,l} and the level sums of this process.
  std::vector<double> M(static_cast<size_t>(quantities) * kLevels, 0.0), sums(M.size(), 0.0);
  for (int q = 0; q < quantities; ++q) {
    if (!(head[q] > 0.0) || !std::isfinite(head[q])) continue;
    int e = 0;
    std::frexp(head[q], &e);  // head < 2^e
    for (int l = 0; l < kLevels; ++l) M[q * kLevels + l] = std::ldexp(1.0, e + bits_n - l * (52 - bits_n));
  }
  for (size_t k = 0; k < count; ++k)
    for (int q = 0; q < quantities; ++q) {
      double x = term(k, q);
      for (int l = 0; l < kLevels; ++l) {
        const double m = M[q * kLevels + l];
        if (m == 0.0) break;
        const double rounded = (m + x) - m;
        sums[q * kLevels + l] += rounded;
        x -= rounded;
      }
    }
  if (reduce_sum) reduce_sum(sums.data(), static_cast<int>(sums.size()));
  for (int q = 0; q < quantities; ++q) {
    if (!std::isfinite(head[q])) {  // a non-finite term: the plain sum says so
      double plain = 0.0;
      for (size_t k = 0; k < count; ++k) plain += term(k, q);
      out[q] = plain;
      continue;
    }
    for (int l = 0; l < kLevels; ++l) out[q] += sums[q * kLevels + l];
  }
}

}  // namespace breccia
