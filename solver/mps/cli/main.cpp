// breccia-mps CASE.yaml -o DIR [--threads N]: run an MPS case on its own (the same entry
// point breccia-solve calls for `model: {type: mps}`). The command line is CLI11's with the
// tools' conventions (common/cli.hpp).
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "breccia/common/cli.hpp"
#include "breccia/common/error.hpp"
#include "breccia/common/yaml_input.hpp"
#include "breccia/mps/run_case.hpp"

namespace {

constexpr const char* kAbout =
    "breccia-mps: run an MPS (moving particle semi-implicit) case on its own, the solver breccia-solve\n"
    "runs for a case with `model: {type: mps}`.";
constexpr const char* kFooter =
    "Input: CASE.yaml with model.type mps (docs/case-format.md). Output: DIR/history.csv,\n"
    "DIR/results.h5 and DIR/summary.json. Bad input: one message naming the file and field, exit code 2.\n"
    "--variant and --set change the case for this run as breccia-solve's do; a relative input file is\n"
    "looked for in DIR first, then next to the case file.";

}  // namespace

int main(int argc, char** argv) {
  std::string case_file, out_dir;
  int threads = 0;
  std::string variant;
  std::vector<std::string> overrides;
  CLI::App app{kAbout, "breccia-mps"};
  breccia::cli::configure(app, kFooter);
  app.add_option("CASE", case_file, "the case file (YAML)")->required()->type_name("CASE.yaml");
  app.add_option("-o,--out", out_dir, "the folder for the results")->required()->type_name("DIR");
  app.add_option("--threads", threads, "OpenMP threads (default: all)")
      ->type_name("N")
      ->check(breccia::cli::whole_number(1));
  app.add_option("--variant", variant, "apply the case file's variants.NAME overrides (before any --set)")
      ->type_name("NAME");
  app.add_option("--set", overrides, "override a value of the case file (repeatable)")
      ->type_name("KEY=VALUE")
      ->allow_extra_args(false);
  if (const auto code = breccia::cli::parse(app, argc, argv)) return *code;
  return breccia::cli::run_reporting_errors([&]() -> int {
    breccia::Section::set_overrides(case_file, overrides, variant, out_dir);
    breccia::cli::require_writable_folder("-o", out_dir);
    return breccia::mps::run_case(case_file, out_dir, threads);
  });
}
