#include "surface_cut.hpp"

#include <algorithm>
#include <cmath>

namespace breccia::solver {
namespace {

// Segment p->q against triangle (a, b, c): Moller-Trumbore, open segment.
bool segment_hits_triangle(const double* p, const double* q, const double* a, const double* b, const double* c) {
  const double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const double dir[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
  const double h[3] = {dir[1] * e2[2] - dir[2] * e2[1], dir[2] * e2[0] - dir[0] * e2[2], dir[0] * e2[1] - dir[1] * e2[0]};
  const double det = e1[0] * h[0] + e1[1] * h[1] + e1[2] * h[2];
  if (std::fabs(det) < 1e-300) return false;
  const double s[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]};
  const double u = (s[0] * h[0] + s[1] * h[1] + s[2] * h[2]) / det;
  if (u < 0 || u > 1) return false;
  const double qv[3] = {s[1] * e1[2] - s[2] * e1[1], s[2] * e1[0] - s[0] * e1[2], s[0] * e1[1] - s[1] * e1[0]};
  const double v = (dir[0] * qv[0] + dir[1] * qv[1] + dir[2] * qv[2]) / det;
  if (v < 0 || u + v > 1) return false;
  const double t = (e2[0] * qv[0] + e2[1] * qv[1] + e2[2] * qv[2]) / det;
  return t > 0 && t < 1;
}

// Segment p->q against segment a->b in the x-y plane (proper crossing).
bool segment_hits_segment(const double* p, const double* q, const double* a, const double* b) {
  auto orient = [](const double* o, const double* u, const double* w) {
    return (u[0] - o[0]) * (w[1] - o[1]) - (u[1] - o[1]) * (w[0] - o[0]);
  };
  const double d1 = orient(a, b, p), d2 = orient(a, b, q), d3 = orient(p, q, a), d4 = orient(p, q, b);
  return ((d1 > 0) != (d2 > 0)) && d1 != 0 && d2 != 0 && ((d3 > 0) != (d4 > 0));
}

}  // namespace

SurfaceCut::SurfaceCut(const ParticleModel& model, const SurfaceFacets& facets, double max_bond_length_m)
    : dimension_(model.dimension), thickness_m_(model.thickness_m), facets_(&facets) {
  const size_t nf = facets.size();
  const int per_facet = dimension_ == 3 ? 3 : 2;  // vertices of a facet
  const int npc = model.nodes_per_cell;
  // Recover each facet's vertices from its owner cell: the face (3D: 3 of the tet's 4
  // nodes; 2D: 2 of the triangle's 3) whose vertex mean is the stored centroid.
  exact_ = npc == dimension_ + 1 && !model.mesh_cells.empty();
  if (exact_) {
    vertices_m_.assign(nf * per_facet * 3, 0.0);
    for (size_t f = 0; f < nf && exact_; ++f) {
      const int64_t cell = facets.particle[f];
      const int64_t* nodes = &model.mesh_cells[static_cast<size_t>(cell * npc)];
      double best = 1e300;
      int skip_best = -1;
      for (int skip = 0; skip < npc; ++skip) {  // the face opposite node `skip`
        double mean[3] = {0, 0, 0};
        for (int v = 0; v < npc; ++v)
          if (v != skip)
            for (int d = 0; d < 3; ++d) mean[d] += model.mesh_nodes_m[3 * nodes[v] + d] / per_facet;
        double d2 = 0;
        for (int d = 0; d < 3; ++d) d2 += std::pow(mean[d] - facets.centroid_m[3 * f + d], 2);
        if (d2 < best) {
          best = d2;
          skip_best = skip;
        }
      }
      // The stored centroid is the mean of the same vertices: round-off only. Anything else
      // means the file's facet is not a face of its owner: fall back to discs.
      const double size = dimension_ == 3 ? std::sqrt(facets.area_m2[f]) : facets.area_m2[f] / thickness_m_;
      if (skip_best < 0 || best > 1e-12 * size * size) {
        exact_ = false;
        break;
      }
      int out = 0;
      for (int v = 0; v < npc; ++v)
        if (v != skip_best) {
          for (int d = 0; d < 3; ++d)
            vertices_m_[(f * per_facet + out) * 3 + d] = model.mesh_nodes_m[3 * nodes[v] + d];
          ++out;
        }
    }
    if (!exact_) vertices_m_.clear();
  }
  // Facet bounding boxes into the grid (discs: centroid +- radius).
  cell_m_ = std::max(max_bond_length_m, 1e-12);
  double lo[3] = {1e300, 1e300, 1e300};
  for (size_t f = 0; f < nf; ++f)
    for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], facets.centroid_m[3 * f + d]);
  for (int d = 0; d < 3; ++d) origin_m_[d] = lo[d] - 4.0 * cell_m_;
  for (size_t f = 0; f < nf; ++f) {
    double a[3], b[3];
    if (exact_) {
      for (int d = 0; d < 3; ++d) a[d] = 1e300, b[d] = -1e300;
      for (int v = 0; v < per_facet; ++v)
        for (int d = 0; d < 3; ++d) {
          a[d] = std::min(a[d], vertices_m_[(f * per_facet + v) * 3 + d]);
          b[d] = std::max(b[d], vertices_m_[(f * per_facet + v) * 3 + d]);
        }
    } else {
      const double r = dimension_ == 3 ? std::sqrt(facets.area_m2[f] / M_PI) : 0.5 * facets.area_m2[f] / thickness_m_;
      for (int d = 0; d < 3; ++d) a[d] = facets.centroid_m[3 * f + d] - r, b[d] = facets.centroid_m[3 * f + d] + r;
    }
    for (int d = 0; d < 3; ++d) {
      box_lo_[d] = std::min(box_lo_[d], a[d]);
      box_hi_[d] = std::max(box_hi_[d], b[d]);
    }
    int64_t ca[3], cb[3];
    for (int d = 0; d < 3; ++d) {
      ca[d] = static_cast<int64_t>(std::floor((a[d] - origin_m_[d]) / cell_m_));
      cb[d] = static_cast<int64_t>(std::floor((b[d] - origin_m_[d]) / cell_m_));
    }
    for (int64_t x = ca[0]; x <= cb[0]; ++x)
      for (int64_t y = ca[1]; y <= cb[1]; ++y)
        for (int64_t z = ca[2]; z <= cb[2]; ++z) grid_[key(x, y, z)].push_back(static_cast<int32_t>(f));
  }
}

