#include "breccia/postproc/size_distribution.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numeric>

namespace breccia::postproc {

double RosinRammlerFit::passing(double x) const { return x <= 0 ? 0.0 : 1.0 - std::exp(-std::pow(x / xc_m, n)); }
double RosinRammlerFit::size_at(double p) const { return xc_m * std::pow(-std::log(1.0 - p), 1.0 / n); }

double SwebrecFit::passing(double x) const {
  if (x <= 0) return 0.0;
  if (x >= xmax_m) return 1.0;
  return 1.0 / (1.0 + std::pow(std::log(xmax_m / x) / std::log(xmax_m / x50_m), b));
}
double SwebrecFit::size_at(double p) const {
  return xmax_m * std::exp(-std::log(xmax_m / x50_m) * std::pow(1.0 / p - 1.0, 1.0 / b));
}

namespace {

using Model = std::function<double(const Eigen::Vector2d& theta, double x)>;

double sum_squares(const Model& f, const Eigen::Vector2d& th, std::span<const double> x, std::span<const double> y) {
  double s = 0;
  for (size_t k = 0; k < x.size(); ++k) {
    const double r = f(th, x[k]) - y[k];
    s += r * r;
  }
  return s;
}

// Levenberg-Marquardt on two parameters with a forward-difference Jacobian
// (Nocedal & Wright 2006, section 10.3); a few dozen iterations suffice for smooth CDFs.
Eigen::Vector2d levenberg_marquardt(const Model& f, Eigen::Vector2d th, std::span<const double> x,
                                    std::span<const double> y) {
  double lambda = 1e-3;
  double cost = sum_squares(f, th, x, y);
  for (int it = 0; it < 200; ++it) {
    Eigen::Matrix2d jtj = Eigen::Matrix2d::Zero();
    Eigen::Vector2d jtr = Eigen::Vector2d::Zero();
    for (size_t k = 0; k < x.size(); ++k) {
      const double f0 = f(th, x[k]);  // once per point: the crushed block has 10^5 fragments
      const double r = f0 - y[k];
      Eigen::Vector2d g;
      for (int p = 0; p < 2; ++p) {
        Eigen::Vector2d t2 = th;
        const double h = 1e-7 * std::max(1.0, std::abs(th[p]));
        t2[p] += h;
        g[p] = (f(t2, x[k]) - f0) / h;
      }
      jtj += g * g.transpose();
      jtr += g * r;
    }
    bool improved = false;
    for (int tries = 0; tries < 30 && !improved; ++tries) {
      Eigen::Matrix2d a = jtj;
      a.diagonal() *= 1.0 + lambda;
      a.diagonal().array() += 1e-30;
      const Eigen::Vector2d step = a.ldlt().solve(-jtr);
      const Eigen::Vector2d cand = th + step;
      const double c = sum_squares(f, cand, x, y);
      if (std::isfinite(c) && c < cost) {
        const double gain = cost - c;
        th = cand;
        cost = c;
        lambda = std::max(lambda * 0.3, 1e-12);
        improved = true;
        if (gain < 1e-15 * std::max(cost, 1e-30) || step.norm() < 1e-12) return th;
      } else {
        lambda *= 10.0;
      }
    }
    if (!improved) break;
  }
  return th;
}

double r_squared(const std::function<double(double)>& p, std::span<const double> x, std::span<const double> y) {
  const double mean = std::accumulate(y.begin(), y.end(), 0.0) / y.size();
  double ss_res = 0, ss_tot = 0;
  for (size_t k = 0; k < x.size(); ++k) {
    ss_res += (p(x[k]) - y[k]) * (p(x[k]) - y[k]);
    ss_tot += (y[k] - mean) * (y[k] - mean);
  }
  return ss_tot > 0 ? 1.0 - ss_res / ss_tot : 1.0;
}

// Least-squares line y = a + b x.
std::pair<double, double> line_fit(const std::vector<double>& x, const std::vector<double>& y) {
  const double n = static_cast<double>(x.size());
  const double sx = std::accumulate(x.begin(), x.end(), 0.0), sy = std::accumulate(y.begin(), y.end(), 0.0);
  double sxx = 0, sxy = 0;
  for (size_t k = 0; k < x.size(); ++k) {
    sxx += x[k] * x[k];
    sxy += x[k] * y[k];
  }
  const double den = n * sxx - sx * sx;
  const double b = den != 0 ? (n * sxy - sx * sy) / den : 0.0;
  return {(sy - b * sx) / n, b};
}

double interpolate_size(const std::vector<double>& x, const std::vector<double>& p, double target) {
  for (size_t k = 0; k < x.size(); ++k) {
    if (p[k] < target) continue;
    if (k == 0) return x[0];
    const double t = (target - p[k - 1]) / (p[k] - p[k - 1]);
    return x[k - 1] + t * (x[k] - x[k - 1]);
  }
  return x.back();
}

}  // namespace

SizeDistribution size_distribution(std::span<const double> size_m, std::span<const double> mass_kg) {
  SizeDistribution d;
  d.fragment_count = size_m.size();
  if (size_m.empty()) return d;
  std::vector<size_t> order(size_m.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return size_m[a] < size_m[b]; });
  const double total = std::accumulate(mass_kg.begin(), mass_kg.end(), 0.0);
  double cum = 0;
  for (size_t k = 0; k < order.size(); ++k) {
    cum += mass_kg[order[k]];
    // Fragments of equal size form one sieve step: keep only the last (highest) point. Equal
    // within 1e-9: sizes are box edges, differences of coordinates, so pieces of one size
    // differ by rounding (0.003 and 0.0030000000000000027 m), not by a sieve.
    if (!d.size_m.empty() && size_m[order[k]] - d.size_m.back() <= 1e-9 * d.size_m.back()) {
      d.passing.back() = cum / total;
      continue;
    }
    d.size_m.push_back(size_m[order[k]]);
    d.passing.push_back(cum / total);
  }
  d.x50_m = interpolate_size(d.size_m, d.passing, 0.5);
  d.x80_m = interpolate_size(d.size_m, d.passing, 0.8);
  if (d.size_m.size() < 3) return d;
  const std::vector<double>& x = d.size_m;
  const std::vector<double>& y = d.passing;

