#pragma once
// Regular lattices in the particles.h5 format, for benchmarks and solver tests: particles
// at the centres of the cells of a box divided into cubes (3D) or squares (2D) of side dx,
// each with the exact cell volume. Particle index runs x fastest, then y, then z.
// Sets and surfaces "xmin", "xmax", "ymin", "ymax" (and "zmin", "zmax" in 3D) hold the
// outermost particle layer on each face; each boundary particle owns one facet of area
// dx^2 (2D: dx * thickness) with the outward unit normal of that face.
#include <array>
#include <string>

#include "breccia/common/particle_file.hpp"

namespace breccia::geometry {

enum class LatticeKind { Cubic, Square };

struct LatticeSpec {
  LatticeKind kind = LatticeKind::Cubic;
  std::array<double, 3> lower_m{0, 0, 0};  // box corner; z ignored for Square
  std::array<double, 3> upper_m{1, 1, 1};
  double spacing_m = 0.1;                  // dx; every box side must be a whole number of dx
  double thickness_m = 1.0;                // Square only
  std::string material = "default";
};

// Throws InputError (file "lattice") when a side is not positive or is not an integer
// multiple of the spacing (to 1e-6 of a cell), or when spacing/thickness are not positive.
ParticleModel make_lattice(const LatticeSpec& spec);

// Conveniences for tests.
ParticleModel make_cubic_lattice(std::array<double, 3> lower_m, std::array<double, 3> upper_m,
                                 double spacing_m);
ParticleModel make_square_lattice(std::array<double, 2> lower_m, std::array<double, 2> upper_m,
                                  double spacing_m, double thickness_m);

}  // namespace breccia::geometry
