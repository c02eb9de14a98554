#pragma once
// The command-line contract every tool shares (common/cli.hpp), checked by running the
// executable as a user would: --help and --version exit 0, and a malformed number or an
// unknown option is a usage error, exit code 2, with a message naming the option. Each
// tests/<stage>/test_cli.cpp calls expect_cli_contract for its tools.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <regex>
#include <string>
#include <vector>

#include "breccia/common/cli.hpp"

namespace breccia::testing {

struct ToolRun {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
};

inline ToolRun run_tool(const std::string& exe, const std::string& args) {
  const std::string cmd = "'" + exe + "' " + args + " 2>&1";
  ToolRun r;
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) return r;
  std::array<char, 4096> buf{};
  while (fgets(buf.data(), buf.size(), p)) r.output += buf.data();
  const int status = pclose(p);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

// An option given a value that is not what it takes, e.g. {"--threads", "4x"}: the message
// must name the option and say what was expected.
struct Malformed {
  std::string option, value;
};

// `name`: the tool's name; `usable`: arguments that would otherwise be a whole command line
// (usage errors are found before any file is read, so the files need not exist).
inline void expect_cli_contract(const std::string& exe, const std::string& name, const std::string& usable,
                                const std::vector<Malformed>& malformed) {
  const ToolRun help = run_tool(exe, "--help");
  EXPECT_EQ(help.exit_code, 0) << help.output;
  EXPECT_NE(help.output.find("Usage: " + name), std::string::npos) << help.output;
  EXPECT_NE(help.output.find("--version"), std::string::npos) << help.output;

  const ToolRun version = run_tool(exe, "--version");
  EXPECT_EQ(version.exit_code, 0) << version.output;
  EXPECT_EQ(version.output, name + " (Breccia) " + cli::version() + "\n");
  EXPECT_TRUE(std::regex_match(std::string(cli::version()), std::regex(R"(\d+\.\d+\.\d+)"))) << cli::version();

  const ToolRun unknown = run_tool(exe, usable + " --no-such-option");
  EXPECT_EQ(unknown.exit_code, 2) << unknown.output;
  EXPECT_NE(unknown.output.find("error: command line: --no-such-option: unknown option"), std::string::npos)
      << unknown.output;

  for (const Malformed& m : malformed) {
    const ToolRun r = run_tool(exe, usable + " " + m.option + " '" + m.value + "'");
    EXPECT_EQ(r.exit_code, 2) << m.option << " " << m.value << ": " << r.output;
    EXPECT_NE(r.output.find("error: command line: " + m.option + ": "), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("expected"), std::string::npos) << r.output;
  }
}

}  // namespace breccia::testing
