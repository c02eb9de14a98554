// The lattice specimen's particle model (lattice_model.hpp).
#include "breccia/solver/lattice_model.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

namespace breccia::solver {

std::array<int64_t, 3> lattice_point_counts(const LatticeSpec& l) {
  std::array<int64_t, 3> count{1, 1, 1};
  for (int k = 0; k < l.dimension; ++k)
    count[k] = std::max<int64_t>(1, std::llround((l.box[k + l.dimension] - l.box[k]) / l.spacing));
  return count;
}

namespace {
// Lattice point idx's position (its cell's centre; 0 beyond the dimension).
void lattice_point(const LatticeSpec& l, const long long idx[3], double x[3]) {
  for (int k = 0; k < 3; ++k) x[k] = k < l.dimension ? l.box[k] + (idx[k] + 0.5) * l.spacing : 0.0;
}

double lattice_volume(const LatticeSpec& l) {
  return l.dimension == 3 ? l.spacing * l.spacing * l.spacing : l.spacing * l.spacing * l.thickness;
}

}  // namespace

std::string lattice_content_id(const LatticeSpec& l) {
  const std::array<int64_t, 3> count = lattice_point_counts(l);
  ContentHash h;
  for (long long kz = 0; kz < count[2]; ++kz)
    for (long long ky = 0; ky < count[1]; ++ky)
      for (long long kx = 0; kx < count[0]; ++kx) {
        const long long idx[3] = {kx, ky, kz};
        double x[3];
        lattice_point(l, idx, x);
        h.add(x, sizeof x);
      }
  const double vol = lattice_volume(l);
  for (int64_t q = 0; q < count[0] * count[1] * count[2]; ++q) h.add(&vol, sizeof vol);
  return h.hex();
}

ParticleModel lattice_model(const LatticeSpec& l, const std::vector<int64_t>* rows) {
  ParticleModel m;
  m.dimension = l.dimension;
  m.thickness_m = l.dimension == 2 ? l.thickness : 1.0;
  const int d = l.dimension;
  const std::array<int64_t, 3> count = lattice_point_counts(l);
  const double vol = lattice_volume(l);
  const char* names[6] = {"xmin", "xmax", "ymin", "ymax", "zmin", "zmax"};
  std::vector<ParticleSet> faces(2 * d);
  for (int f = 0; f < 2 * d; ++f) faces[f].name = names[f];
  // Reserved: grown by push_back the arrays held up to twice their size to the end of the set-up.
  const size_t points = rows ? rows->size() : static_cast<size_t>(count[0] * count[1] * count[2]);
  m.position_m.reserve(3 * points);
  m.volume_m3.reserve(points);
  m.material_id.reserve(points);
  std::vector<double> face_centre;  // the face particles' positions, for their facets' centroids
  size_t next = 0;                  // the next of `rows`
  int64_t id = 0;
  for (long long kz = 0; kz < count[2]; ++kz)
    for (long long ky = 0; ky < count[1]; ++ky)
      for (long long kx = 0; kx < count[0]; ++kx, ++id) {
        const long long idx[3] = {kx, ky, kz};
        double x[3];
        lattice_point(l, idx, x);
        if (!rows || (next < rows->size() && (*rows)[next] == id)) {
          m.position_m.insert(m.position_m.end(), x, x + 3);
          m.volume_m3.push_back(vol);
          m.material_id.push_back(0);
          ++next;
        }
        bool face = false;
        for (int k = 0; k < d; ++k) {
          if (idx[k] == 0) faces[2 * k].indices.push_back(id), face = true;
          if (idx[k] == count[k] - 1) faces[2 * k + 1].indices.push_back(id), face = true;
        }
        if (face) face_centre.insert(face_centre.end(), x, x + 3);
      }
  if (rows && next != rows->size()) throw std::logic_error("lattice_model: a row outside the lattice");
  std::vector<int64_t> face_ids;  // ascending, with face_centre
  for (const ParticleSet& f : faces) face_ids.insert(face_ids.end(), f.indices.begin(), f.indices.end());
  std::sort(face_ids.begin(), face_ids.end());
  face_ids.erase(std::unique(face_ids.begin(), face_ids.end()), face_ids.end());
  const double facet_area = d == 3 ? l.spacing * l.spacing : l.spacing * l.thickness;
  for (int f = 0; f < 2 * d; ++f) {
    SurfaceFacets s;
    s.name = faces[f].name;
    for (auto id : faces[f].indices) {
      const double* centre =
          &face_centre[3 * static_cast<size_t>(std::lower_bound(face_ids.begin(), face_ids.end(), id) - face_ids.begin())];
      s.area_m2.push_back(facet_area);
      double nrm[3] = {0, 0, 0};
      nrm[f / 2] = (f % 2) ? 1.0 : -1.0;
      for (int k = 0; k < 3; ++k) {
        s.normal.push_back(nrm[k]);
        s.centroid_m.push_back(centre[k] + 0.5 * l.spacing * nrm[k]);
      }
      s.particle.push_back(id);
    }
    m.surfaces.push_back(std::move(s));
  }
  m.sets = std::move(faces);
  m.spacing_m.assign(m.volume_m3.size(), l.spacing);
  m.material_names = {"default"};
  m.source = "lattice";
  if (rows) {
    m.held_rows = *rows;
  } else {
    m.content_id = compute_content_id(m);
  }
  return m;
}

}  // namespace breccia::solver
