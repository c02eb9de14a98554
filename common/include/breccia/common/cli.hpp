#pragma once
// The command line of every Breccia tool: CLI11 with the project's conventions, in one place.
//   - --help says what the tool does, its inputs and its outputs, and exits 0;
//   - --version prints the project's version (CMake's project(VERSION)) and exits 0;
//   - a usage error (unknown option, malformed number, missing value) prints one message
//     naming the option and what was expected, and exits 2 (kExitBadInput), whatever CLI11's
//     own exit code for it would be.
// Usage errors found after parsing (two options that exclude each other) are InputErrors
// with file "command line", as in usage_error below: the tools print those the same way.
#include <CLI/CLI.hpp>
#include <climits>
#include <exception>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace breccia::cli {

// The project's version, e.g. "0.1.0": the same string for every tool.
const char* version();

// Sets up `app` the same way for every tool: --version, the text after the options
// (`footer`: inputs, outputs, examples), unknown arguments collected for parse() to name, and
// an option given twice taking its last value (as the hand-written parsers did; CLI11 would
// refuse it). Call it first, before adding the options: the last rule applies to options
// added after it.
void configure(CLI::App& app, const std::string& footer);

// Parses the command line. nullopt: go on. Otherwise the tool returns the code at once:
// 0 after --help or --version (printed to stdout), 2 after a usage error (one message on
// stderr). `speak` false prints nothing (the MPI ranks other than 0: the message appears
// once, and every rank exits with the same code).
std::optional<int> parse(CLI::App& app, int argc, char** argv, bool speak = true);

// The whole number `text` is, with nothing after it, or nullopt ("4x", "2.5", "", out of range).
std::optional<long long> to_whole_number(const std::string& text);

// Checks a whole number before CLI11 converts it: "4x", "two", "2.5" and numbers outside
// [min, max] are rejected with the text and the range ("--threads: '4x' is not a number
// (expected a whole number >= 1)"), where a bare std::stoi takes "4x" as 4. The default
// bound is the largest int (the message then gives the lower bound only).
CLI::Validator whole_number(long long min, long long max = INT_MAX);
// The same for a real number: finite, and nothing after it ("10s" is rejected).
CLI::Validator real_number();
// A real number above `lower` (or at it, where `lower_included`): "--m: '-1' is out of range
// (expected a real number > 0)".
CLI::Validator real_number(double lower, bool lower_included);

// One of a fixed set of words (--backend cpu|cuda|auto): anything else is rejected with the
// list ("--backend: 'gpu' is not one of the choices (expected one of cpu, cuda, auto)").
CLI::Validator one_of(std::vector<std::string> choices);

// Runs a tool's work after parsing: its return value, or an error printed once as
// "error: ..." with exit code 2 for bad input (InputError) and 3 for a failure mid-way.
int run_reporting_errors(const std::function<int()>& work);

// What a failure that is not an InputError says: its what(), or for std::bad_alloc that the
// machine's memory ran out (what() says only "std::bad_alloc").
std::string failure_message(const std::exception& e);

// A usage error found after parsing, in the format of the tools' other input errors; throws
// breccia::InputError (exit code 2).
[[noreturn]] void usage_error(const std::string& option, const std::string& found, const std::string& expected);

// A folder that cannot take the tool's outputs (breccia::folder_write_problem) as a usage
// error naming `option` (exit 2): called before a tool's work, so that an output path it
// cannot write is reported at once, not as a failure once the work is done.
void require_writable_folder(const std::string& option, const std::filesystem::path& folder);
// Its error, for a caller that learnt `why` elsewhere (a distributed run's ranks other than 0
// learn only that rank 0 could not write: `why` empty).
[[noreturn]] void unwritable_folder_error(const std::string& option, const std::filesystem::path& folder,
                                          const std::string& why);

}  // namespace breccia::cli
