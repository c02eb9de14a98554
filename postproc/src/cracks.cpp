#include "breccia/postproc/cracks.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <unordered_map>

#include "breccia/common/cell_list.hpp"
#include "breccia/common/error.hpp"
#include "breccia/common/union_find.hpp"

namespace breccia::postproc {
namespace {

using Vec3 = std::array<double, 3>;

Vec3 point(std::span<const double> x, int64_t i) { return {x[3 * i], x[3 * i + 1], x[3 * i + 2]}; }
Vec3 sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double norm(const Vec3& a) { return std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); }

struct FaceKey {
  std::array<int64_t, 3> nodes;  // sorted; third = -1 for edges
  int32_t cell;
  int8_t local;
};

}  // namespace

CandidateFaces mesh_candidate_faces(const ParticleModel& m) {
  static constexpr int kTetFaces[4][3] = {{0, 1, 2}, {0, 1, 3}, {0, 2, 3}, {1, 2, 3}};
  static constexpr int kTriEdges[3][2] = {{0, 1}, {1, 2}, {2, 0}};
  const int npc = m.nodes_per_cell;
  if (npc != 4 && npc != 3)
    throw InputError(m.source, "/mesh/cells", "nodes_per_cell " + std::to_string(npc), "4 (tets) or 3 (triangles)");
  const size_t cells = m.mesh_cells.size() / npc;
  const int faces_per_cell = npc == 4 ? 4 : 3;
  const int vpf = npc == 4 ? 3 : 2;
  std::vector<FaceKey> keys;
  keys.reserve(cells * faces_per_cell);
  for (size_t c = 0; c < cells; ++c) {
    const int64_t* cn = &m.mesh_cells[c * npc];
    for (int f = 0; f < faces_per_cell; ++f) {
      FaceKey k{{-1, -1, -1}, static_cast<int32_t>(c), static_cast<int8_t>(f)};
      for (int v = 0; v < vpf; ++v) k.nodes[v] = cn[npc == 4 ? kTetFaces[f][v] : kTriEdges[f][v]];
      std::sort(k.nodes.begin(), k.nodes.begin() + vpf);
      keys.push_back(k);
    }
  }
  std::sort(keys.begin(), keys.end(), [](const FaceKey& a, const FaceKey& b) {
    return a.nodes != b.nodes ? a.nodes < b.nodes : a.cell < b.cell;
  });
  CandidateFaces out;
  out.dimension = npc == 4 ? 3 : 2;
  out.vertices_per_face = vpf;
  out.points_m = m.mesh_nodes_m;
  const std::span<const double> x(m.mesh_nodes_m);
  for (size_t k = 0; k + 1 < keys.size(); ++k) {
    if (keys[k].nodes != keys[k + 1].nodes) continue;
    const FaceKey& a = keys[k];
    const int64_t* cn = &m.mesh_cells[static_cast<size_t>(a.cell) * npc];
    std::array<int64_t, 3> v{};
    for (int i = 0; i < vpf; ++i) v[i] = cn[npc == 4 ? kTetFaces[a.local][i] : kTriEdges[a.local][i]];
    for (int i = 0; i < vpf; ++i) out.vertices.push_back(v[i]);
    out.particle_a.push_back(std::min(a.cell, keys[k + 1].cell));
    out.particle_b.push_back(std::max(a.cell, keys[k + 1].cell));
    if (vpf == 3) {
      out.area_m2.push_back(0.5 * norm(cross(sub(point(x, v[1]), point(x, v[0])), sub(point(x, v[2]), point(x, v[0])))));
      out.length_m.push_back(0.0);
    } else {
      const double len = norm(sub(point(x, v[1]), point(x, v[0])));
      out.length_m.push_back(len);
      out.area_m2.push_back(len * m.thickness_m);
    }
    ++k;  // a face is shared by at most two cells in a conforming mesh
  }
  return out;
}

