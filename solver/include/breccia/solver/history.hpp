#pragma once
// Time histories of the case files: a load's multiplier or pressure (PD, case_config.hpp) and
// the ground motion of MPS obstacles (mps/contact_spec.hpp). Plain data and one parser; no
// kernel header, so both solvers' headers can include it.
#include <string>
#include <vector>

#include "breccia/common/units.hpp"

namespace breccia {
class Section;
}

namespace breccia::solver {

// Constant, ramp, double exponential ([Fukuda PD] eq. 12), or a CSV table (time_s, value)
// interpolated linearly and held after its end.
struct HistorySpec {
  enum class Kind { Constant, Ramp, DoubleExponential, Table } kind = Kind::Constant;
  double value = 1.0;        // Constant: value; Ramp: final value; DoubleExp: peak
  double ramp_time = 0.0;    // Ramp
  double rise_time = 0.0;    // DoubleExponential: t0
  double ratio = 0.0;        // DoubleExponential: beta/alpha
  std::vector<double> table_time, table_value;
  double at(double t) const;
};

// A history block (type: constant | ramp | double_exponential | table) with values of
// quantity q; a relative table file is looked for as Section::input_path says (the run's
// output folder, then next to the case file). Throws InputError naming the field
// (a table whose times do not increase names the file and the line).
HistorySpec parse_history(const Section& s, Quantity q);

}  // namespace breccia::solver
