#pragma once
// Cumulative passing-by-mass curve and its Rosin-Rammler and Swebrec fits (least squares
// on the CDF, Levenberg-Marquardt).
//   Rosin-Rammler (Weibull): P(x) = 1 - exp(-(x/xc)^n)
//   Swebrec (Ouchterlony 2005): P(x) = 1 / (1 + (ln(xmax/x) / ln(xmax/x50))^b), x < xmax,
//   with xmax fixed to the largest fragment.
#include <span>
#include <vector>

namespace breccia::postproc {

struct RosinRammlerFit {
  double xc_m = 0, n = 0, r2 = 0, x50_m = 0, x80_m = 0;
  double passing(double x) const;
  double size_at(double p) const;
};

struct SwebrecFit {
  double xmax_m = 0, x50_m = 0, b = 0, r2 = 0, x80_m = 0;
  double passing(double x) const;
  double size_at(double p) const;
};

struct SizeDistribution {
  std::vector<double> size_m;   // ascending
  std::vector<double> passing;  // mass fraction with size <= size_m[k]
  size_t fragment_count = 0;
  double x50_m = 0, x80_m = 0;  // interpolated from the data
  bool fitted = false;          // needs >= 3 distinct sizes
  RosinRammlerFit rosin_rammler;
  SwebrecFit swebrec;
};

SizeDistribution size_distribution(std::span<const double> size_m, std::span<const double> mass_kg);

}  // namespace breccia::postproc