CandidateFaces lattice_candidate_faces(const ParticleModel& m, const Families& fam) {
  CandidateFaces out;
  out.dimension = m.dimension;
  out.vertices_per_face = m.dimension == 3 ? 4 : 2;
  const std::span<const double> x(m.position_m);
  double min_spacing = 1e300;
  for (double s : m.spacing_m) min_spacing = std::min(min_spacing, s);
  // Corners of neighbouring faces coincide up to rounding: weld them on a grid far finer
  // than the spacing so that crack faces share vertices (needed for crack counting).
  const double q = 1e-4 * min_spacing;
  struct KeyHash {
    size_t operator()(const std::array<int64_t, 3>& k) const {
      return static_cast<size_t>(k[0] * 73856093LL ^ k[1] * 19349663LL ^ k[2] * 83492791LL);
    }
  };
  std::unordered_map<std::array<int64_t, 3>, int64_t, KeyHash> weld;
  auto vertex = [&](const Vec3& p) {
    const std::array<int64_t, 3> key{std::llround(p[0] / q), std::llround(p[1] / q), std::llround(p[2] / q)};
    auto [it, inserted] = weld.try_emplace(key, static_cast<int64_t>(out.points_m.size() / 3));
    if (inserted) out.points_m.insert(out.points_m.end(), p.begin(), p.end());
    return it->second;
  };
  const size_t n = m.size();
  for (size_t i = 0; i < n; ++i) {
    for (int64_t k = fam.offsets[i]; k < fam.offsets[i + 1]; ++k) {
      const int32_t j = fam.neighbors[k];
      if (j <= static_cast<int32_t>(i)) continue;
      const double s = 0.5 * (m.spacing_m[i] + m.spacing_m[j]);
      const Vec3 xi = sub(point(x, j), point(x, i));
      const double r = norm(xi);
      if (std::abs(r - s) > 0.01 * s) continue;  // face neighbours only (lattice spacing)
      const Vec3 nrm{xi[0] / r, xi[1] / r, xi[2] / r};
      const Vec3 mid{0.5 * (x[3 * i] + x[3 * j]), 0.5 * (x[3 * i + 1] + x[3 * j + 1]),
                     0.5 * (x[3 * i + 2] + x[3 * j + 2])};
      out.particle_a.push_back(static_cast<int32_t>(i));
      out.particle_b.push_back(j);
      const double h = 0.5 * s;
      if (m.dimension == 2) {
        const Vec3 t{-nrm[1], nrm[0], 0.0};
        out.vertices.push_back(vertex({mid[0] - h * t[0], mid[1] - h * t[1], mid[2]}));
        out.vertices.push_back(vertex({mid[0] + h * t[0], mid[1] + h * t[1], mid[2]}));
        out.length_m.push_back(s);
        out.area_m2.push_back(s * m.thickness_m);
        continue;
      }
      // In-plane axes: cross with the coordinate axis least aligned with the normal.
      int least = 0;
      for (int d = 1; d < 3; ++d)
        if (std::abs(nrm[d]) < std::abs(nrm[least])) least = d;
      Vec3 axis{0, 0, 0};
      axis[least] = 1.0;
      Vec3 e1 = cross(nrm, axis);
      const double l1 = norm(e1);
      e1 = {e1[0] / l1, e1[1] / l1, e1[2] / l1};
      const Vec3 e2 = cross(nrm, e1);
      const double signs[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
      for (const auto& sg : signs)
        out.vertices.push_back(vertex({mid[0] + h * (sg[0] * e1[0] + sg[1] * e2[0]),
                                       mid[1] + h * (sg[0] * e1[1] + sg[1] * e2[1]),
                                       mid[2] + h * (sg[0] * e1[2] + sg[1] * e2[2])}));
      out.length_m.push_back(0.0);
      out.area_m2.push_back(s * s);
    }
  }
  return out;
}

CandidateFaces candidate_faces(const ParticleModel& m, const Families& fam) {
  return m.nodes_per_cell > 0 ? mesh_candidate_faces(m) : lattice_candidate_faces(m, fam);
}

namespace {

// Local crack plane per crack face from the principal axes of the centroids of the faces of
// the same crack (crack_id: faces joined through shared vertices) within a radius (3D:
// normal = least-variance axis; 2D: normal = in-plane perpendicular of the largest-variance
// axis), then area x |n_face . n_plane|. Only faces with weight[f] > 0 take part (as faces and
// as neighbours); each counts weight[f] x its projected area. Two parallel cracks a few
// spacings apart would otherwise share a neighbourhood, and the fit across both would turn
// the plane through the gap between them and project every face to nothing.
struct Smoothed {
  double area_m2 = 0.0, fracture_area_m2 = 0.0, G0_fracture_area_J = 0.0, length_m = 0.0, radius_m = 0.0;
};

Smoothed smooth_areas(const CandidateFaces& faces, const CrackInputs& in, const CrackResult& r,
                      const std::vector<double>& weight) {
  // Cell moments are kept per (cell, crack): a block's fit sees one crack's faces only.
  struct CellCrack {
    long long cell;
    int32_t crack;
    bool operator==(const CellCrack&) const = default;
  };
  struct CellCrackHash {
    size_t operator()(const CellCrack& k) const {
      return std::hash<long long>()(k.cell) ^ (std::hash<int32_t>()(k.crack) * 0x9e3779b97f4a7c15ULL);
    }
  };
  Smoothed out;
  const int vpf = faces.vertices_per_face;
  const bool planar = faces.dimension == 2;
  std::vector<size_t> crack;
  double size_sum = 0;
  for (size_t f = 0; f < faces.size(); ++f)
    if (weight[f] > 0) {
      crack.push_back(f);
      size_sum += planar ? faces.length_m[f] : std::sqrt(faces.area_m2[f]);
    }
  if (crack.empty()) return out;
  // A few face sizes: wide enough to average the staircase, narrow against curvature.
  const double radius = 4.0 * size_sum / crack.size();
  out.radius_m = radius;
  const size_t nc = crack.size();
  std::vector<Eigen::Vector3d> centroid(nc), normal(nc);
  for (size_t k = 0; k < nc; ++k) {
    const size_t f = crack[k];
    Eigen::Vector3d p[4];
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int v = 0; v < vpf; ++v) {
      const int64_t id = faces.vertices[f * vpf + v];
      p[v] = Eigen::Vector3d(faces.points_m[3 * id], faces.points_m[3 * id + 1], faces.points_m[3 * id + 2]);
      c += p[v] / vpf;
    }
    centroid[k] = c;
    Eigen::Vector3d n;
    if (vpf == 2) n = Eigen::Vector3d(-(p[1] - p[0]).y(), (p[1] - p[0]).x(), 0.0);
    else if (vpf == 3) n = (p[1] - p[0]).cross(p[2] - p[0]);
    else n = (p[2] - p[0]).cross(p[3] - p[1]);
    normal[k] = n.normalized();
  }
  // The neighbourhood is a block of 3 x 3 x 3 grid cells of side 2/3 radius (a cube of side
  // 2 radius around the face's cell) rather than a sphere: the centroid moments are summed
  // once per cell and once per block, so the fit costs O(faces + cells) instead of
  // O(faces x neighbours). A pulverised 290k-particle run has ~10^6 crack faces with
  // hundreds of neighbours each, which took a minute per output with the sphere search.
  const double cell = 2.0 * radius / 3.0;
  Eigen::Vector3d lo = centroid[0], hi = centroid[0];
  for (const auto& c : centroid) {
    lo = lo.cwiseMin(c);
    hi = hi.cwiseMax(c);
  }
  // The cell list's grid (common/cell_list.hpp) over the centroids; only occupied cells are
  // kept (in maps), so its members are not sorted.
  const CellGrid grid = CellGrid::covering({{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}}, cell);
  const long long* dims = grid.count;
  struct Moments {
    double w = 0.0;
    Eigen::Vector3d first = Eigen::Vector3d::Zero();
    Eigen::Matrix3d second = Eigen::Matrix3d::Zero();
  };
  std::unordered_map<CellCrack, Moments, CellCrackHash> cell_moments;
  std::vector<CellCrack> face_cell(nc);
  for (size_t k = 0; k < nc; ++k) {
    face_cell[k] = {grid.index_of(centroid[k].data()), r.crack_id[crack[k]]};
    Moments& m = cell_moments[face_cell[k]];
    const double w = weight[crack[k]] * faces.area_m2[crack[k]];
    m.w += w;
    m.first += w * centroid[k];
    m.second += w * centroid[k] * centroid[k].transpose();
  }
  // One plane per occupied cell, fitted to the moments of its 27-cell block.
  struct Plane {
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();
    bool defined = false;
  };
  std::unordered_map<CellCrack, Plane, CellCrackHash> cell_plane;
  cell_plane.reserve(cell_moments.size());
  for (const auto& [key, own] : cell_moments) {
    const long long cx = key.cell % dims[0], cy = (key.cell / dims[0]) % dims[1], cz = key.cell / (dims[0] * dims[1]);
    Moments block;
    for (long long z = std::max(0LL, cz - 1); z <= std::min(dims[2] - 1, cz + 1); ++z)
      for (long long y = std::max(0LL, cy - 1); y <= std::min(dims[1] - 1, cy + 1); ++y)
        for (long long x = std::max(0LL, cx - 1); x <= std::min(dims[0] - 1, cx + 1); ++x) {
          const auto it = cell_moments.find({grid.index(x, y, z), key.crack});
          if (it == cell_moments.end()) continue;
          block.w += it->second.w;
          block.first += it->second.first;
          block.second += it->second.second;
        }
    Plane plane;
    if (block.w > 0) {
      const Eigen::Vector3d mean = block.first / block.w;
      const Eigen::Matrix3d cov = block.second / block.w - mean * mean.transpose();
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
      if (planar) {
        const Eigen::Vector3d t = es.eigenvectors().col(2);
        plane.normal = Eigen::Vector3d(-t.y(), t.x(), 0.0);
      } else {
        plane.normal = es.eigenvectors().col(0);
      }
      // Too few neighbours, or no dominant plane (a junction, a blob): keep the face area.
      const Eigen::Vector3d ev = es.eigenvalues();
      // 2D: the centroids lie in the plane z = const, so ev[0] is ~0 and the line must dominate
      // the across-crack spread, ev[1]; 3D: the plane must dominate its normal's spread.
      plane.defined = plane.normal.norm() > 0.5 && (planar ? ev[2] > 4.0 * std::max(ev[1], 0.0)
                                                           : ev[1] > 4.0 * std::max(ev[0], 0.0));
      if (plane.defined) plane.normal.normalize();
    }
    cell_plane.emplace(key, plane);
  }
  for (size_t k = 0; k < nc; ++k) {
    const Plane& plane = cell_plane.at(face_cell[k]);
    const bool defined = plane.defined;
    const Eigen::Vector3d plane_normal = plane.normal;
    const size_t f = crack[k];
    const double factor = weight[f] * (defined ? std::abs(normal[k].dot(plane_normal)) : 1.0);
    out.area_m2 += factor * faces.area_m2[f];
    if (r.state[f] == kFractured) {
      out.fracture_area_m2 += factor * faces.area_m2[f];
      auto g0 = [&](int32_t p) {
        return in.fracture_energy_J_m2.empty() || in.material_id.empty() ? 0.0 : in.fracture_energy_J_m2[in.material_id[p]];
      };
      out.G0_fracture_area_J += factor * faces.area_m2[f] * 0.5 * (g0(faces.particle_a[f]) + g0(faces.particle_b[f]));
    }
  }
  if (planar && faces.area_m2[crack[0]] > 0)
    out.length_m = out.area_m2 * faces.length_m[crack[0]] / faces.area_m2[crack[0]];
  return out;
}

}  // namespace

