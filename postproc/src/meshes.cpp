#include "breccia/postproc/meshes.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <optional>

namespace breccia::postproc {
namespace {

constexpr int kVtkVertex = 1, kVtkLine = 3, kVtkTriangle = 5, kVtkQuad = 9, kVtkTetra = 10, kVtkHexahedron = 12;

// node -> incident cells (CSR).
struct NodeCells {
  std::vector<int64_t> offsets;
  std::vector<int32_t> cells;
};

NodeCells node_cells(const ParticleModel& m) {
  const size_t nodes = m.mesh_nodes_m.size() / 3;
  NodeCells nc;
  nc.offsets.assign(nodes + 1, 0);
  for (int64_t v : m.mesh_cells) ++nc.offsets[v + 1];
  for (size_t i = 0; i < nodes; ++i) nc.offsets[i + 1] += nc.offsets[i];
  nc.cells.resize(m.mesh_cells.size());
  std::vector<int64_t> fill(nc.offsets.begin(), nc.offsets.end() - 1);
  const int npc = m.nodes_per_cell;
  for (size_t k = 0; k < m.mesh_cells.size(); ++k) nc.cells[fill[m.mesh_cells[k]]++] = static_cast<int32_t>(k / npc);
  return nc;
}

// Weighted least-squares affine fit of u at `node_x` from (x_c, u_c, w_c), d spatial
// dimensions; the constant term is u(node_x). Empty when the cells do not determine an
// affine field (fewer than d + 1, or all on one plane/line).
template <int D>
std::optional<Eigen::Vector3d> affine_fit(const std::vector<int32_t>& cells, std::span<const double> x,
                                          std::span<const double> u, std::span<const double> w,
                                          const Eigen::Vector3d& node_x) {
  if (static_cast<int>(cells.size()) < D + 1) return std::nullopt;
  double wsum = 0, h2 = 0;
  for (int32_t c : cells) {
    wsum += w[c];
    for (int d = 0; d < D; ++d) h2 += w[c] * (x[3 * c + d] - node_x[d]) * (x[3 * c + d] - node_x[d]);
  }
  if (!(h2 > 0)) return std::nullopt;
  const double h = std::sqrt(h2 / wsum);  // offsets scaled to O(1): a well-conditioned system
  using Mat = Eigen::Matrix<double, D + 1, D + 1>;
  using Rhs = Eigen::Matrix<double, D + 1, 3>;
  Mat a = Mat::Zero();
  Rhs b = Rhs::Zero();
  for (int32_t c : cells) {
    Eigen::Matrix<double, D + 1, 1> phi;
    phi[0] = 1.0;
    for (int d = 0; d < D; ++d) phi[d + 1] = (x[3 * c + d] - node_x[d]) / h;
    a += (w[c] / wsum) * phi * phi.transpose();
    b += (w[c] / wsum) * phi * Eigen::RowVector3d(u[3 * c], u[3 * c + 1], u[3 * c + 2]);
  }
  Eigen::LDLT<Mat> ldlt(a);
  if (ldlt.info() != Eigen::Success || ldlt.rcond() < 1e-8) return std::nullopt;
  const Eigen::Vector3d u0 = ldlt.solve(b).row(0).transpose();
  if (!u0.allFinite()) return std::nullopt;
  return u0;
}

Eigen::Vector3d weighted_mean(const std::vector<int32_t>& cells, std::span<const double> u, std::span<const double> w) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  double wsum = 0;
  for (int32_t c : cells) {
    mean += w[c] * Eigen::Vector3d(u[3 * c], u[3 * c + 1], u[3 * c + 2]);
    wsum += w[c];
  }
  return mean / wsum;
}

Mesh lattice_blocks(const ParticleModel& m, std::span<const double> u) {
  Mesh out;
  const bool three_d = m.dimension == 3;
  out.vtk_cell_type = three_d ? kVtkHexahedron : kVtkQuad;
  out.nodes_per_cell = three_d ? 8 : 4;
  static constexpr double kCorner[8][3] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                                           {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};
  // Each block's corners move with its particle: their point data is the particle's
  // displacement (a mesh's deformed.vtu carries the nodes'; blocks share no node, so there
  // is no source_node).
  std::vector<double> displacement;
  for (size_t i = 0; i < m.size(); ++i) {
    const double h = 0.5 * m.spacing_m[i];
    for (int c = 0; c < out.nodes_per_cell; ++c) {
      out.cells.push_back(static_cast<int64_t>(out.points_m.size() / 3));
      for (int d = 0; d < 3; ++d) {
        const double offset = (d < 2 || three_d) ? kCorner[c][d] * h : 0.0;
        const double ud = u.empty() ? 0.0 : u[3 * i + d];
        out.points_m.push_back(m.position_m[3 * i + d] + offset + ud);
        displacement.push_back(ud);
      }
    }
  }
  if (!u.empty()) out.point_data.push_back({"displacement", 3, std::move(displacement), false});
  return out;
}

}  // namespace

