#include "breccia/postproc/spectrum.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <stdexcept>

namespace breccia::postproc {
namespace {

using cd = std::complex<double>;

bool is_power_of_two(size_t n) { return n && !(n & (n - 1)); }

// Iterative radix-2 Cooley-Tukey; sign -1 forward, +1 inverse (unscaled).
void radix2(std::vector<cd>& a, int sign) {
  const size_t n = a.size();
  for (size_t i = 1, j = 0; i < n; ++i) {
    size_t bit = n >> 1;
    for (; j & bit; bit >>= 1) j ^= bit;
    j ^= bit;
    if (i < j) std::swap(a[i], a[j]);
  }
  for (size_t len = 2; len <= n; len <<= 1) {
    const double ang = sign * 2.0 * std::numbers::pi / static_cast<double>(len);
    const cd wl(std::cos(ang), std::sin(ang));
    for (size_t i = 0; i < n; i += len) {
      cd w(1.0, 0.0);
      for (size_t k = 0; k < len / 2; ++k) {
        const cd u = a[i + k], v = a[i + k + len / 2] * w;
        a[i + k] = u + v;
        a[i + k + len / 2] = u - v;
        w *= wl;
      }
    }
  }
}

}  // namespace

std::vector<cd> fft(std::vector<cd> x) {
  const size_t n = x.size();
  if (n <= 1) return x;
  if (is_power_of_two(n)) {
    radix2(x, -1);
    return x;
  }
  // Bluestein: the DFT as a convolution with the chirp exp(i pi k^2 / N), done with
  // radix-2 transforms of length >= 2N - 1 (Bluestein 1970).
  size_t m = 1;
  while (m < 2 * n - 1) m <<= 1;
  std::vector<cd> chirp(n);
  for (size_t k = 0; k < n; ++k) {
    // k^2 mod 2N keeps the angle small and exact for large k.
    const unsigned long long k2 = (static_cast<unsigned long long>(k) * k) % (2ull * n);
    const double ang = std::numbers::pi * static_cast<double>(k2) / static_cast<double>(n);
    chirp[k] = cd(std::cos(ang), std::sin(ang));
  }
  std::vector<cd> a(m, 0.0), b(m, 0.0);
  for (size_t k = 0; k < n; ++k) a[k] = x[k] * std::conj(chirp[k]);
  b[0] = chirp[0];
  for (size_t k = 1; k < n; ++k) b[k] = b[m - k] = chirp[k];
  radix2(a, -1);
  radix2(b, -1);
  for (size_t k = 0; k < m; ++k) a[k] *= b[k];
  radix2(a, +1);
  for (size_t k = 0; k < n; ++k) x[k] = a[k] / static_cast<double>(m) * std::conj(chirp[k]);
  return x;
}

Spectrum amplitude_spectrum(std::span<const double> signal, double dt_s, const SpectrumOptions& o) {
  const size_t n = signal.size();
  if (n < 4) throw std::invalid_argument("amplitude_spectrum: need at least 4 samples");
  if (!(dt_s > 0)) throw std::invalid_argument("amplitude_spectrum: dt must be positive");
  size_t length = n;
  if (o.resolution_Hz) {
    if (!(*o.resolution_Hz > 0)) throw std::invalid_argument("amplitude_spectrum: resolution must be positive");
    const double wanted = std::max(static_cast<double>(n), 1.0 / (*o.resolution_Hz * dt_s));
    length = 1;
    while (static_cast<double>(length) < wanted) length <<= 1;
  }
  const double mean = std::accumulate(signal.begin(), signal.end(), 0.0) / static_cast<double>(n);
  std::vector<cd> x(length, 0.0);
  double window_sum = 0;
  const double period = o.window == Window::HannSymmetric ? static_cast<double>(n - 1) : static_cast<double>(n);
  for (size_t k = 0; k < n; ++k) {
    const double w = o.window == Window::Rectangular ? 1.0 : 0.5 * (1.0 - std::cos(2.0 * std::numbers::pi * k / period));
    window_sum += w;
    x[k] = (signal[k] - mean) * w;
  }
  const std::vector<cd> X = fft(std::move(x));
  Spectrum s;
  s.samples = n;
  s.transform_length = length;
  const size_t bins = length / 2 + 1;
  const double df = 1.0 / (static_cast<double>(length) * dt_s);
  for (size_t k = 0; k < bins; ++k) {
    s.frequency_Hz.push_back(k * df);
    // Single-sided: double every bin but DC (and Nyquist for an even length).
    const double factor = (k == 0 || (length % 2 == 0 && k == length / 2)) ? 1.0 : 2.0;
    s.amplitude.push_back(factor * std::abs(X[k]) / window_sum);
  }
  // Largest amplitude with |f - centre| < half_width (strictly, as a band edge on a bin
  // belongs to neither side); `bins` (no such bin) when the band holds none.
  const auto largest_in = [&](double centre, double half_width) {
    size_t best = bins;
    for (size_t k = 1; k < bins; ++k)
      if (std::fabs(s.frequency_Hz[k] - centre) < half_width && (best == bins || s.amplitude[k] > s.amplitude[best]))
        best = k;
    return best;
  };
  size_t ref = 1;
  if (o.reference_Hz && o.band_Hz) {
    ref = largest_in(*o.reference_Hz, *o.band_Hz);
    if (ref == bins) throw std::invalid_argument("amplitude_spectrum: no bin within the band around the reference frequency");
  } else if (o.reference_Hz) {
    ref = static_cast<size_t>(std::llround(*o.reference_Hz / df));
    ref = std::clamp<size_t>(ref, 1, bins - 1);
  } else {
    for (size_t k = 1; k < bins; ++k)
      if (s.amplitude[k] > s.amplitude[ref]) ref = k;
  }
  s.reference_frequency_Hz = s.frequency_Hz[ref];
  s.reference_amplitude = s.amplitude[ref];
  const double norm = s.reference_amplitude > 0 ? s.reference_amplitude : 1.0;
  for (double a : s.amplitude) s.normalised.push_back(a / norm);
  // Harmonics of the nominal reference (the given frequency, else the peak's bin).
  const double nominal = o.reference_Hz ? *o.reference_Hz : s.reference_frequency_Hz;
  for (int order = 2; order <= 5; ++order) {
    size_t best = bins;
    if (o.band_Hz) {
      if (order * nominal + *o.band_Hz > s.frequency_Hz.back()) break;
      best = largest_in(order * nominal, *o.band_Hz);
      if (best == bins) break;
    } else {
      // +-1 bin around order x the reference bin; a reference in bin 1 leaves no room for it
      // (bin order - 1 is the harmonic below), so there the harmonic's own bin alone.
      const size_t centre = order * ref, half = ref >= 2 ? 1 : 0;
      if (centre + half >= bins) break;
      best = centre;
      for (size_t k = centre - half; k <= centre + half; ++k)
        if (s.amplitude[k] > s.amplitude[best]) best = k;
    }
    s.harmonics.push_back({order, s.frequency_Hz[best], s.amplitude[best], s.amplitude[best] / norm});
  }
  return s;
}

Spectrum amplitude_spectrum(std::span<const double> signal, double dt_s, bool hann,
                            std::optional<double> reference_Hz) {
  SpectrumOptions o;
  o.window = hann ? Window::Hann : Window::Rectangular;
  o.reference_Hz = reference_Hz;
  return amplitude_spectrum(signal, dt_s, o);
}

GateRows gate_rows(std::span<const double> t, double t0, double t1) {
  GateRows g;
  while (g.first < t.size() && t[g.first] < t0) ++g.first;
  g.last = g.first;
  while (g.last < t.size() && t[g.last] <= t1) ++g.last;
  return g;
}

}  // namespace breccia::postproc
