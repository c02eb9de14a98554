// breccia-mesh: specimen spec (YAML) or existing geometry/mesh -> gmsh 4.1 .msh.
//   breccia-mesh SPEC.yaml -o OUT.msh [--size-factor F] [--threads N]
//   breccia-mesh INPUT.{geo,step,stp,msh} -o OUT.msh [--size S] [--threads N]
// Progress goes to stderr, the summary to stdout. Bad input: exit 2 with one message.
// The command line is CLI11's with the tools' conventions (common/cli.hpp).
#include <cstdio>
#include <filesystem>
#include <string>

#include "breccia/common/cli.hpp"
#include "breccia/common/error.hpp"
#include "breccia/common/units.hpp"
#include "breccia/mesher/mesher.hpp"

namespace {

constexpr const char* kAbout =
    "breccia-mesh: mesh a parametric specimen (YAML) or an existing geometry or mesh into a gmsh 4.1\n"
    ".msh file with its physical groups (materials, surfaces, holes) named.";
constexpr const char* kFooter =
    "Inputs: SPEC.yaml, a parametric specimen (docs/specimen-format.md), or INPUT.geo/.step/.stp/.msh.\n"
    "Output: OUT.msh (gmsh 4.1); progress goes to stderr, the summary (elements, nodes, sizes, groups)\n"
    "to stdout. Bad input: one message naming the file and field, exit code 2, no output file.\n"
    "Example: breccia-mesh cases/concrete-blast/specimen-quick.yaml -o specimen.msh";

struct Arguments {
  std::string input;
  breccia::mesher::MeshOptions options;
  std::string size_factor, size;  // quantities, read once the command line is parsed
};

double parse_positive(const std::string& flag, const std::string& text, breccia::Quantity q) {
  const double v = breccia::parse_quantity(text, q, "command line", flag);
  if (!(v > 0)) breccia::cli::usage_error(flag, text, "a positive value");
  return v;
}

bool is_spec(const std::string& input) {
  const auto ext = std::filesystem::path(input).extension();
  return ext == ".yaml" || ext == ".yml";
}

}  // namespace

int main(int argc, char** argv) {
  using namespace breccia;
  Arguments args;
  CLI::App app{kAbout, "breccia-mesh"};
  cli::configure(app, kFooter);
  app.add_option("INPUT", args.input, "SPEC.yaml, or a geometry or mesh: .geo, .step, .stp, .msh")
      ->required()
      ->type_name("FILE");
  app.add_option("-o,--output", args.options.output, "the mesh to write (.msh)")->required()->type_name("OUT.msh");
  app.add_option("--size-factor", args.size_factor, "multiply every element size of the spec by F (default 1)")
      ->type_name("F");
  app.add_option("--size", args.size, "maximum element size for .geo/.step input, e.g. '5 mm' (SI if no unit)")
      ->type_name("S");
  app.add_option("--threads", args.options.threads, "gmsh threads (default 1)")
      ->type_name("N")
      ->check(cli::whole_number(1, 1024));
  app.add_flag_callback(
      "-q,--quiet", [&] { args.options.verbose = false; }, "no progress on stderr");
  if (const auto code = cli::parse(app, argc, argv)) return *code;
  return breccia::cli::run_reporting_errors([&]() -> int {
    if (std::filesystem::path(args.options.output).extension() != ".msh")
      cli::usage_error("-o", "'" + args.options.output + "'", "a file name ending in .msh");
    cli::require_writable_folder("-o", std::filesystem::path(args.options.output).parent_path());
    if (!args.size_factor.empty())
      args.options.size_factor = parse_positive("--size-factor", args.size_factor, Quantity::Dimensionless);
    if (!args.size.empty()) args.options.size_m = parse_positive("--size", args.size, Quantity::Length);
    mesher::MeshSummary summary;
    if (is_spec(args.input)) {
      if (args.options.size_m > 0)
        cli::usage_error("--size", "given with a spec", ".geo/.step input (a spec sets mesh.size)");
      summary = mesher::mesh_specimen(mesher::load_specimen(args.input), args.options);
    } else {
      summary = mesher::mesh_file(args.input, args.options);
    }
    mesher::print_summary(summary, stdout);
    return 0;
  });
}
