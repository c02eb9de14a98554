#include "breccia/solver/boundary_field.hpp"

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
  return f;
}

void attach_boundary_field(PdSystem::Constraint& con, std::shared_ptr<const BoundaryField> field) {
  con.field = std::move(field);
  con.values.assign(con.field ? 3 * con.particles.size() : 0, 0.0);
  con.values_time = std::numeric_limits<double>::quiet_NaN();
}

bool refresh_boundary_values(PdSystem::Constraint& con, const std::vector<double>& x0, double t) {
  const BoundaryField& f = *con.field;
  const double ramp_time = con.spec->ramp_time;
  const bool fresh = !std::isnan(con.values_time) && (!f.uses_time || t == con.values_time) &&
                     boundary_ramp(ramp_time, t) == boundary_ramp(ramp_time, con.values_time);
  if (fresh) return false;
  const double ramp = boundary_ramp(ramp_time, t);
  std::vector<double> at(4, t);
  for (size_t q = 0; q < con.particles.size(); ++q) {
    const int64_t i = con.particles[q];
    for (int k = 0; k < 3; ++k) at[k] = x0[3 * i + k];
    for (size_t d = 0; d < 3; ++d) con.values[3 * q + d] = d < f.components.size() ? ramp * f.components[d](at) : 0.0;
  }
  con.values_time = t;
  return true;
}

void check_boundary_fields_over_run(const PdSystem& s, double t_end) {
  constexpr int kSamples = 8;  // intervals: nine times, both ends included
  for (const PdSystem::Constraint& con : s.constraints) {
    if (!con.field || !con.field->uses_time) continue;
    std::vector<double> at(4);
    for (int k = 0; k <= kSamples; ++k) {
      at[3] = t_end * k / kSamples;
      for (const int64_t i : con.particles) {
        for (int d = 0; d < 3; ++d) at[d] = s.x0[3 * i + d];
        for (const Expression& e : con.field->components) e(at);  // throws where not finite
      }
    }
  }
}

}  // namespace breccia::solver