CrackResult find_cracks(const CandidateFaces& faces, const CrackInputs& in, CrackCriterion criterion,
                        double damage_threshold) {
  const size_t nf = faces.size();
  CrackResult r;
  r.state.assign(nf, kIntact);
  r.crack_id.assign(nf, -1);
  auto g0 = [&](int32_t p) {
    if (in.fracture_energy_J_m2.empty() || in.material_id.empty()) return 0.0;
    return in.fracture_energy_J_m2[in.material_id[p]];
  };
  for (size_t f = 0; f < nf; ++f) {
    const int32_t a = faces.particle_a[f], b = faces.particle_b[f];
    if (in.precracks && in.precracks->contains(a, b)) {
      r.state[f] = kPrecrack;
    } else if (criterion == CrackCriterion::Bond) {
      if (in.broken && in.broken->contains_face(f, a, b)) r.state[f] = kFractured;
    } else if (in.damage[a] > damage_threshold && in.damage[b] > damage_threshold) {
      r.state[f] = kFractured;
    }
    if (r.state[f] == kIntact) continue;
    ++r.face_count;
    r.area_m2 += faces.area_m2[f];
    r.length_m += faces.length_m[f];
    if (r.state[f] == kPrecrack) {
      r.precrack_area_m2 += faces.area_m2[f];
    } else {
      r.fracture_area_m2 += faces.area_m2[f];
      r.fracture_length_m += faces.length_m[f];
      r.G0_area_J += faces.area_m2[f] * 0.5 * (g0(a) + g0(b));
    }
  }
  // Cracks: crack faces connected through shared vertices (edge or node).
  const int vpf = faces.vertices_per_face;
  UnionFind uf(nf);
  std::vector<int32_t> first_face(faces.points_m.size() / 3, -1);
  for (size_t f = 0; f < nf; ++f) {
    if (r.state[f] == kIntact) continue;
    for (int v = 0; v < vpf; ++v) {
      int32_t& first = first_face[faces.vertices[f * vpf + v]];
      if (first < 0) first = static_cast<int32_t>(f);
      else uf.unite(first, static_cast<int32_t>(f));
    }
  }
  std::vector<int32_t> id_of_root(nf, -1);
  for (size_t f = 0; f < nf; ++f) {
    if (r.state[f] == kIntact) continue;
    const int32_t root = uf.find(static_cast<int32_t>(f));
    if (id_of_root[root] < 0) id_of_root[root] = r.crack_count++;
    r.crack_id[f] = id_of_root[root];
  }
  std::vector<double> weight(nf, 0.0);
  for (size_t f = 0; f < nf; ++f) weight[f] = r.state[f] != kIntact ? 1.0 : 0.0;
  const Smoothed all = smooth_areas(faces, in, r, weight);
  r.smoothed_area_m2 = all.area_m2;
  r.smoothed_fracture_area_m2 = all.fracture_area_m2;
  r.G0_smoothed_area_J = all.G0_fracture_area_J;
  r.smoothed_length_m = all.length_m;
  r.smoothing_radius_m = all.radius_m;
  if (!in.fragment_of.empty()) {
    r.has_separating = true;
    std::vector<int64_t> fragment_size;
    for (int32_t label : in.fragment_of) {
      if (static_cast<size_t>(label) >= fragment_size.size()) fragment_size.resize(static_cast<size_t>(label) + 1, 0);
      ++fragment_size[static_cast<size_t>(label)];
    }
    for (size_t f = 0; f < nf; ++f) {
      const int32_t la = in.fragment_of[faces.particle_a[f]], lb = in.fragment_of[faces.particle_b[f]];
      weight[f] = 0.0;
      if (r.state[f] != kFractured || la == lb) continue;
      // A debris chip lying in the crack has crack faces on both sides, but the crack runs
      // once through where it sits: its faces count half.
      const bool debris = std::min(fragment_size[la], fragment_size[lb]) < in.debris_particles;
      weight[f] = debris ? 0.5 : 1.0;
      ++r.separating_face_count;
      r.separating_fracture_area_m2 += weight[f] * faces.area_m2[f];
    }
    const Smoothed sep = smooth_areas(faces, in, r, weight);
    r.smoothed_separating_fracture_area_m2 = sep.fracture_area_m2;
    r.G0_smoothed_separating_area_J = sep.G0_fracture_area_J;
  }
  return r;
}

}  // namespace breccia::postproc
