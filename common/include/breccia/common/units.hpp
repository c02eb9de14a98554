#pragma once
// Physical quantities in input files: a plain number is SI; a string "<number> <unit>"
// is converted to SI. A unit of the wrong kind ("5 mm" for a pressure) is an error that
// names the field and lists the accepted units.
#include <string>
#include <string_view>

namespace breccia {

enum class Quantity {
  Dimensionless, Length, Area, Volume, Time, Frequency, Pressure, Density, Energy,
  FractureEnergy, Velocity, Acceleration, Force, Mass, StrainRate,
  AngularVelocity  // rad/s; "Hz" is turns per second (2 pi rad/s), "rpm" turns per minute
};

std::string_view quantity_name(Quantity q);
std::string accepted_units(Quantity q);

// Parse "<number>" or "<number> <unit>" into SI; throws InputError naming file/field.
double parse_quantity(const std::string& text, Quantity q, const std::string& file,
                      const std::string& field);

// A number for a message, in 6 significant digits ("%.6g"): std::to_string's fixed 6
// decimals print a 2e-7 s step as "0.000000".
std::string short_number(double v);

}  // namespace breccia
