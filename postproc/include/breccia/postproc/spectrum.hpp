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
  size_t samples = 0, transform_length = 0;  // transform_length > samples: zero-padded
};

enum class Window {
  Rectangular,
  // 0.5 (1 - cos(2 pi k / N)): zero at k = 0 only; on an unpadded record of N samples the
  // DFT bins stay orthogonal and the coherent gain is exactly 1/2 (whole-record analysis).
  Hann,
  // 0.5 (1 - cos(2 pi k / (N - 1))) (numpy.hanning): zero at both ends, symmetric about the
  // middle. For a gate cut out of a longer record: both cut edges are tapered alike.
  HannSymmetric,
};

struct SpectrumOptions {
  Window window = Window::Rectangular;
  std::optional<double> reference_Hz;  // unset: the largest non-DC peak
  // Zero padding: the transform length is the smallest power of two >= the samples and >=
  // 1 / (resolution_Hz dt), so the bins are at most resolution_Hz apart. Padding only
  // interpolates the spectrum (the true resolution stays 1 / record length); it lets a peak
  // search find the top of a peak that falls between the unpadded bins.
  std::optional<double> resolution_Hz;
  // Peak search half-width: the reference amplitude is the largest with |f - reference_Hz|
  // < band_Hz and harmonic n the largest with |f - n reference_Hz| < band_Hz. Unset: the bin
  // nearest reference_Hz, and +-1 bin around n x that bin.
  std::optional<double> band_Hz;
};

// signal sampled at a constant dt_s; the mean is removed first. Amplitudes are corrected
// for the window's coherent gain (2 |X_k| / sum of the window), so a sine of amplitude A on a
// bin reads A. Throws std::invalid_argument for fewer than 4 samples, dt <= 0, or a band
// with no bin in it.
Spectrum amplitude_spectrum(std::span<const double> signal, double dt_s, const SpectrumOptions& options);
// The whole-record form: periodic Hann or rectangular, no padding, +-1 bin peaks.
Spectrum amplitude_spectrum(std::span<const double> signal, double dt_s, bool hann,
                            std::optional<double> reference_Hz);

// Time gate: the rows [first, last) of increasing sample times t with t0 <= t <= t1.
struct GateRows {
  size_t first = 0, last = 0;
};
GateRows gate_rows(std::span<const double> t, double t0, double t1);

}  // namespace breccia::postproc
