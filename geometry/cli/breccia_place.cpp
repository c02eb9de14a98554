// breccia-place: a gmsh mesh (or a regular lattice) -> particles.h5 (+ particles.xdmf).
//
//   breccia-place MESH.msh -o particles.h5 [--thickness T] [--volume-groups a,b]
//                 [--require-groups g1,g2]
//   breccia-place --lattice cubic  --box x0,y0,z0,x1,y1,z1 --spacing dx -o particles.h5
//   breccia-place --lattice square --box x0,y0,x1,y1 --spacing dx --thickness t -o particles.h5
//
// Lengths are metres, or "<number> <unit>" ("5 mm"). Bad input: a message naming the
// file and the entity on stderr, exit code 2, and no output file.
#include <chrono>
#include <cstdio>
#include <exception>
#include <optional>
#include <string>
#include <vector>

#include "breccia/common/error.hpp"
#include "breccia/common/particle_file.hpp"
#include "breccia/common/units.hpp"
#include "breccia/geometry/lattice.hpp"
#include "breccia/geometry/place.hpp"
#include "breccia/geometry/summary.hpp"

namespace {

constexpr const char* kUsage =
    "usage:\n"
    "  breccia-place MESH.msh -o particles.h5 [--thickness T] [--volume-groups a,b]\n"
    "                [--require-groups g1,g2]\n"
    "  breccia-place --lattice cubic --box x0,y0,z0,x1,y1,z1 --spacing dx -o particles.h5\n"
    "  breccia-place --lattice square --box x0,y0,x1,y1 --spacing dx --thickness t -o particles.h5\n"
    "\n"
    "MESH.msh: gmsh format 2.2 or 4.1, linear tetrahedra (3D) or triangles in z = 0 (2D).\n"
    "One particle per cell at its centroid with the exact cell volume (2D: area x T).\n"
    "--thickness is required for 2D meshes and square lattices. Lengths in metres or\n"
    "with a unit (\"5 mm\"). Output format: docs/formats.md, section particles.h5.\n";

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

Arguments parse_arguments(int argc, char** argv) {
  Arguments args;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw breccia::InputError(kCommandLine, a, "no value", "a value after " + a);
      return argv[++i];
    };
    if (a == "-o" || a == "--output") args.output_path = value();
    else if (a == "--thickness") args.thickness = value();
    else if (a == "--volume-groups") args.volume_groups = split_commas(value());
    else if (a == "--require-groups") args.required_groups = split_commas(value());
    else if (a == "--lattice") args.lattice = value();
    else if (a == "--box") args.box = value();
    else if (a == "--spacing") args.spacing = value();
    else if (!a.empty() && a[0] == '-')
      throw breccia::InputError(kCommandLine, a, "unknown option",
                                "-o, --thickness, --volume-groups, --require-groups, --lattice, --box, --spacing");
    else if (args.mesh_path.empty()) args.mesh_path = a;
    else throw breccia::InputError(kCommandLine, a, "a second input file", "one MESH.msh");
  }
  if (args.output_path.empty()) throw breccia::InputError(kCommandLine, "-o", "missing", "-o particles.h5");
  if (args.lattice && !args.mesh_path.empty())
    throw breccia::InputError(kCommandLine, "--lattice", "given together with the mesh " + args.mesh_path,
                              "either a mesh file or --lattice");
  if (!args.lattice && args.mesh_path.empty())
    throw breccia::InputError(kCommandLine, "MESH.msh", "missing", "a mesh file or --lattice cubic|square");
  return args;
}

double length(const std::string& text, const std::string& field) {
  return breccia::parse_quantity(text, breccia::Quantity::Length, kCommandLine, field);
}

breccia::ParticleModel make_lattice_from(const Arguments& args) {
  using breccia::geometry::LatticeKind;
  breccia::geometry::LatticeSpec spec;
  if (*args.lattice == "cubic") spec.kind = LatticeKind::Cubic;
  else if (*args.lattice == "square") spec.kind = LatticeKind::Square;
  else throw breccia::InputError(kCommandLine, "--lattice", "'" + *args.lattice + "'", "cubic or square");
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
  for (int i = 1; i < argc; ++i)
    if (std::string(argv[i]) == "-h" || std::string(argv[i]) == "--help") {
      std::fputs(kUsage, stdout);
      return 0;
    }
  const auto start = std::chrono::steady_clock::now();
  try {
    const Arguments args = parse_arguments(argc, argv);
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
  } catch (const breccia::InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return breccia::kExitBadInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return breccia::kExitRunFailed;
  }
}
