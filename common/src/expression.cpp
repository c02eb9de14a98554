#include "breccia/common/expression.hpp"

#include <muParser.h>

#include <cmath>
#include <regex>

#include "breccia/common/error.hpp"

namespace breccia {

struct Expression::Impl {
  mu::Parser parser;
  std::vector<double> slots;
};

Expression::Expression(const std::string& text, const std::vector<std::string>& variables, const std::string& file,
                       const std::string& field)
    : impl_(std::make_unique<Impl>()), text_(text), file_(file), field_(field) {
  std::string names;
  for (const auto& v : variables) names += (names.empty() ? "" : ", ") + v;
  impl_->slots.assign(variables.size(), 0.0);
  try {
    // Built with GCC, muparser 2.3 defines _pi as 3.141592653589 (for speed), 2.5e-13 off:
    // full precision here, so that an expression agrees with the same formula in C++.
    impl_->parser.DefineConst("_pi", 3.141592653589793238462643);
    impl_->parser.DefineConst("_e", 2.718281828459045235360287);
    for (size_t k = 0; k < variables.size(); ++k) impl_->parser.DefineVar(variables[k], &impl_->slots[k]);
    impl_->parser.SetExpr(text);
    impl_->parser.Eval();  // parses now: syntax errors and unknown names surface here
  } catch (const mu::Parser::exception_type& e) {
    // muparser counts from 0 and says so in some messages only: one position, from 1.
    const std::string msg = std::regex_replace(e.GetMsg(), std::regex(" (found )?at position [0-9]+\\.?"), "");
    throw InputError(file, field,
                     "'" + text + "': " + msg + " (at position " + std::to_string(e.GetPos() + 1) + ", counting from 1)",
                     "an expression in " + names + " (SI units), e.g. '100 * (z / 0.05 - 1)'");
  }
}

Expression::~Expression() = default;
Expression::Expression(Expression&&) noexcept = default;
Expression& Expression::operator=(Expression&&) noexcept = default;

bool Expression::uses(const std::string& variable) const {
  const mu::varmap_type used = impl_->parser.GetUsedVar();
  return used.count(variable) > 0;
}

double Expression::operator()(const std::vector<double>& values) const {
  for (size_t k = 0; k < impl_->slots.size() && k < values.size(); ++k) impl_->slots[k] = values[k];
  double v;
  try {
    v = impl_->parser.Eval();
  } catch (const mu::Parser::exception_type& e) {
    throw InputError(file_, field_, "'" + text_ + "': " + e.GetMsg(), "an expression that evaluates everywhere");
  }
  if (!std::isfinite(v)) {
    std::string at;
    for (double x : values) at += (at.empty() ? "" : ", ") + std::to_string(x);
    throw InputError(file_, field_, "'" + text_ + "' is not finite at (" + at + ")",
                     "an expression finite at every particle (a division by zero?)");
  }
  return v;
}

}  // namespace breccia
