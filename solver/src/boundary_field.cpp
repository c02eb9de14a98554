#include "breccia/solver/boundary_field.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace breccia::solver {

std::shared_ptr<const BoundaryField> make_boundary_field(const BoundarySpec& b, const std::string& file, size_t index) {
  if (b.expression.empty()) return nullptr;
  auto f = std::make_shared<BoundaryField>();
  const std::string key = "boundary[" + std::to_string(index) + "].expression";
  for (size_t d = 0; d < b.expression.size(); ++d) {
    f->components.emplace_back(b.expression[d], std::vector<std::string>{"x", "y", "z", "t"}, file,
                               key + "[" + std::to_string(d) + "]");
    f->uses_time = f->uses_time || f->components.back().uses("t");
  }
  f->kind = b.kind;
  f->ramp_time = b.ramp_time;
  return f;
}

void attach_boundary_field(PdSystem::Constraint& con, std::shared_ptr<const BoundaryField> field) {
  con.field = std::move(field);
  con.values.assign(con.field ? 3 * con.particles.size() : 0, 0.0);
  con.values_time = std::numeric_limits<double>::quiet_NaN();
}

double boundary_value_time(BoundarySpec::Kind kind, double t, double dt) {
  return kind == BoundarySpec::Kind::Velocity ? t - 0.5 * dt : t;
}

namespace {
double ramp_factor(double ramp_time, double t) { return ramp_time > 0 ? std::clamp(t / ramp_time, 0.0, 1.0) : 1.0; }
}  // namespace

bool refresh_boundary_values(PdSystem::Constraint& con, const std::vector<double>& x0, double t) {
  const BoundaryField& f = *con.field;
  const bool fresh = !std::isnan(con.values_time) && (!f.uses_time || t == con.values_time) &&
                     ramp_factor(f.ramp_time, t) == ramp_factor(f.ramp_time, con.values_time);
  if (fresh) return false;
  const double ramp = ramp_factor(f.ramp_time, t);
  std::vector<double> at(4, t);
  for (size_t q = 0; q < con.particles.size(); ++q) {
    const int64_t i = con.particles[q];
    for (int k = 0; k < 3; ++k) at[k] = x0[3 * i + k];
    for (size_t d = 0; d < 3; ++d) con.values[3 * q + d] = d < f.components.size() ? ramp * f.components[d](at) : 0.0;
  }
  con.values_time = t;
  return true;
}

}  // namespace breccia::solver
