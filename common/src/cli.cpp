// The shared conventions of the tools' command lines (cli.hpp).
#include "breccia/common/cli.hpp"

#include <cerrno>
#include <climits>
#include <new>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>

#include "breccia/common/error.hpp"
#include "breccia/common/output_file.hpp"

#ifndef BRECCIA_VERSION
#error "BRECCIA_VERSION comes from CMake's project(VERSION ...) (common/CMakeLists.txt)"
#endif

namespace breccia::cli {

const char* version() {
  return BRECCIA_VERSION;
}

void configure(CLI::App& app, const std::string& footer) {
  app.set_version_flag("--version", app.get_name() + " (Breccia) " + version(), "Print the version and exit");
  app.footer(footer);
  // Unknown options and surplus arguments are collected, not thrown: parse() names the
  // first one and lists the options (CLI11's own message lists them all, unnamed).
  app.allow_extras();
  app.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  app.get_formatter()->column_width(36);
}

namespace {

std::string option_names(const CLI::App& app) {
  std::string names;
  for (const CLI::Option* o : app.get_options()) {
    if (o->get_lnames().empty() && o->get_snames().empty()) continue;  // positional
    names += (names.empty() ? "" : ", ") + o->get_name();
  }
  return names;
}

std::string positional_names(const CLI::App& app) {
  std::string names;
  for (const CLI::Option* o : app.get_options())
    if (o->get_lnames().empty() && o->get_snames().empty()) names += (names.empty() ? "" : " ") + o->get_name();
  return names.empty() ? "no arguments besides the options" : names;
}

// The first unknown option, else the first surplus argument, as an InputError.
void reject_extras(const CLI::App& app) {
  const std::vector<std::string> extras = app.remaining();
  if (extras.empty()) return;
  for (const std::string& e : extras)
    if (e.size() > 1 && e[0] == '-')
      throw InputError("command line", e.substr(0, e.find('=')), "unknown option", "one of " + option_names(app));
  throw InputError("command line", "'" + extras.front() + "'", "an argument too many", positional_names(app));
}

}  // namespace

std::optional<int> parse(CLI::App& app, int argc, char** argv, bool speak) {
  const std::string hint = "(" + app.get_name() + " --help lists the options)\n";
  try {
    app.parse(argc, argv);
    reject_extras(app);
    return std::nullopt;
  } catch (const CLI::Success& e) {  // --help, --version
    if (speak) app.exit(e, std::cout, std::cerr);
    return 0;
  } catch (const CLI::ArgumentMismatch& e) {
    // CLI11 says "--threads: 1 required N missing" for an option given last without its value.
    std::string what = e.what();
    if (const size_t colon = what.find(": "); colon != std::string::npos && what.ends_with(" missing")) {
      const std::string option = what.substr(0, colon);
      what = option + ": no value (expected a value after " + option + ")";
    }
    if (speak) std::cerr << "error: command line: " << what << "\n" << hint;
    return kExitBadInput;
  } catch (const CLI::ParseError& e) {
    if (speak) std::cerr << "error: command line: " << e.what() << "\n" << hint;
    return kExitBadInput;  // CLI11's codes (105-115) differ by kind; the tools' contract is 2
  } catch (const InputError& e) {
    if (speak) std::cerr << "error: " << e.what() << "\n" << hint;
    return kExitBadInput;
  }
}

std::optional<long long> to_whole_number(const std::string& text) {
  errno = 0;
  char* end = nullptr;
  const long long v = std::strtoll(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0' || errno == ERANGE) return std::nullopt;
  return v;
}

CLI::Validator whole_number(long long min, long long max) {
  std::string expected = "a whole number";
  if (max >= INT_MAX)
    expected += " >= " + std::to_string(min);
  else
    expected += " from " + std::to_string(min) + " to " + std::to_string(max);
  return CLI::Validator(
      [min, max, expected](std::string& text) -> std::string {
        const std::optional<long long> v = to_whole_number(text);
        if (!v) return "'" + text + "' is not a number (expected " + expected + ")";
        if (*v < min || *v > max) return "'" + text + "' is out of range (expected " + expected + ")";
        return {};
      },
      "");
}

CLI::Validator real_number() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        if (text.empty() || *end != '\0' || !std::isfinite(v))
          return "'" + text + "' is not a number (expected a finite real number, e.g. 0.02 or 2e-2)";
        return {};
      },
      "");
}

CLI::Validator real_number(double lower, bool lower_included) {
  char bound[64];
  std::snprintf(bound, sizeof bound, "%s %g", lower_included ? ">=" : ">", lower);
  return CLI::Validator(
      [lower, lower_included, bound = std::string(bound)](std::string& text) -> std::string {
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        if (text.empty() || *end != '\0' || !std::isfinite(v))
          return "'" + text + "' is not a number (expected a real number " + bound + ")";
        if (lower_included ? v < lower : v <= lower) return "'" + text + "' is out of range (expected a real number " + bound + ")";
        return {};
      },
      "");
}

CLI::Validator one_of(std::vector<std::string> choices) {
  std::string list;
  for (const auto& c : choices) list += (list.empty() ? "" : ", ") + c;
  return CLI::Validator(
      [choices = std::move(choices), list](std::string& text) -> std::string {
        for (const auto& c : choices)
          if (text == c) return {};
        return "'" + text + "' is not one of the choices (expected one of " + list + ")";
      },
      "");
}

void usage_error(const std::string& option, const std::string& found, const std::string& expected) {
  throw InputError("command line", option, found, expected);
}

void unwritable_folder_error(const std::string& option, const std::filesystem::path& folder, const std::string& why) {
  usage_error(option, "'" + folder.string() + "' not writable" + (why.empty() ? std::string() : " (" + why + ")"),
              "a folder this user can write");
}

void require_writable_folder(const std::string& option, const std::filesystem::path& folder) {
  if (const std::string why = breccia::folder_write_problem(folder); !why.empty())
    unwritable_folder_error(option, folder, why);
}

int run_reporting_errors(const std::function<int()>& work) {
  try {
    return work();
  } catch (const InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", failure_message(e).c_str());
    return kExitRunFailed;
  }
}

std::string failure_message(const std::exception& e) {
  if (dynamic_cast<const std::bad_alloc*>(&e))
    return "out of memory: the case needs more memory than this machine gave (breccia-plan CASE estimates it)";
  return e.what();
}

}  // namespace breccia::cli
