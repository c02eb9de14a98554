#pragma once
// The gas load's equation of state along an isentrope, and the choked outflow through a vent
// (loads[].type: gas; gas.hpp, docs/theory.md "Borehole gas"). Host and device alike.
#include <cmath>

#include "breccia/solver/hd.hpp"

namespace breccia::solver {

// Isentrope of the detonation or deflagration products through the case's pressure at the
// reference cavity. Two-gamma (the default): p rho^-gamma constant, gamma_high above
// switch_pressure, gamma_low below (the blasting-practice law). JWL: the shape of the
// principal isentrope of the Jones-Wilkins-Lee products equation of state,
//   p_s(v) = A exp(-R1 v) + B exp(-R2 v) + C v^-(1 + omega),
// v the products' volume over the unreacted explosive's, scaled so that it passes through the
// case's pressure at the reference cavity (docs/theory.md).
struct GasLaw {
  double gamma_high = 3.0;
  double gamma_low = 1.3;
  double switch_pressure = 0.1e9;  // Pa, absolute
  // JWL: A, B, C [Pa], R1, R2, omega, and v in the reference cavity with all the gas
  // (the explosive's density over the gas density there: 1 for a hole filled with the charge).
  double jwl_a = 0.0, jwl_b = 0.0, jwl_c = 0.0, jwl_r1 = 0.0, jwl_r2 = 0.0, jwl_omega = 0.0;
  double jwl_v_ref = 1.0;
  enum class Kind { TwoGamma, Jwl } kind = Kind::TwoGamma;  // last: {gamma_high, gamma_low, switch} still reads
};

// The JWL principal isentrope p_s(v) [Pa] and its local exponent -d ln p_s / d ln v.
BRECCIA_HD double jwl_isentrope(const GasLaw& g, double v) {
  return g.jwl_a * std::exp(-g.jwl_r1 * v) + g.jwl_b * std::exp(-g.jwl_r2 * v) +
         g.jwl_c * std::pow(v, -(1.0 + g.jwl_omega));
}
BRECCIA_HD double jwl_exponent(const GasLaw& g, double v) {
  const double a = g.jwl_a * std::exp(-g.jwl_r1 * v), b = g.jwl_b * std::exp(-g.jwl_r2 * v);
  const double c = g.jwl_c * std::pow(v, -(1.0 + g.jwl_omega));
  return (a * g.jwl_r1 * v + b * g.jwl_r2 * v + c * (1.0 + g.jwl_omega)) / (a + b + c);
}

// Absolute pressure at relative density rho on the isentrope through (1, p_ref): rho is the
// gas's density over its density in the reference cavity with all its mass.
BRECCIA_HD double gas_isentrope_pressure(double p_ref, double rho, const GasLaw& g) {
  if (p_ref <= 0.0 || rho <= 0.0) return 0.0;
  if (g.kind == GasLaw::Kind::Jwl)
    return p_ref * jwl_isentrope(g, g.jwl_v_ref / rho) / jwl_isentrope(g, g.jwl_v_ref);
  if (p_ref >= g.switch_pressure) {
    const double rho_switch = std::pow(g.switch_pressure / p_ref, 1.0 / g.gamma_high);  // <= 1
    return rho >= rho_switch ? p_ref * std::pow(rho, g.gamma_high)
                             : g.switch_pressure * std::pow(rho / rho_switch, g.gamma_low);
  }
  const double rho_switch = std::pow(g.switch_pressure / p_ref, 1.0 / g.gamma_low);  // > 1
  return rho <= rho_switch ? p_ref * std::pow(rho, g.gamma_low)
                           : g.switch_pressure * std::pow(rho / rho_switch, g.gamma_high);
}

// The isentrope's local exponent -d ln p / d ln V at pressure p and relative density rho
// (the gamma of the outflow).
BRECCIA_HD double gas_local_gamma(double p, double rho, const GasLaw& g) {
  if (g.kind == GasLaw::Kind::Jwl) return jwl_exponent(g, g.jwl_v_ref / rho);
  return p >= g.switch_pressure ? g.gamma_high : g.gamma_low;
}

// Escape speed of the gas at absolute pressure p and density rho_kg [kg/m3] (relative density
// rho, as above): the largest speed a gas released into an empty channel reaches, the
// Riemann invariant integral of c d(ln rho) from zero density up along the isentrope
// (Courant & Friedrichs 1948, the centred rarefaction into vacuum). For a single gamma it is
// 2 c / (gamma - 1); the local gamma alone misses the rest of the isentrope below, which for
// the two-gamma law is most of it (gamma_high 3 gives 2 c / 2 at the state, the gamma_low 1.3
// branch below the switch adds 2 c_switch / 0.3): two-gamma in closed form, JWL by quadrature.
BRECCIA_HD double gas_escape_speed(double p, double rho_kg, double rho, const GasLaw& g) {
  if (!(p > 0.0) || !(rho_kg > 0.0) || !(rho > 0.0)) return 0.0;
  if (g.kind == GasLaw::Kind::TwoGamma) {
    // Below the switch, written as before the high branch was added (bit-identical runs).
    if (p < g.switch_pressure) return 2.0 * std::sqrt(g.gamma_low * p / rho_kg) / (g.gamma_low - 1.0);
    // The high branch through (p, rho_kg) meets the switch at rho_s, then the low branch.
    const double rho_s = rho_kg * std::pow(g.switch_pressure / p, 1.0 / g.gamma_high);
    return 2.0 / (g.gamma_high - 1.0) *
               (std::sqrt(g.gamma_high * p / rho_kg) - std::sqrt(g.gamma_high * g.switch_pressure / rho_s)) +
           2.0 * std::sqrt(g.gamma_low * g.switch_pressure / rho_s) / (g.gamma_low - 1.0);
  }
  // JWL, v = v_ref / rho: the integral of c dv'/v' from v out to where the exponential terms
  // are below e^-50 of theirs (Simpson in ln v'), then the C term's ideal-gas tail 2 c / omega.
  const double v = g.jwl_v_ref / rho, ps = jwl_isentrope(g, v);
  double v_end = v;
  if (g.jwl_a != 0.0 && g.jwl_r1 > 0.0) v_end = std::fmax(v_end, 50.0 / g.jwl_r1);
  if (g.jwl_b != 0.0 && g.jwl_r2 > 0.0) v_end = std::fmax(v_end, 50.0 / g.jwl_r2);
  const auto c = [&](double vv) {  // sound speed at v' on the isentrope through (v, p)
    return std::sqrt(jwl_exponent(g, vv) * p * jwl_isentrope(g, vv) / ps / (rho_kg * v / vv));
  };
  const int n = 512;  // even; Simpson's error at this n is below 1e-8 of the result (test)
  const double h = std::log(v_end / v) / n;
  double sum = 0.0;
  if (h > 0.0) {
    for (int i = 0; i <= n; ++i) sum += (i == 0 || i == n ? 1.0 : i % 2 ? 4.0 : 2.0) * c(v * std::exp(i * h));
    sum *= h / 3.0;
  }
  return sum + 2.0 * c(v_end) / (jwl_exponent(g, v_end) - 1.0);
}

// Choked (sonic) mass flux through an orifice: mdot = Gamma A sqrt(gamma p rho), with
// Gamma = (2 / (gamma + 1))^((gamma + 1) / (2 (gamma - 1))) (isentropic nozzle flow).
BRECCIA_HD double choked_flow_factor(double gamma) {
  return std::pow(2.0 / (gamma + 1.0), (gamma + 1.0) / (2.0 * (gamma - 1.0)));
}

}  // namespace breccia::solver
