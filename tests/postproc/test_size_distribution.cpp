// Size-distribution fits recover the parameters of samples drawn from known laws.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>

#include "breccia/postproc/size_distribution.hpp"

using namespace breccia::postproc;

namespace {

// Equal-mass fragments: the passing-by-mass curve is then the empirical CDF of the sizes.
std::vector<double> draw(size_t n, unsigned seed, const std::function<double(double)>& inverse_cdf) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<double> x(n);
  for (auto& v : x) v = inverse_cdf(u(rng));
  return x;
}

}  // namespace

TEST(SizeDistribution, RosinRammlerSampleIsFittedBackWithinFivePercent) {
  const double xc = 0.02, n = 1.4;  // 20 mm characteristic size, uniformity 1.4
  const auto x = draw(3000, 42, [&](double p) { return xc * std::pow(-std::log(1.0 - p), 1.0 / n); });
  const std::vector<double> mass(x.size(), 1.0);
  const SizeDistribution d = size_distribution(x, mass);
  ASSERT_TRUE(d.fitted);
  // 5 %: sampling error of 3000 draws is ~2 % on n and ~1 % on xc (Kolmogorov band ~0.025).
  EXPECT_NEAR(d.rosin_rammler.xc_m, xc, 0.05 * xc);
  EXPECT_NEAR(d.rosin_rammler.n, n, 0.05 * n);
  EXPECT_GT(d.rosin_rammler.r2, 0.99);
  const double x50 = xc * std::pow(std::log(2.0), 1.0 / n);
  EXPECT_NEAR(d.x50_m, x50, 0.05 * x50);
  EXPECT_NEAR(d.rosin_rammler.x50_m, x50, 0.05 * x50);
  const double x80 = xc * std::pow(std::log(5.0), 1.0 / n);
  EXPECT_NEAR(d.x80_m, x80, 0.05 * x80);
  EXPECT_NEAR(d.rosin_rammler.x80_m, x80, 0.05 * x80);
}

TEST(SizeDistribution, SwebrecSampleIsFittedBackWithinFivePercent) {
  const double xmax = 0.5, x50 = 0.1, b = 2.5;
  const auto x = draw(3000, 7, [&](double p) { return xmax * std::exp(-std::log(xmax / x50) * std::pow(1.0 / p - 1.0, 1.0 / b)); });
  const std::vector<double> mass(x.size(), 1.0);
  const SizeDistribution d = size_distribution(x, mass);
  ASSERT_TRUE(d.fitted);
  // xmax is fixed to the largest draw (slightly below the true xmax), which the fit
  // compensates in b; 5 % covers that bias and the sampling error.
  EXPECT_NEAR(d.swebrec.x50_m, x50, 0.05 * x50);
  EXPECT_NEAR(d.swebrec.b, b, 0.05 * b);
  EXPECT_GT(d.swebrec.r2, 0.99);
}

TEST(SizeDistribution, PassingIsCumulativeMassFractionAndInterpolatesX50) {
  // Sizes 1, 2, 3 m with masses 1, 1, 2: passing 0.25, 0.5, 1; x50 = 2 exactly, x80 between 2 and 3.
  const std::vector<double> x{3.0, 1.0, 2.0}, m{2.0, 1.0, 1.0};
  const SizeDistribution d = size_distribution(x, m);
  ASSERT_EQ(d.passing.size(), 3u);
  EXPECT_DOUBLE_EQ(d.passing[0], 0.25);
  EXPECT_DOUBLE_EQ(d.passing[1], 0.5);
  EXPECT_DOUBLE_EQ(d.passing[2], 1.0);
  EXPECT_DOUBLE_EQ(d.x50_m, 2.0);
  EXPECT_NEAR(d.x80_m, 2.6, 1e-12);  // linear between (2, 0.5) and (3, 1)
}

TEST(SizeDistribution, PiecesOfOneSizeUpToRoundingAreOneSieveStepAndNotFitted) {
  // Twelve 3 mm pieces whose box edges, as coordinate differences, came out as 0.003 or
  // 0.0030000000000000027 m: one sieve step passing everything at 3 mm, nothing to fit.
  std::vector<double> x, m;
  for (int k = 0; k < 12; ++k) {
    x.push_back(k % 3 == 0 ? 0.003 : 0.0030000000000000027);
    m.push_back(1.0);
  }
  const SizeDistribution d = size_distribution(x, m);
  ASSERT_EQ(d.size_m.size(), 1u);
  EXPECT_DOUBLE_EQ(d.passing[0], 1.0);
  EXPECT_FALSE(d.fitted);
  // Sizes a part in 10^6 apart are two steps (real sieve sizes, not rounding).
  const SizeDistribution two = size_distribution(std::vector<double>{0.003, 0.003003}, std::vector<double>{1.0, 1.0});
  EXPECT_EQ(two.size_m.size(), 2u);
}
