// reproducible_sum.hpp: the same bits whatever the order of the terms and however they are
// split between processes, and the exact sum where the terms' exact sum is a double.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

#include "breccia/common/reproducible_sum.hpp"

namespace {

// Each chunk plays a process. reproducible_sums asks its reductions twice: the maxima (and
// the count), then the level sums. The emulation runs every chunk once to collect its level
// sums, adds them up (exactly: they are multiples of one grid), and runs every chunk again
// answering with the totals, as MPI_Allreduce would; every chunk must then return the same.
double sum_in_chunks(const std::vector<double>& x, const std::vector<size_t>& cuts) {
  double global_max = 0.0;
  for (double v : x) global_max = std::max(global_max, std::fabs(v));
  const double global_count = static_cast<double>(x.size());
  std::vector<double> totals;
  std::vector<double> results;
  for (int round = 0; round < 2; ++round) {
    std::vector<double> collected;
    for (size_t c = 0; c + 1 < cuts.size(); ++c) {
      const size_t b = cuts[c], e = cuts[c + 1];
      std::vector<double> out;
      int calls = 0;
      breccia::reproducible_sums(
          e - b, 1, [&](size_t k, int) { return x[b + k]; }, out, [&](double* v, int) { v[0] = global_max; },
          [&](double* v, int n) {
            if (calls++ == 0) {  // the count
              v[0] = global_count;
              return;
            }
            if (round == 0) {
              if (collected.empty()) collected.assign(n, 0.0);
              for (int i = 0; i < n; ++i) collected[i] += v[i];
            } else {
              std::copy(totals.begin(), totals.end(), v);
            }
          });
      if (round == 1) results.push_back(out[0]);
    }
    totals = collected;
  }
  for (double r : results) EXPECT_EQ(r, results.front()) << "chunks disagree";
  return results.front();
}

}  // namespace

TEST(ReproducibleSum, SameBitsInAnyOrderAndAnySplit) {
  std::mt19937_64 rng(7);
  std::lognormal_distribution<double> mag(0.0, 6.0);
  std::uniform_int_distribution<int> sign(0, 1);
  std::vector<double> x(100000);
  for (double& v : x) v = (sign(rng) ? 1 : -1) * mag(rng);
  const double reference = sum_in_chunks(x, {0, x.size()});
  double plain_a = 0.0, plain_b = 0.0;
  for (double v : x) plain_a += v;
  std::vector<double> shuffled = x;
  std::shuffle(shuffled.begin(), shuffled.end(), rng);
  for (double v : shuffled) plain_b += v;
  EXPECT_NE(plain_a, plain_b) << "the plain sum should depend on the order here (else the test shows nothing)";
  EXPECT_EQ(sum_in_chunks(shuffled, {0, shuffled.size()}), reference);
  EXPECT_EQ(sum_in_chunks(shuffled, {0, 1, 33333, 66667, shuffled.size()}), reference);
  EXPECT_EQ(sum_in_chunks(x, {0, 50000, 50000, x.size()}), reference);  // an empty chunk
}

TEST(ReproducibleSum, ExactWhenTheExactSumIsADouble) {
  // Integers times 2^-30 of very different sizes: their exact sum is known in int64 and is a
  // double; a plain double sum loses the small ones next to 2^40.
  std::mt19937_64 rng(11);
  std::uniform_int_distribution<int64_t> small(-1000, 1000);
  std::vector<double> x;
  int64_t exact = 0;
  for (int k = 0; k < 20000; ++k) {
    const int64_t v = k % 1000 == 0 ? (int64_t{1} << 40) * (k % 2000 == 0 ? 1 : -1) : small(rng);
    exact += v;
    x.push_back(std::ldexp(static_cast<double>(v), -30));
  }
  std::vector<double> out;
  breccia::reproducible_sums(x.size(), 1, [&](size_t k, int) { return x[k]; }, out);
  EXPECT_EQ(out[0], std::ldexp(static_cast<double>(exact), -30));
}
