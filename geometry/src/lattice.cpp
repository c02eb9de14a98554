#include "breccia/geometry/lattice.hpp"

#include <cmath>
#include <cstdio>

#include "breccia/common/error.hpp"
#include "breccia/common/particle_file.hpp"

namespace breccia::geometry {
namespace {

constexpr const char* kAxis = "xyz";

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

// Cells along one axis; the side must be a whole number of spacings so that every
// particle carries exactly dx^3 (dx^2 t) and the lattice fills the box.
int64_t cells_along(double lower, double upper, double dx, int axis) {
  const double length = upper - lower;
  const std::string field = std::string("--box ") + kAxis[axis];
  if (!(length > 0) || !std::isfinite(length))
    throw InputError("lattice", field, "side length " + num(length) + " m", "upper > lower");
  const double ratio = length / dx;
  const double count = std::round(ratio);
  if (count < 1 || std::abs(ratio - count) > 1e-6)  // 1e-6 of a cell: decimal input round-off
    throw InputError("lattice", field,
                     "side " + num(length) + " m is " + num(ratio) + " spacings of " + num(dx) + " m",
                     "a whole number of spacings");
  return static_cast<int64_t>(count);
}

}  // namespace

ParticleModel make_lattice(const LatticeSpec& spec) {
  const double dx = spec.spacing_m;
  if (!(dx > 0) || !std::isfinite(dx))
    throw InputError("lattice", "--spacing", "value " + num(dx), "a positive length in metres");
  const bool cubic = spec.kind == LatticeKind::Cubic;
  if (!cubic && (!(spec.thickness_m > 0) || !std::isfinite(spec.thickness_m)))
    throw InputError("lattice", "--thickness", "value " + num(spec.thickness_m), "a positive length in metres");
  const int dim = cubic ? 3 : 2;
  int64_t count[3] = {1, 1, 1};
  for (int a = 0; a < dim; ++a) count[a] = cells_along(spec.lower_m[a], spec.upper_m[a], dx, a);
  const double points = static_cast<double>(count[0]) * static_cast<double>(count[1]) * static_cast<double>(count[2]);
  require_indexable_particle_count(points, "lattice", "--spacing", num(dx) + " m, " + num(points) + " lattice points");
  const int64_t n = count[0] * count[1] * count[2];

  ParticleModel m;
  m.dimension = dim;
  m.thickness_m = cubic ? 1.0 : spec.thickness_m;
  m.material_names = {spec.material};
  m.position_m.resize(3 * n);
  m.volume_m3.assign(n, cubic ? dx * dx * dx : dx * dx * spec.thickness_m);
  m.spacing_m.assign(n, dx);
  m.material_id.assign(n, 0);
  char source[256];
  std::snprintf(source, sizeof source, "lattice %s spacing %.9g m, %lld x %lld x %lld cells",
                cubic ? "cubic" : "square", dx, static_cast<long long>(count[0]),
                static_cast<long long>(count[1]), static_cast<long long>(count[2]));
  m.source = source;

  for (int64_t k = 0; k < count[2]; ++k)
    for (int64_t j = 0; j < count[1]; ++j)
      for (int64_t i = 0; i < count[0]; ++i) {
        const int64_t p = i + count[0] * (j + count[1] * k);
        const int64_t ijk[3] = {i, j, k};
        for (int a = 0; a < 3; ++a)
          m.position_m[3 * p + a] = a < dim ? spec.lower_m[a] + (static_cast<double>(ijk[a]) + 0.5) * dx : 0.0;
      }

  // One facet per particle of the outermost layer on each face.
  const double facet_area = cubic ? dx * dx : dx * spec.thickness_m;
  for (int axis = 0; axis < dim; ++axis) {
    for (int upper = 0; upper < 2; ++upper) {
      const std::string name = std::string(1, kAxis[axis]) + (upper ? "max" : "min");
      ParticleSet set{name, {}};
      SurfaceFacets surface;
      surface.name = name;
      const int64_t layer = upper ? count[axis] - 1 : 0;
      for (int64_t p = 0; p < n; ++p) {
        const int64_t ijk[3] = {p % count[0], (p / count[0]) % count[1], p / (count[0] * count[1])};
        if (ijk[axis] != layer) continue;
        set.indices.push_back(p);
        surface.area_m2.push_back(facet_area);
        surface.particle.push_back(p);
        for (int a = 0; a < 3; ++a) {
          surface.normal.push_back(a == axis ? (upper ? 1.0 : -1.0) : 0.0);
          surface.centroid_m.push_back(a == axis ? (upper ? spec.upper_m[a] : spec.lower_m[a])
                                                 : m.position_m[3 * p + a]);
        }
      }
      m.sets.push_back(std::move(set));
      m.surfaces.push_back(std::move(surface));
    }
  }
  return m;
}

ParticleModel make_cubic_lattice(std::array<double, 3> lower_m, std::array<double, 3> upper_m,
                                 double spacing_m) {
  LatticeSpec spec;
  spec.kind = LatticeKind::Cubic;
  spec.lower_m = lower_m;
  spec.upper_m = upper_m;
  spec.spacing_m = spacing_m;
  return make_lattice(spec);
}

ParticleModel make_square_lattice(std::array<double, 2> lower_m, std::array<double, 2> upper_m,
                                  double spacing_m, double thickness_m) {
  LatticeSpec spec;
  spec.kind = LatticeKind::Square;
  spec.lower_m = {lower_m[0], lower_m[1], 0.0};
  spec.upper_m = {upper_m[0], upper_m[1], 0.0};
  spec.spacing_m = spacing_m;
  spec.thickness_m = thickness_m;
  return make_lattice(spec);
}

}  // namespace breccia::geometry