  // Rosin-Rammler, theta = (ln xc, ln n). Start from the linearised form
  // ln(-ln(1-P)) = n ln x - n ln xc over the points with 0 < P < 1.
  {
    std::vector<double> lx, ly;
    for (size_t k = 0; k < x.size(); ++k)
      if (y[k] > 0 && y[k] < 1) {
        lx.push_back(std::log(x[k]));
        ly.push_back(std::log(-std::log(1.0 - y[k])));
      }
    Eigen::Vector2d th(std::log(d.x50_m), 0.0);
    if (lx.size() >= 2) {
      const auto [a, b] = line_fit(lx, ly);
      if (b > 0) th = Eigen::Vector2d(-a / b, std::log(b));
    }
    // Evaluated on z = ln x (computed once): (x/xc)^n = exp(n (z - ln xc)), one exp per point
    // instead of a pow (the fits were a sixth of the post-processing time of a crushed block).
    const Model rr = [](const Eigen::Vector2d& t, double z) {
      return 1.0 - std::exp(-std::exp(std::exp(t[1]) * (z - t[0])));
    };
    std::vector<double> z(x.size());
    for (size_t k = 0; k < x.size(); ++k) z[k] = std::log(x[k]);
    th = levenberg_marquardt(rr, th, z, y);
    d.rosin_rammler.xc_m = std::exp(th[0]);
    d.rosin_rammler.n = std::exp(th[1]);
    d.rosin_rammler.x50_m = d.rosin_rammler.size_at(0.5);
    d.rosin_rammler.x80_m = d.rosin_rammler.size_at(0.8);
    d.rosin_rammler.r2 = r_squared([&](double v) { return d.rosin_rammler.passing(v); }, x, y);
  }
  // Swebrec with xmax = largest size; theta = (ln ln(xmax/x50), ln b) keeps x50 < xmax, b > 0.
  {
    const double xmax = x.back();
    // Evaluated on z = ln ln(xmax/x) (computed once; -inf at x = xmax, where P = 1):
    // (ln(xmax/x)/l50)^b = exp(b (z - ln l50)).
    const Model sw = [](const Eigen::Vector2d& t, double z) {
      return 1.0 / (1.0 + std::exp(std::exp(t[1]) * (z - t[0])));
    };
    std::vector<double> z(x.size());
    for (size_t k = 0; k < x.size(); ++k)
      z[k] = x[k] < xmax ? std::log(std::log(xmax / x[k])) : -std::numeric_limits<double>::infinity();
    double l50 = std::log(xmax / std::min(d.x50_m, 0.999 * xmax));
    Eigen::Vector2d th(std::log(l50), std::log(2.0));
    {  // linearised: ln(1/P - 1) = b ln ln(xmax/x) - b ln ln(xmax/x50)
      std::vector<double> lx, ly;
      for (size_t k = 0; k < x.size(); ++k)
        if (y[k] > 0 && y[k] < 1 && x[k] < xmax) {
          lx.push_back(std::log(std::log(xmax / x[k])));
          ly.push_back(std::log(1.0 / y[k] - 1.0));
        }
      if (lx.size() >= 2) {
        const auto [a, b] = line_fit(lx, ly);
        if (b > 0) th = Eigen::Vector2d(-a / b, std::log(b));
      }
    }
    th = levenberg_marquardt(sw, th, z, y);
    d.swebrec.xmax_m = xmax;
    d.swebrec.x50_m = xmax / std::exp(std::exp(th[0]));
    d.swebrec.b = std::exp(th[1]);
    d.swebrec.x80_m = d.swebrec.size_at(0.8);
    d.swebrec.r2 = r_squared([&](double v) { return d.swebrec.passing(v); }, x, y);
  }
  d.fitted = true;
  return d;
}

}  // namespace breccia::postproc