std::vector<double> cell_to_node_average(const ParticleModel& m, std::span<const double> cell_value) {
  const size_t nodes = m.mesh_nodes_m.size() / 3;
  std::vector<double> num(nodes, 0.0), den(nodes, 0.0);
  const int npc = m.nodes_per_cell;
  for (size_t c = 0; c < m.size(); ++c)
    for (int k = 0; k < npc; ++k) {
      const int64_t v = m.mesh_cells[c * npc + k];
      num[v] += m.volume_m3[c] * cell_value[c];
      den[v] += m.volume_m3[c];
    }
  for (size_t v = 0; v < nodes; ++v) num[v] = den[v] > 0 ? num[v] / den[v] : 0.0;
  return num;
}

Mesh source_mesh(const ParticleModel& m) {
  Mesh out;
  if (m.nodes_per_cell == 0) {
    out.points_m = m.position_m;
    out.vtk_cell_type = kVtkVertex;
    out.nodes_per_cell = 1;
    out.cells.resize(m.size());
    for (size_t i = 0; i < m.size(); ++i) out.cells[i] = static_cast<int64_t>(i);
    return out;
  }
  out.points_m = m.mesh_nodes_m;
  out.cells = m.mesh_cells;
  out.nodes_per_cell = m.nodes_per_cell;
  out.vtk_cell_type = m.nodes_per_cell == 4 ? kVtkTetra : kVtkTriangle;
  return out;
}

