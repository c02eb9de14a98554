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
// (the gamma of the outflow and of the front's escape speed).
BRECCIA_HD double gas_local_gamma(double p, double rho, const GasLaw& g) {
  if (g.kind == GasLaw::Kind::Jwl) return jwl_exponent(g, g.jwl_v_ref / rho);
  return p >= g.switch_pressure ? g.gamma_high : g.gamma_low;
}

// Choked (sonic) mass flux through an orifice: mdot = Gamma A sqrt(gamma p rho), with
// Gamma = (2 / (gamma + 1))^((gamma + 1) / (2 (gamma - 1))) (isentropic nozzle flow).
BRECCIA_HD double choked_flow_factor(double gamma) {
  return std::pow(2.0 / (gamma + 1.0), (gamma + 1.0) / (2.0 * (gamma - 1.0)));
}

}  // namespace breccia::solver
