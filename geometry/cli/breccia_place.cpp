// breccia-place: a gmsh mesh (or a regular lattice) -> particles.h5 (+ particles.xdmf).
//
//   breccia-place MESH.msh -o particles.h5 [--thickness T] [--volume-groups a,b]
//                 [--require-groups g1,g2]
//   breccia-place --lattice cubic  --box x0,y0,z0,x1,y1,z1 --spacing dx -o particles.h5
//   breccia-place --lattice square --box x0,y0,x1,y1 --spacing dx --thickness t -o particles.h5
//
// Lengths are metres, or "<number> <unit>" ("5 mm"). Bad input: a message naming the
// file and the entity on stderr, exit code 2, and no output file. The command line is CLI11's
// with the tools' conventions (common/cli.hpp).
#include <chrono>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "breccia/common/cli.hpp"
#include "breccia/common/error.hpp"
#include "breccia/common/particle_file.hpp"
#include "breccia/common/units.hpp"
#include "breccia/geometry/lattice.hpp"
#include "breccia/geometry/place.hpp"
#include "breccia/geometry/summary.hpp"

namespace {

constexpr const char* kAbout =
    "breccia-place: particles for the solver, one per cell of a gmsh mesh (at its centroid, with the\n"
    "exact cell volume) or on a regular lattice, written to particles.h5 (+ particles.xdmf).";
constexpr const char* kFooter =
    "Usage forms:\n"
    "  breccia-place MESH.msh -o particles.h5 [--thickness T] [--volume-groups a,b] [--require-groups g1,g2]\n"
    "  breccia-place --lattice cubic --box x0,y0,z0,x1,y1,z1 --spacing dx -o particles.h5\n"
    "  breccia-place --lattice square --box x0,y0,x1,y1 --spacing dx --thickness t -o particles.h5\n"
    "Input: MESH.msh, gmsh format 2.2 or 4.1, linear tetrahedra (3D) or triangles in z = 0 (2D; volume\n"
    "= area x T). --thickness is required for 2D meshes and square lattices. Lengths in metres or with\n"
    "a unit (\"5 mm\"). Output: particles.h5 (docs/formats.md, section particles.h5) and particles.xdmf;\n"
    "a summary on stdout. Bad input: one message naming the file and entity, exit code 2, no file.";

const std::string kCommandLine = "command line";

struct Arguments {
  std::string mesh_path;
  std::string output_path;
  std::optional<std::string> thickness, lattice, box, spacing;
  std::vector<std::string> volume_groups, required_groups;
};

std::vector<std::string> split_commas(const std::string& text) {
  std::vector<std::string> parts;
  size_t start = 0;
  while (start <= text.size()) {
    const size_t comma = text.find(',', start);
    const std::string part = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    if (!part.empty()) parts.push_back(part);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return parts;
}

// The checks that involve several options (CLI11 has parsed each one).
void check_arguments(const Arguments& args) {
  if (args.lattice && !args.mesh_path.empty())
    throw breccia::InputError(kCommandLine, "--lattice", "given together with the mesh " + args.mesh_path,
                              "either a mesh file or --lattice");
  if (!args.lattice && args.mesh_path.empty())
    throw breccia::InputError(kCommandLine, "MESH.msh", "missing", "a mesh file or --lattice cubic|square");
}

double length(const std::string& text, const std::string& field) {
  return breccia::parse_quantity(text, breccia::Quantity::Length, kCommandLine, field);
}

breccia::ParticleModel make_lattice_from(const Arguments& args) {
  using breccia::geometry::LatticeKind;
  breccia::geometry::LatticeSpec spec;
  spec.kind = *args.lattice == "cubic" ? LatticeKind::Cubic : LatticeKind::Square;  // one of the two (parse)
  const bool cubic = spec.kind == LatticeKind::Cubic;
  if (!args.box) throw breccia::InputError(kCommandLine, "--box", "missing", cubic ? "x0,y0,z0,x1,y1,z1" : "x0,y0,x1,y1");
  if (!args.spacing) throw breccia::InputError(kCommandLine, "--spacing", "missing", "the lattice spacing dx");
  const auto corners = split_commas(*args.box);
  const size_t dim = cubic ? 3 : 2;
  if (corners.size() != 2 * dim)
    throw breccia::InputError(kCommandLine, "--box", std::to_string(corners.size()) + " values",
                              cubic ? "6 values x0,y0,z0,x1,y1,z1" : "4 values x0,y0,x1,y1");
  for (size_t a = 0; a < dim; ++a) {
    spec.lower_m[a] = length(corners[a], "--box");
    spec.upper_m[a] = length(corners[dim + a], "--box");
  }
  spec.spacing_m = length(*args.spacing, "--spacing");
  if (!cubic) {
    if (!args.thickness)
      throw breccia::InputError(kCommandLine, "--thickness", "missing for a square lattice",
                                "--thickness T: particle volume = dx^2 T");
    spec.thickness_m = length(*args.thickness, "--thickness");
  }
  return breccia::geometry::make_lattice(spec);
}

}  // namespace

int main(int argc, char** argv) {
  Arguments args;
  CLI::App app{kAbout, "breccia-place"};
  breccia::cli::configure(app, kFooter);
  const auto text_into = [](std::optional<std::string>& into) { return [&into](const std::string& v) { into = v; }; };
  const auto list_into = [](std::vector<std::string>& into) {
    return [&into](const std::string& v) { into = split_commas(v); };
  };
  app.add_option("MESH.msh", args.mesh_path, "the mesh (gmsh 2.2 or 4.1); omitted with --lattice");
  app.add_option("-o,--output", args.output_path, "the particle file to write")->required()->type_name("particles.h5");
  app.add_option_function<std::string>("--thickness", text_into(args.thickness), "thickness of a 2D model, e.g. '5 mm'")
      ->type_name("T");
  app.add_option_function<std::string>("--volume-groups", list_into(args.volume_groups),
                                       "the physical groups that define materials (default: every group of the mesh dimension)")
      ->type_name("a,b");
  app.add_option_function<std::string>("--require-groups", list_into(args.required_groups),
                                       "physical groups that must exist and hold at least one particle")
      ->type_name("g1,g2");
  app.add_option_function<std::string>("--lattice", text_into(args.lattice), "a regular lattice instead of a mesh")
      ->type_name("cubic|square")
      ->check(breccia::cli::one_of({"cubic", "square"}));
  app.add_option_function<std::string>("--box", text_into(args.box), "the lattice's box corners (lengths)")
      ->type_name("x0,y0,[z0,]x1,y1[,z1]");
  app.add_option_function<std::string>("--spacing", text_into(args.spacing), "the lattice spacing (a length)")
      ->type_name("dx");
  if (const auto code = breccia::cli::parse(app, argc, argv)) return *code;
  const auto start = std::chrono::steady_clock::now();
  return breccia::cli::run_reporting_errors([&]() -> int {
    check_arguments(args);
    breccia::cli::require_writable_folder("-o", std::filesystem::path(args.output_path).parent_path());
    breccia::ParticleModel model;
    if (args.lattice) {
      model = make_lattice_from(args);
    } else {
      breccia::geometry::PlaceOptions options;
      if (args.thickness) options.thickness_m = length(*args.thickness, "--thickness");
      options.volume_groups = args.volume_groups;
      options.required_groups = args.required_groups;
      options.progress = true;
      model = breccia::geometry::place_particles(args.mesh_path, options);
    }
    breccia::write_particle_file(args.output_path, model);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::fputs(breccia::geometry::summarize(model).c_str(), stdout);
    std::printf("written     %s\ntime        %.3f s\n", args.output_path.c_str(), seconds);
    return 0;
  });
}
