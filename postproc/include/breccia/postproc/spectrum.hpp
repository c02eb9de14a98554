#pragma once
// Discrete Fourier transform (radix-2, Bluestein for other lengths) and single-sided
// amplitude spectra of probe histories, normalised at a reference frequency.
#include <complex>
#include <optional>
#include <span>
#include <vector>

namespace breccia::postproc {

// Exact DFT X_k = sum_n x_n exp(-2 pi i k n / N) for any N >= 1.
std::vector<std::complex<double>> fft(std::vector<std::complex<double>> x);

struct Harmonic {
  int order = 0;
  double frequency_Hz = 0, amplitude = 0, ratio = 0;  // ratio to the reference amplitude
};

struct Spectrum {
  std::vector<double> frequency_Hz, amplitude, normalised;
  double reference_frequency_Hz = 0, reference_amplitude = 0;
  std::vector<Harmonic> harmonics;  // orders 2..5 of the reference frequency
};

// signal sampled at a constant dt_s; the mean is removed first. Amplitudes are corrected
// for the window's coherent gain, so a sine of amplitude A on a bin reads A. Reference:
// the bin nearest reference_Hz, or the largest non-DC peak. Harmonic amplitudes are the
// largest within +-1 bin of order x reference frequency.
Spectrum amplitude_spectrum(std::span<const double> signal, double dt_s, bool hann,
                            std::optional<double> reference_Hz);

}  // namespace breccia::postproc
