#pragma once
// Fields given by expression in a case file (muparser, Debian's libmuparser-dev): an
// expression in named variables (x, y, z in metres; t in seconds where a key allows it),
// checked when it is read, so that a bad one is an input error naming the file, the key and
// the position in the text, never a failure in the middle of a run.
#include <memory>
#include <string>
#include <vector>

namespace breccia {

class Expression {
public:
  // Throws InputError(file, field, ...) for a syntax error or an unknown variable (muparser
  // reports the position, 1-based here). `variables` are the names the expression may use.
  Expression(const std::string& text, const std::vector<std::string>& variables, const std::string& file,
             const std::string& field);
  ~Expression();
  Expression(Expression&&) noexcept;
  Expression& operator=(Expression&&) noexcept;

  // The value at `values` (one per variable, in the constructor's order). Not thread-safe:
  // one Expression per thread. A non-finite result throws InputError naming the key.
  double operator()(const std::vector<double>& values) const;
  const std::string& text() const { return text_; }
  // Whether the text names `variable` (a boundary value in t is evaluated every step).
  bool uses(const std::string& variable) const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string text_, file_, field_;
};

}  // namespace breccia
