// FFT correctness and harmonic ratios of synthetic probe signals.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "breccia/postproc/spectrum.hpp"

using namespace breccia::postproc;
using cd = std::complex<double>;

namespace {

std::vector<cd> naive_dft(const std::vector<cd>& x) {
  const size_t n = x.size();
  std::vector<cd> out(n);
  for (size_t k = 0; k < n; ++k)
    for (size_t j = 0; j < n; ++j)
      out[k] += x[j] * std::polar(1.0, -2.0 * std::numbers::pi * static_cast<double>(k * j % n) / n);
  return out;
}

std::vector<double> signal(size_t n, double dt, double f0, double a3) {
  std::vector<double> s(n);
  for (size_t k = 0; k < n; ++k) {
    const double t = k * dt;
    s[k] = 1e-8 * (std::sin(2 * std::numbers::pi * f0 * t) + a3 * std::sin(2 * std::numbers::pi * 3 * f0 * t + 0.3));
  }
  return s;
}

}  // namespace

TEST(Fft, MatchesNaiveDftForPowerOfTwoAndOtherLengths) {
  std::mt19937 rng(3);
  std::normal_distribution<double> g;
  for (size_t n : {1u, 2u, 8u, 37u, 100u, 256u}) {
    std::vector<cd> x(n);
    for (auto& v : x) v = cd(g(rng), g(rng));
    const auto fast = fft(x), ref = naive_dft(x);
    for (size_t k = 0; k < n; ++k) EXPECT_LT(std::abs(fast[k] - ref[k]), 1e-9 * std::sqrt(double(n))) << "n=" << n;
  }
}

TEST(Spectrum, SinePeaksAtItsBinAndThirdHarmonicRatioIsItsAmplitude) {
  // 2 MHz on bin 40 of a 2048-sample record: dt = 40 / (2048 * 2 MHz).
  const size_t n = 2048;
  const double f0 = 2e6, dt = 40.0 / (n * f0);
  for (bool hann : {false, true}) {
    const Spectrum s = amplitude_spectrum(signal(n, dt, f0, 0.1), dt, hann, std::nullopt);
    EXPECT_NEAR(s.reference_frequency_Hz, f0, 1e-6 * f0) << "hann=" << hann;
    EXPECT_NEAR(s.reference_amplitude, 1e-8, 1e-3 * 1e-8);  // coherent gain corrected
    ASSERT_GE(s.harmonics.size(), 2u);
    EXPECT_EQ(s.harmonics[1].order, 3);
    EXPECT_NEAR(s.harmonics[1].frequency_Hz, 3 * f0, 1e-6 * f0);
    EXPECT_NEAR(s.harmonics[1].ratio, 0.1, 0.001);  // 1 %: on-bin tones leak nothing
    EXPECT_LT(s.harmonics[0].ratio, 1e-6);          // no second harmonic in the signal
  }
}

TEST(Spectrum, GivenReferenceFrequencyNormalisesThere) {
  // Odd length (Bluestein path) and an explicit reference at the third harmonic.
  const size_t n = 1500;
  const double f0 = 1e6, dt = 30.0 / (n * f0);
  const Spectrum s = amplitude_spectrum(signal(n, dt, f0, 0.1), dt, false, 3 * f0);
  EXPECT_NEAR(s.reference_frequency_Hz, 3 * f0, 1e-6 * f0);
  EXPECT_NEAR(s.reference_amplitude, 1e-9, 1e-12);
  // Spectrum normalised at 3 f0: the fundamental reads 1 / 0.1 = 10.
  EXPECT_NEAR(s.normalised[30], 10.0, 0.01);
}
