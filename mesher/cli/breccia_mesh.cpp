// breccia-mesh: specimen spec (YAML) or existing geometry/mesh -> gmsh 4.1 .msh.
//   breccia-mesh SPEC.yaml -o OUT.msh [--size-factor F] [--threads N]
//   breccia-mesh INPUT.{geo,step,stp,msh} -o OUT.msh [--size S] [--threads N]
// Progress goes to stderr, the summary to stdout. Bad input: exit 2 with one message.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "breccia/common/error.hpp"
#include "breccia/common/units.hpp"
#include "breccia/mesher/mesher.hpp"

namespace {

constexpr const char* kUsage =
    "usage: breccia-mesh SPEC.yaml -o OUT.msh [--size-factor F] [--threads N] [--quiet]\n"
    "       breccia-mesh INPUT.{geo,step,stp,msh} -o OUT.msh [--size S] [--threads N] [--quiet]\n"
    "  SPEC.yaml      parametric specimen (docs/specimen-format.md)\n"
    "  --size-factor  multiply every element size of the spec by F (default 1)\n"
    "  --size         maximum element size for .geo/.step input, e.g. '5 mm' (SI if no unit)\n"
    "  --threads      gmsh threads (default 1)\n";

struct Arguments {
  std::string input;
  breccia::mesher::MeshOptions options;
  bool size_factor_given = false;
};

[[noreturn]] void usage_error(const std::string& message) {
  throw breccia::InputError("command line", "", message, "see breccia-mesh --help");
}

double parse_positive(const std::string& flag, const std::string& text, breccia::Quantity q) {
  const double v = breccia::parse_quantity(text, q, "command line", flag);
  if (!(v > 0)) usage_error(flag + " " + text + " is not positive");
  return v;
}

Arguments parse_arguments(int argc, char** argv) {
  Arguments a;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) usage_error(arg + " needs a value");
      return argv[++i];
    };
    if (arg == "-h" || arg == "--help") {
      std::fputs(kUsage, stdout);
      std::exit(0);
    } else if (arg == "-o" || arg == "--output") {
      a.options.output = value();
    } else if (arg == "--size-factor") {
      a.options.size_factor = parse_positive(arg, value(), breccia::Quantity::Dimensionless);
      a.size_factor_given = true;
    } else if (arg == "--size") {
      a.options.size_m = parse_positive(arg, value(), breccia::Quantity::Length);
    } else if (arg == "--threads") {
      const std::string v = value();
      char* end = nullptr;
      const long n = std::strtol(v.c_str(), &end, 10);
      if (*end != '\0' || n < 1 || n > 1024) usage_error("--threads '" + v + "' is not a positive integer");
      a.options.threads = static_cast<int>(n);
    } else if (arg == "-q" || arg == "--quiet") {
      a.options.verbose = false;
    } else if (!arg.empty() && arg[0] == '-') {
      usage_error("unknown option '" + arg + "'");
    } else if (a.input.empty()) {
      a.input = arg;
    } else {
      usage_error("more than one input file ('" + a.input + "', '" + arg + "')");
    }
  }
  if (a.input.empty()) usage_error("no input file");
  if (a.options.output.empty()) usage_error("no output file (-o OUT.msh)");
  if (std::filesystem::path(a.options.output).extension() != ".msh")
    usage_error("output '" + a.options.output + "' does not end in .msh");
  return a;
}

bool is_spec(const std::string& input) {
  const auto ext = std::filesystem::path(input).extension();
  return ext == ".yaml" || ext == ".yml";
}

}  // namespace

int main(int argc, char** argv) {
  using namespace breccia;
  try {
    const Arguments args = parse_arguments(argc, argv);
    mesher::MeshSummary summary;
    if (is_spec(args.input)) {
      if (args.options.size_m > 0) usage_error("--size applies to .geo/.step input; a spec sets mesh.size");
      summary = mesher::mesh_specimen(mesher::load_specimen(args.input), args.options);
    } else {
      summary = mesher::mesh_file(args.input, args.options);
    }
    mesher::print_summary(summary, stdout);
    return 0;
  } catch (const InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return kExitRunFailed;
  }
}
