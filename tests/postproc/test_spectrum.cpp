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

TEST(Spectrum, AFundamentalInBinOneReadsEachHarmonicInItsOwnBin) {
  // One period of a sine plus 0.1 of its second harmonic over 64 samples: the fundamental is
  // bin 1, the harmonic bin 2, nothing in bins 3-5. A +-1-bin search around order x 1 would
  // read order 2's ratio from the fundamental (1.0) and order 3's from bin 2 (0.1).
  const size_t n = 64;
  const double dt = 1e-7, f0 = 1.0 / (n * dt);
  std::vector<double> s(n);
  for (size_t k = 0; k < n; ++k)
    s[k] = std::sin(2 * std::numbers::pi * f0 * k * dt) + 0.1 * std::sin(2 * std::numbers::pi * 2 * f0 * k * dt);
  const Spectrum sp = amplitude_spectrum(s, dt, false, std::nullopt);
  EXPECT_NEAR(sp.reference_frequency_Hz, f0, 1e-9 * f0);
  ASSERT_EQ(sp.harmonics.size(), 4u);
  for (const auto& h : sp.harmonics) {
    EXPECT_NEAR(h.frequency_Hz, h.order * f0, 1e-9 * f0) << "order " << h.order;
    EXPECT_NEAR(h.ratio, h.order == 2 ? 0.1 : 0.0, 1e-9) << "order " << h.order;  // on-bin tones: rounding only
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

TEST(Spectrum, GateRowsAreTheSamplesInsideTheClosedInterval) {
  const std::vector<double> t = {0.0, 1.0, 2.0, 3.0, 4.0, 5.0};
  const GateRows g = gate_rows(t, 1.0, 3.5);
  EXPECT_EQ(g.first, 1u);  // t = 1 is inside (t0 <= t)
  EXPECT_EQ(g.last, 4u);   // t = 1, 2, 3
  const GateRows all = gate_rows(t, 0.0, 5.0);
  EXPECT_EQ(all.first, 0u);
  EXPECT_EQ(all.last, 6u);
}

// A gated, zero-padded, symmetric-Hann spectrum (what the harmonics case asks of post):
// inside the gate a 2 MHz sine of amplitude A plus 0.1 A at 6 MHz, outside it a tone 5 times
// larger at 1.3 MHz that the gate must exclude. Checked against (1) the direct DTFT of the
// windowed gate samples at every padded bin (padding samples the DTFT: equal to rounding),
// and (2) the analytic amplitudes: a sine of amplitude A windowed by w reads A at its
// frequency up to the scalloping of the nearest padded bin and the leakage of the other
// tone; both are below 0.3 % here (bins 48.8 kHz apart, main lobe 2 x 182 kHz wide).
TEST(Spectrum, GatedPaddedHannSpectrumIsTheDtftOfTheGateAndReadsTheAmplitudes) {
  const double dt = 1.0e-8, f0 = 2e6, a = 1e-8, t0 = 16.995e-6, t1 = 28.005e-6;  // edges between samples
  std::vector<double> t, u;
  for (int k = 0; k * dt <= 30e-6; ++k) {
    const double tk = k * dt;
    t.push_back(tk);
    const bool inside = tk >= t0 && tk <= t1;
    u.push_back(inside ? a * (std::sin(2 * std::numbers::pi * f0 * tk) + 0.1 * std::sin(2 * std::numbers::pi * 3 * f0 * tk + 0.3))
                       : 5 * a * std::sin(2 * std::numbers::pi * 1.3e6 * tk));
  }
  const GateRows g = gate_rows(t, t0, t1);
  ASSERT_EQ(g.last - g.first, 1101u);  // 17.00 ... 28.00 us in steps of 10 ns
  const std::span<const double> gate(u.data() + g.first, g.last - g.first);
  SpectrumOptions o;
  o.window = Window::HannSymmetric;
  o.reference_Hz = f0;
  o.resolution_Hz = 0.05e6;
  o.band_Hz = 0.3e6;
  const Spectrum s = amplitude_spectrum(gate, dt, o);
  EXPECT_EQ(s.samples, 1101u);
  EXPECT_EQ(s.transform_length, 2048u);  // smallest power of two >= 1 / (0.05 MHz x 10 ns) = 2000
  // (1) the DTFT of (u - mean) w over the gate, single-sided and divided by sum w.
  const size_t n = gate.size();
  double mean = 0, wsum = 0;
  for (double v : gate) mean += v / n;
  std::vector<double> w(n);
  for (size_t k = 0; k < n; ++k) wsum += w[k] = 0.5 * (1 - std::cos(2 * std::numbers::pi * k / (n - 1.0)));
  for (size_t bin : {1u, 41u, 53u, 123u, 300u}) {
    std::complex<double> x = 0;
    for (size_t k = 0; k < n; ++k)
      x += (gate[k] - mean) * w[k] * std::polar(1.0, -2 * std::numbers::pi * double(bin * k % 2048) / 2048.0);
    EXPECT_NEAR(s.amplitude[bin], 2 * std::abs(x) / wsum, 1e-9 * a) << "bin " << bin;
  }
  // (2) analytic amplitudes, and nothing of the 1.3 MHz tone outside the gate.
  EXPECT_NEAR(s.reference_amplitude, a, 3e-3 * a);
  EXPECT_NEAR(s.reference_frequency_Hz, f0, 0.5 * 48.83e3);
  ASSERT_GE(s.harmonics.size(), 4u);
  EXPECT_EQ(s.harmonics[1].order, 3);
  EXPECT_NEAR(s.harmonics[1].ratio, 0.1, 3e-3 * 0.1 + 1e-4);
  EXPECT_LT(s.harmonics[0].ratio, 1e-3);  // no 4 MHz: Hann sidelobes of the 2 and 6 MHz tones only
  const size_t at_1p3 = static_cast<size_t>(std::llround(1.3e6 / s.frequency_Hz[1]));
  EXPECT_LT(s.normalised[at_1p3], 1e-2);  // 5 A outside the gate; inside, the 2 MHz lobe's tail only
}

TEST(Spectrum, BandWithoutABinIsRefused) {
  std::vector<double> x(64);
  for (size_t k = 0; k < x.size(); ++k) x[k] = std::sin(0.3 * k);
  SpectrumOptions o;
  o.reference_Hz = 0.207e6;
  o.band_Hz = 1.0;  // 1 Hz around 0.207 MHz: the nearest bins of the 15.625 kHz grid are 3.9 kHz away
  EXPECT_THROW(amplitude_spectrum(x, 1e-6, o), std::invalid_argument);
}
