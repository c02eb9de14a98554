#include "breccia/solver/random_field.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

namespace breccia::solver {

GaussianRandomField::GaussianRandomField(double correlation_length, uint64_t seed, int modes)
    : length_(correlation_length), k_(3 * static_cast<size_t>(modes)), phase_(static_cast<size_t>(modes)) {
  // std::mt19937_64's sequence is fixed by the standard; the normal and uniform draws are
  // done here by Box-Muller and a 53-bit mantissa so that every standard library gives the
  // same field (std::normal_distribution's algorithm is left to the implementation).
  std::mt19937_64 rng(seed ^ 0x5851F42D4C957F2Dull);
  auto uniform = [&] { return (static_cast<double>(rng() >> 11) + 0.5) * (1.0 / 9007199254740992.0); };
  auto normal = [&] { return std::sqrt(-2.0 * std::log(uniform())) * std::cos(2.0 * std::numbers::pi * uniform()); };
  const double sigma_k = std::sqrt(2.0) / correlation_length;
  for (int m = 0; m < modes; ++m) {
    for (int d = 0; d < 3; ++d) k_[3 * m + d] = sigma_k * normal();
    phase_[m] = 2.0 * std::numbers::pi * uniform();
  }
}

double GaussianRandomField::operator()(const double* x) const {
  const size_t modes = phase_.size();
  double sum = 0.0;
  for (size_t m = 0; m < modes; ++m)
    sum += std::cos(k_[3 * m] * x[0] + k_[3 * m + 1] * x[1] + k_[3 * m + 2] * x[2] + phase_[m]);
  return std::sqrt(2.0 / static_cast<double>(modes)) * sum;
}

double GaussianRandomField::correlation(double r) const { return std::exp(-(r * r) / (length_ * length_)); }

double correlated_bond_uniform(double g_i, double g_j, double rho_ij) {
  // Var((g_i + g_j) / 2) = (1 + rho) / 2 for unit-variance ends with correlation rho.
  const double g = (g_i + g_j) / std::sqrt(2.0 * (1.0 + rho_ij));
  const double u = 0.5 * std::erfc(-g / std::numbers::sqrt2);
  return std::clamp(u, 1e-16, 1.0 - 1e-16);  // (0, 1): the Weibull draw takes -log(U)
}

}  // namespace breccia::solver