bool SurfaceCut::crosses_facet(size_t f, const double* p, const double* q) const {
  if (exact_) {
    const double* v = &vertices_m_[f * (dimension_ == 3 ? 9 : 6)];
    return dimension_ == 3 ? segment_hits_triangle(p, q, v, v + 3, v + 6) : segment_hits_segment(p, q, v, v + 3);
  }
  const SurfaceFacets& s = *facets_;
  const double* n = &s.normal[3 * f];
  const double* c = &s.centroid_m[3 * f];
  const double dp = (p[0] - c[0]) * n[0] + (p[1] - c[1]) * n[1] + (p[2] - c[2]) * n[2];
  const double dq = (q[0] - c[0]) * n[0] + (q[1] - c[1]) * n[1] + (q[2] - c[2]) * n[2];
  if ((dp > 0) == (dq > 0) || dp == dq) return false;
  const double t = dp / (dp - dq);
  double r2 = 0.0;
  for (int k = 0; k < 3; ++k) {
    const double x = p[k] + t * (q[k] - p[k]) - c[k];
    r2 += x * x;
  }
  const double radius = dimension_ == 3 ? std::sqrt(s.area_m2[f] / M_PI) : 0.5 * s.area_m2[f] / thickness_m_;
  return r2 <= radius * radius * (1.0 + 1e-9);
}

bool SurfaceCut::crosses(const double* p, const double* q) const {
  for (int d = 0; d < 3; ++d)
    if (std::max(p[d], q[d]) < box_lo_[d] || std::min(p[d], q[d]) > box_hi_[d]) return false;
  int64_t c[3];
  for (int d = 0; d < 3; ++d) c[d] = static_cast<int64_t>(std::floor((0.5 * (p[d] + q[d]) - origin_m_[d]) / cell_m_));
  for (int64_t x = c[0] - 1; x <= c[0] + 1; ++x)
    for (int64_t y = c[1] - 1; y <= c[1] + 1; ++y)
      for (int64_t z = c[2] - 1; z <= c[2] + 1; ++z) {
        const auto it = grid_.find(key(x, y, z));
        if (it == grid_.end()) continue;
        for (int32_t f : it->second)
          if (crosses_facet(static_cast<size_t>(f), p, q)) return true;
      }
  return false;
}

}  // namespace breccia::solver
