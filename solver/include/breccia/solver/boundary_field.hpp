#pragma once
// A boundary value given by expression (`boundary[].expression` of a case): the velocity or
// displacement of each particle of the set as a function of its reference position and of
// time. The host evaluates it (muparser is host code) into the constraint's per-particle
// values, once when the expression does not name t and its ramp is over, every step
// otherwise; the step's Constrain functor reads those values on any backend.
#include <memory>
#include <string>
#include <vector>

#include "breccia/common/expression.hpp"
#include "breccia/solver/pd_system.hpp"

namespace breccia::solver {

struct BoundaryField {
  std::vector<Expression> components;  // one per component of the case (2 in 2D, 3 in 3D)
  bool uses_time = false;              // any component names t
};

// The field of `boundary[index]` of case file `file`, or null when it has a constant value.
std::shared_ptr<const BoundaryField> make_boundary_field(const BoundarySpec& b, const std::string& file, size_t index);

// Gives `con` its field and one value slot (3 doubles) per particle of its set; values stay
// unevaluated until the first refresh.
void attach_boundary_field(PdSystem::Constraint& con, std::shared_ptr<const BoundaryField> field);

// Evaluates con's field at `t` (boundary_value_time of the step; times the boundary's ramp,
// boundary_ramp of load_kernels.hpp) into con.values when they do not
// already hold that; true when they changed (a device backend copies them then).
// `x0`: reference positions, 3 per particle, absolute (what the expression reads).
bool refresh_boundary_values(PdSystem::Constraint& con, const std::vector<double>& x0, double t);

// Evaluates every field that names t at each particle of its set at nine times evenly over
// [0, t_end]: an expression that stops being finite mid-run (sqrt(2e-6 - t) past 2 us) is then
// refused at set-up (InputError naming the boundary and the point), before any output is
// written, instead of a few thousand steps in. A sample, not a proof: a slip between the
// samples is still refused when the step reaches it.
void check_boundary_fields_over_run(const PdSystem& s, double t_end);

}  // namespace breccia::solver
