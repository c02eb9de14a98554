#include "breccia/mps/bodies.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>

#include "breccia/common/error.hpp"
#include "breccia/mps/neighbours.hpp"

namespace breccia::mps {
namespace {

void add_box(const BodiesSpec& b, const BodyShapeSpec& s, int id, ParticleCloud& c) {
  std::array<long long, 3> count{1, 1, 1};
  for (int a = 0; a < b.dimension; ++a) count[a] = std::max(1LL, std::llround((s.box_m[3 + a] - s.box_m[a]) / b.spacing_m));
  const size_t added = append_lattice(b.dimension, {s.box_m[0], s.box_m[1], s.box_m[2]}, count, b.spacing_m, b.thickness_m, c);
  c.body_id.insert(c.body_id.end(), added, id);
}

// The cubic lattice cut to a cylinder along z: the axis runs along a cell corner, so the
// cross-section is symmetric under x -> -x and y -> -y (ceil(R/h) cells each side of it),
// and a particle is kept when its centre lies within the radius; round(length/h) layers.
// The surface is a staircase: the outermost centres lie between R - h and R from the axis.
void add_cylinder(const BodiesSpec& b, const BodyShapeSpec& s, int id, ParticleCloud& c) {
  const double h = b.spacing_m, radius = s.outer_radius_m;
  const long long across = static_cast<long long>(std::ceil(radius / h - 1e-9));
  const long long layers = std::max(1LL, std::llround(s.length_m / h));
  const std::array<double, 3> low{s.center_m[0] - across * h, s.center_m[1] - across * h, s.center_m[2]};
  const auto inside = [&](double x, double y, double) {
    const double dx = x - s.center_m[0], dy = y - s.center_m[1];
    return dx * dx + dy * dy <= radius * radius * (1.0 + 1e-12);
  };
  const size_t added = append_lattice(3, low, {2 * across, 2 * across, layers}, h, h, c, inside);
  c.body_id.insert(c.body_id.end(), added, id);
}

// Concentric circles, as many as fit the wall at about one spacing, each with about one
// spacing between particles and every other circle rotated by half a step; a particle's
// volume is its annular sector, so the volumes sum to the annulus exactly.
void add_annulus(const BodiesSpec& b, const BodyShapeSpec& s, int id, ParticleCloud& c) {
  const double wall = s.outer_radius_m - s.inner_radius_m;
  const long long layers = std::max(1LL, std::llround(wall / b.spacing_m));
  const double h = wall / layers;
  for (long long k = 0; k < layers; ++k) {
    const double r = s.inner_radius_m + (k + 0.5) * h;
    const long long count = std::max(3LL, std::llround(2.0 * std::numbers::pi * r / h));
    const double step = 2.0 * std::numbers::pi / count;
    for (long long m = 0; m < count; ++m) {
      const double theta = (m + 0.5 * (k % 2)) * step;
      c.position_m.push_back(s.center_m[0] + r * std::cos(theta));
      c.position_m.push_back(s.center_m[1] + r * std::sin(theta));
      c.position_m.push_back(0.0);
      c.volume_m3.push_back(r * step * h * b.thickness_m);
      c.body_id.push_back(id);
    }
  }
}

}  // namespace

ParticleCloud build_bodies_cloud(const CaseSpec& spec) {
  const BodiesSpec& b = *spec.bodies;
  ParticleCloud c;
  c.dimension = b.dimension;
  c.spacing_m = b.spacing_m;
  c.thickness_m = b.thickness_m;
  for (size_t k = 0; k < b.shapes.size(); ++k) {
    const BodyShapeSpec& s = b.shapes[k];
    const size_t first = c.volume_m3.size();
    if (s.type == "box") add_box(b, s, static_cast<int>(k), c);
    else if (s.type == "cylinder") add_cylinder(b, s, static_cast<int>(k), c);
    else add_annulus(b, s, static_cast<int>(k), c);
    c.set_names.push_back(s.name);
    c.set_members.emplace_back();
    for (size_t i = first; i < c.volume_m3.size(); ++i) c.set_members.back().push_back(static_cast<int64_t>(i));
  }
  // Bodies must start apart: particles of two bodies closer than the contact distance
  // would start in penetration and be thrown apart by the penalty.
  const double distance = (spec.particle_contact ? spec.particle_contact->distance_factor : 1.0) * b.spacing_m;
  const BondList close = build_bonds(b.dimension, c.position_m, distance * (1.0 - 1e-6));
  for (size_t i = 0; i < close.particles(); ++i)
    for (long long m = close.offset[i]; m < close.offset[i + 1]; ++m) {
      const int j = close.neighbour[m];
      if (c.body_id[i] == c.body_id[j]) continue;
      const int later = std::max(c.body_id[i], c.body_id[j]), earlier = std::min(c.body_id[i], c.body_id[j]);
      char gap[64];
      std::snprintf(gap, sizeof gap, "%.4g m", std::sqrt(close.rx[m] * close.rx[m] + close.ry[m] * close.ry[m] + close.rz[m] * close.rz[m]));
      throw InputError(spec.file, "specimen.bodies.shapes[" + std::to_string(later) + "]",
                       "overlaps body '" + b.shapes[earlier].name + "' (particles " + gap + " apart)",
                       "bodies at least the contact distance (" + std::to_string(distance) + " m) apart at the start");
    }
  return c;
}

}  // namespace breccia::mps
