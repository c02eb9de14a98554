#pragma once
// Errors are values until a CLI turns them into a message and an exit code.
// An InputError always names where the problem is (file, field or entity), what was
// found, and what was expected; CLIs print it and exit with code 2.
#include <stdexcept>
#include <string>

namespace breccia {

inline constexpr int kExitBadInput = 2;
inline constexpr int kExitRunFailed = 3;

class InputError : public std::runtime_error {
public:
  InputError(std::string file, std::string field, std::string found, std::string expected)
      : std::runtime_error(compose(file, field, found, expected)),
        file_(std::move(file)), field_(std::move(field)) {}
  // A message composed already (another process's InputError, passed on whole: what()).
  static InputError composed(std::string file, std::string field, const std::string& message) {
    return InputError(std::move(file), std::move(field), message, Composed{});
  }
  const std::string& file() const { return file_; }
  const std::string& field() const { return field_; }

private:
  struct Composed {};
  InputError(std::string file, std::string field, const std::string& message, Composed)
      : std::runtime_error(message), file_(std::move(file)), field_(std::move(field)) {}
  static std::string compose(const std::string& file, const std::string& field,
                             const std::string& found, const std::string& expected) {
    std::string msg = file.empty() ? std::string("input") : file;
    if (!field.empty()) msg += ": " + field;
    msg += ": " + found;
    if (!expected.empty()) msg += " (expected " + expected + ")";
    return msg;
  }
  std::string file_, field_;
};

// A run that started but could not finish (instability, I/O failure mid-run).
class RunError : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

}  // namespace breccia