Mesh deformed_mesh(const ParticleModel& m, std::span<const double> u, std::span<const int32_t> component) {
  if (m.nodes_per_cell == 0) return lattice_blocks(m, u);
  const NodeCells nc = node_cells(m);
  const size_t nodes = m.mesh_nodes_m.size() / 3;
  const int npc = m.nodes_per_cell;
  Mesh out;
  out.nodes_per_cell = npc;
  out.vtk_cell_type = npc == 4 ? kVtkTetra : kVtkTriangle;
  std::vector<int32_t> origin_node;
  // Copies of node v: (component, new point id) in copy_offsets[v] .. copy_offsets[v+1].
  std::vector<int64_t> copy_offsets(nodes + 1, 0);
  std::vector<std::pair<int32_t, int64_t>> copies;
  std::vector<int32_t> group, wide;
  std::vector<double> point_displacement;
  auto fit = [&](const std::vector<int32_t>& cells, const Eigen::Vector3d& xv) {
    return m.dimension == 3 ? affine_fit<3>(cells, m.position_m, u, m.volume_m3, xv)
                            : affine_fit<2>(cells, m.position_m, u, m.volume_m3, xv);
  };
  // A fragment of fewer than d + 1 cells can never determine an affine field, not even
  // widened (widening stays inside the fragment): it takes the weighted mean at once. In a
  // crushed block most fragments are single cells and each of their nodes would otherwise
  // try two fits (a sixth of the post-processing time of the full concrete case).
  std::vector<int32_t> component_cells;
  for (size_t c = 0; c < m.size(); ++c) {
    if (component[c] >= static_cast<int32_t>(component_cells.size())) component_cells.resize(component[c] + 1, 0);
    ++component_cells[component[c]];
  }
  std::vector<int32_t> inc;
  for (size_t v = 0; v < nodes; ++v) {
    inc.assign(nc.cells.begin() + nc.offsets[v], nc.cells.begin() + nc.offsets[v + 1]);
    std::sort(inc.begin(), inc.end(), [&](int32_t a, int32_t b) { return component[a] < component[b]; });
    const Eigen::Vector3d xv(m.mesh_nodes_m[3 * v], m.mesh_nodes_m[3 * v + 1], m.mesh_nodes_m[3 * v + 2]);
    for (size_t k = 0; k < inc.size();) {
      size_t e = k;
      while (e < inc.size() && component[inc[e]] == component[inc[k]]) ++e;
      group.assign(inc.begin() + k, inc.begin() + e);
      const bool fittable = component_cells[component[inc[k]]] > m.dimension;
      std::optional<Eigen::Vector3d> uv = fittable ? fit(group, xv) : std::nullopt;
      if (!uv && fittable) {
        // Degenerate stencil (a block corner: its cells' centroids can be coplanar): widen
        // to the cells around the group's nodes, same component.
        wide.clear();
        for (int32_t c : group)
          for (int q = 0; q < npc; ++q) {
            const int64_t w = m.mesh_cells[static_cast<size_t>(c) * npc + q];
            for (int64_t r = nc.offsets[w]; r < nc.offsets[w + 1]; ++r)
              if (component[nc.cells[r]] == component[c]) wide.push_back(nc.cells[r]);
          }
        std::sort(wide.begin(), wide.end());
        wide.erase(std::unique(wide.begin(), wide.end()), wide.end());
        uv = fit(wide, xv);
      }
      if (!uv) uv = weighted_mean(group, u, m.volume_m3);
      const int64_t id = static_cast<int64_t>(out.points_m.size() / 3);
      copies.emplace_back(component[inc[k]], id);
      for (int d = 0; d < 3; ++d) {
        out.points_m.push_back(xv[d] + (*uv)[d]);
        point_displacement.push_back((*uv)[d]);
      }
      origin_node.push_back(static_cast<int32_t>(v));
      k = e;
    }
    copy_offsets[v + 1] = static_cast<int64_t>(copies.size());
  }
  out.cells.resize(m.mesh_cells.size());
  for (size_t c = 0; c < m.size(); ++c)
    for (int k = 0; k < npc; ++k) {
      const int64_t v = m.mesh_cells[c * npc + k];
      for (int64_t q = copy_offsets[v]; q < copy_offsets[v + 1]; ++q)
        if (copies[q].first == component[c]) {
          out.cells[c * npc + k] = copies[q].second;
          break;
        }
    }
  out.point_data.push_back({"displacement", 3, std::move(point_displacement), false});
  out.point_data.push_back({"source_node", 1, std::vector<double>(origin_node.begin(), origin_node.end()), true});
  return out;
}

Mesh crack_mesh(const CandidateFaces& faces, const CrackResult& cracks) {
  Mesh out;
  const int vpf = faces.vertices_per_face;
  out.nodes_per_cell = vpf;
  out.vtk_cell_type = vpf == 2 ? kVtkLine : (vpf == 3 ? kVtkTriangle : kVtkQuad);
  std::vector<int64_t> new_id(faces.points_m.size() / 3, -1);
  Field state{"state", 1, {}, true}, crack_id{"crack_id", 1, {}, true}, area{"area_m2", 1, {}, false};
  Field pa{"particle_a", 1, {}, true}, pb{"particle_b", 1, {}, true};
  for (size_t f = 0; f < faces.size(); ++f) {
    if (cracks.state[f] == kIntact) continue;
    for (int k = 0; k < vpf; ++k) {
      const int64_t v = faces.vertices[f * vpf + k];
      if (new_id[v] < 0) {
        new_id[v] = static_cast<int64_t>(out.points_m.size() / 3);
        for (int d = 0; d < 3; ++d) out.points_m.push_back(faces.points_m[3 * v + d]);
      }
      out.cells.push_back(new_id[v]);
    }
    state.values.push_back(cracks.state[f]);
    crack_id.values.push_back(cracks.crack_id[f]);
    area.values.push_back(faces.area_m2[f]);
    pa.values.push_back(faces.particle_a[f]);
    pb.values.push_back(faces.particle_b[f]);
  }
  out.cell_data = {state, crack_id, area, pa, pb};
  return out;
}

}  // namespace breccia::postproc
