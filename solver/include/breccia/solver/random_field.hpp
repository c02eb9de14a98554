#pragma once
// A stationary Gaussian random field for spatially correlated strength scatter
// (weibull.correlation_length, docs/theory.md "Weibull heterogeneity"). Set-up only.
#include <cstdint>
#include <vector>

namespace breccia::solver {

// Zero mean, unit variance, covariance C(r) = exp(-r^2 / L^2): a sum of random Fourier modes
// (the spectral representation of Shinozuka & Deodatis 1991, with wavevectors drawn from
// the field's spectral density, here Gaussian with variance 2 / L^2 per component), so that
// E[g(x) g(x + r)] = E[cos(k . r)] = exp(-|r|^2 / L^2) exactly in expectation over the modes.
// The same seed gives the same field on every rank and thread.
class GaussianRandomField {
 public:
  GaussianRandomField(double correlation_length, uint64_t seed, int modes = 512);
  double operator()(const double* x) const;
  double correlation(double r) const;  // C(r) of the field (the target, not a sample estimate)

 private:
  double length_;
  std::vector<double> k_;      // 3 per mode
  std::vector<double> phase_;  // 1 per mode
};

// The uniform (0, 1) of a bond from the field at its two ends: their mean, rescaled to unit
// variance with the correlation of the two points (rho = C(|xi|)), through the normal CDF.
// Symmetric in the ends; uniform in distribution whenever the field is Gaussian.
double correlated_bond_uniform(double g_i, double g_j, double rho_ij);

}  // namespace breccia::solver
