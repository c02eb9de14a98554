#include "breccia/common/units.hpp"

#include <cstdio>

#include <cctype>
#include <charconv>
#include <cmath>
#include <stdexcept>
#include <map>
#include <utility>
#include <vector>

#include "breccia/common/error.hpp"

namespace breccia {
namespace {

using UnitTable = std::vector<std::pair<std::string, double>>;

const UnitTable& table(Quantity q) {
  static const std::map<Quantity, UnitTable> tables = {
      {Quantity::Dimensionless, {{"", 1.0}, {"%", 0.01}}},
      {Quantity::Length, {{"m", 1.0}, {"cm", 1e-2}, {"mm", 1e-3}, {"um", 1e-6}, {"nm", 1e-9}, {"km", 1e3}}},
      {Quantity::Area, {{"m2", 1.0}, {"cm2", 1e-4}, {"mm2", 1e-6}}},
      {Quantity::Volume, {{"m3", 1.0}, {"cm3", 1e-6}, {"mm3", 1e-9}, {"l", 1e-3}}},
      {Quantity::Time, {{"s", 1.0}, {"ms", 1e-3}, {"us", 1e-6}, {"ns", 1e-9}}},
      {Quantity::Frequency, {{"Hz", 1.0}, {"kHz", 1e3}, {"MHz", 1e6}, {"GHz", 1e9}}},
      {Quantity::Pressure, {{"Pa", 1.0}, {"kPa", 1e3}, {"MPa", 1e6}, {"GPa", 1e9}}},
      {Quantity::Density, {{"kg/m3", 1.0}, {"g/cm3", 1e3}}},
      {Quantity::Energy, {{"J", 1.0}, {"kJ", 1e3}, {"MJ", 1e6}}},
      {Quantity::FractureEnergy, {{"J/m2", 1.0}, {"N/m", 1.0}, {"kJ/m2", 1e3}, {"N/mm", 1e3}}},
      {Quantity::Velocity, {{"m/s", 1.0}, {"mm/s", 1e-3}, {"km/s", 1e3}}},
      {Quantity::Acceleration, {{"m/s2", 1.0}, {"g", 9.80665}}},  // g: standard gravity
      {Quantity::Force, {{"N", 1.0}, {"kN", 1e3}, {"MN", 1e6}}},
      {Quantity::Mass, {{"kg", 1.0}, {"g", 1e-3}}},
      {Quantity::StrainRate, {{"1/s", 1.0}, {"/s", 1.0}}},
      {Quantity::AngularVelocity, {{"rad/s", 1.0}, {"1/s", 1.0}, {"/s", 1.0}, {"Hz", 2.0 * M_PI}, {"rpm", 2.0 * M_PI / 60.0}}},
  };
  return tables.at(q);
}

std::string trim(std::string_view s) {
  size_t b = 0, e = s.size();
  while (b < e && std::isspace(static_cast<unsigned char>(s[b]))) ++b;
  while (e > b && std::isspace(static_cast<unsigned char>(s[e - 1]))) --e;
  return std::string(s.substr(b, e - b));
}

}  // namespace

std::string_view quantity_name(Quantity q) {
  switch (q) {
    case Quantity::Dimensionless: return "dimensionless number";
    case Quantity::Length: return "length";
    case Quantity::Area: return "area";
    case Quantity::Volume: return "volume";
    case Quantity::Time: return "time";
    case Quantity::Frequency: return "frequency";
    case Quantity::Pressure: return "pressure/stress/modulus";
    case Quantity::Density: return "density";
    case Quantity::Energy: return "energy";
    case Quantity::FractureEnergy: return "fracture energy";
    case Quantity::Velocity: return "velocity";
    case Quantity::Acceleration: return "acceleration";
    case Quantity::Force: return "force";
    case Quantity::Mass: return "mass";
    case Quantity::StrainRate: return "strain rate";
    case Quantity::AngularVelocity: return "angular velocity";
  }
  return "quantity";
}

std::string accepted_units(Quantity q) {
  std::string out;
  for (const auto& [name, factor] : table(q)) {
    if (name.empty()) continue;
    if (!out.empty()) out += ", ";
    out += name;
  }
  return out.empty() ? std::string("no unit") : out;
}

double parse_quantity(const std::string& text, Quantity q, const std::string& file,
                      const std::string& field) {
  const std::string s = trim(text);
  size_t pos = 0;
  double value = 0.0;
  const std::string expected = std::string(quantity_name(q)) + " as a number in SI units or '<number> <unit>'";
  // Decimal only: stod also reads hexadecimal ("0x10" was 16, "0x1p-24" a time step).
  if (s.find_first_of("xX") != std::string::npos && s.find_first_of("xX") < s.find_first_of(" \t"))
    throw InputError(file, field, "'" + text + "' is not a decimal number", expected);
  try {
    value = std::stod(s, &pos);
  } catch (const std::out_of_range&) {  // beyond a double's range (or below its smallest)
    throw InputError(file, field, "'" + text + "' is out of the range of a double", "a finite number");
  } catch (...) {
    throw InputError(file, field, "'" + text + "' is not a number", expected);
  }
  if (!std::isfinite(value))
    throw InputError(file, field, "'" + text + "' is not finite", "a finite number");
  const std::string unit = trim(std::string_view(s).substr(pos));
  if (unit.empty()) return value;  // a plain number is SI
  for (const auto& [name, factor] : table(q)) {
    if (unit == name) {
      const double si = value * factor;  // 1e300 GPa is finite text and an infinite quantity
      if (!std::isfinite(si))
        throw InputError(file, field, "'" + text + "' is " + (std::isnan(si) ? "not a number" : "infinite") + " in SI units",
                         "a finite quantity");
      return si;
    }
  }
  throw InputError(file, field, "unit '" + unit + "' is not a unit of " + std::string(quantity_name(q)),
                   "one of: " + accepted_units(q) + (unit.empty() ? "" : ", or a plain number in SI"));
}

std::string short_number(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.6g", v);
  return b;
}

}  // namespace breccia
