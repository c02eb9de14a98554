#include "surface_facets.hpp"

#include <cmath>

namespace breccia::solver {
namespace {

// The facets' vertices from their owner cells: the face (3D: 3 of a tet's 4 nodes; 2D: 2
// of a triangle's 3) whose vertex mean is the stored centroid. Empty when a facet is not a
// face of its owner.
std::vector<double> vertices_from_mesh(const ParticleModel& model, const SurfaceFacets& facets, std::string& why) {
  const int dimension = model.dimension;
  const int per_facet = dimension;
  const int npc = model.nodes_per_cell;
  const size_t nf = facets.size();
  std::vector<double> out(nf * per_facet * 3, 0.0);
  for (size_t f = 0; f < nf; ++f) {
    const int64_t* nodes = model.cell_nodes(facets.particle[f]);  // (npc of them)
    double best = 1e300;
    int skip_best = -1;
    for (int skip = 0; skip < npc; ++skip) {  // the face opposite node `skip`
      double mean[3] = {0, 0, 0};
      for (int v = 0; v < npc; ++v)
        if (v != skip)
          for (int d = 0; d < 3; ++d) mean[d] += model.node_position(nodes[v])[d] / per_facet;
      double d2 = 0;
      for (int d = 0; d < 3; ++d) d2 += std::pow(mean[d] - facets.centroid_m[3 * f + d], 2);
      if (d2 < best) {
        best = d2;
        skip_best = skip;
      }
    }
    // The stored centroid is the mean of the same vertices: round-off only.
    const double size = dimension == 3 ? std::sqrt(facets.area_m2[f]) : facets.area_m2[f] / model.thickness_m;
    if (skip_best < 0 || best > 1e-12 * size * size) {
      why = "facet " + std::to_string(f) + " is not a face of its owner cell in /mesh";
      return {};
    }
    int k = 0;
    for (int v = 0; v < npc; ++v)
      if (v != skip_best) {
        for (int d = 0; d < 3; ++d) out[(f * per_facet + k) * 3 + d] = model.node_position(nodes[v])[d];
        ++k;
      }
  }
  return out;
}

// Each facet as a square of its area (two triangles) or, in 2D, an edge of its length
// across its normal, centred on its centroid.
std::vector<double> vertices_as_squares(const ParticleModel& model, const SurfaceFacets& facets) {
  std::vector<double> out;
  for (size_t f = 0; f < facets.size(); ++f) {
    const double* n = &facets.normal[3 * f];
    const double* c = &facets.centroid_m[3 * f];
    auto corner = [&](const double* u, double a, const double* v, double b) {
      for (int d = 0; d < 3; ++d) out.push_back(c[d] + a * u[d] + b * v[d]);
    };
    if (model.dimension == 2) {
      const double t[3] = {-n[1], n[0], 0.0}, none[3] = {0, 0, 0};
      const double half = 0.5 * facets.area_m2[f] / model.thickness_m;
      corner(t, -half, none, 0);
      corner(t, half, none, 0);
      continue;
    }
    // In-plane axes from the coordinate axis least aligned with the normal (the first on a
    // tie): for an axis normal they are the other two axes.
    int e = 0;
    for (int d = 1; d < 3; ++d)
      if (std::fabs(n[d]) < std::fabs(n[e])) e = d;
    double u[3] = {0, 0, 0};
    u[e] = 1.0;
    const double un = u[0] * n[0] + u[1] * n[1] + u[2] * n[2];
    double len = 0;
    for (int d = 0; d < 3; ++d) u[d] -= un * n[d], len += u[d] * u[d];
    for (double& x : u) x /= std::sqrt(len);
    const double v[3] = {n[1] * u[2] - n[2] * u[1], n[2] * u[0] - n[0] * u[2], n[0] * u[1] - n[1] * u[0]};
    const double h = 0.5 * std::sqrt(facets.area_m2[f]);
    corner(u, -h, v, -h), corner(u, h, v, -h), corner(u, h, v, h);
    corner(u, -h, v, -h), corner(u, h, v, h), corner(u, -h, v, h);
  }
  return out;
}

}  // namespace

FacetVertices facet_vertices(const ParticleModel& model, const SurfaceFacets& facets) {
  FacetVertices out;
  if (facets.has_vertices()) {
    out.source = FacetVertices::Source::File;
    out.vertices_m = facets.vertices_m;
    return out;
  }
  if (model.nodes_per_cell == model.dimension + 1 && !model.mesh_cells.empty()) {
    out.vertices_m = vertices_from_mesh(model, facets, out.why_approximate);
    if (!out.vertices_m.empty()) {
      out.source = FacetVertices::Source::Mesh;
      return out;
    }
  } else {
    out.why_approximate = "the particle file has no facet vertices and no source mesh";
  }
  out.source = FacetVertices::Source::Squares;
  out.vertices_m = vertices_as_squares(model, facets);
  return out;
}

std::unique_ptr<FacetTree> surface_facet_tree(const ParticleModel& model, const SurfaceFacets& facets,
                                              std::string& note) {
  const FacetVertices v = facet_vertices(model, facets);
  // A lattice's facets are squares, so only other 3D models are approximated.
  const bool lattice = model.source.rfind("lattice", 0) == 0;
  if (v.source == FacetVertices::Source::Squares && model.dimension == 3 && !lattice)
    note = "surface '" + facets.name + "': each facet taken as a square of its area in its plane (" +
           v.why_approximate + ")";
  return std::make_unique<FacetTree>(model.dimension, v.vertices_m);
}

}  // namespace breccia::solver
