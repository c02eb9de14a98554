#pragma once
// Synthetic run directories for post-processing tests: structured tet/triangle meshes or
// lattices with known geometry, written as particles.h5 + results.h5 following the
// results contract (docs/postproc.md, "Inputs").
#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "breccia/common/families.hpp"
#include "breccia/common/h5.hpp"
#include "breccia/common/particle_file.hpp"

namespace breccia::postproc::testing {

// Box of n[0] x n[1] (x n[2]) cells of edge h at `origin`, each hex split into the six
// Kuhn tetrahedra (conforming, volume h^3/6 each), or in 2D each square into two triangles.
inline ParticleModel structured_mesh(int dim, std::array<int, 3> n, double h, std::array<double, 3> origin = {0, 0, 0},
                                     double thickness_m = 1.0) {
  ParticleModel m;
  m.dimension = dim;
  m.thickness_m = dim == 2 ? thickness_m : 1.0;
  const int nz = dim == 3 ? n[2] : 0;
  auto node = [&](int i, int j, int k) { return static_cast<int64_t>((k * (n[1] + 1) + j) * (n[0] + 1) + i); };
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= n[1]; ++j)
      for (int i = 0; i <= n[0]; ++i) {
        m.mesh_nodes_m.push_back(origin[0] + i * h);
        m.mesh_nodes_m.push_back(origin[1] + j * h);
        m.mesh_nodes_m.push_back(dim == 3 ? origin[2] + k * h : 0.0);
      }
  auto add_cell = [&](const std::vector<int64_t>& cell) {
    double c[3] = {0, 0, 0};
    for (auto v : cell)
      for (int d = 0; d < 3; ++d) c[d] += m.mesh_nodes_m[3 * v + d] / cell.size();
    for (int d = 0; d < 3; ++d) m.position_m.push_back(c[d]);
    m.mesh_cells.insert(m.mesh_cells.end(), cell.begin(), cell.end());
    m.volume_m3.push_back(dim == 3 ? h * h * h / 6.0 : h * h / 2.0 * m.thickness_m);
    m.material_id.push_back(0);
  };
  static constexpr int kPerm[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int k = 0; k < std::max(nz, 1); ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i) {
        if (dim == 2) {
          add_cell({node(i, j, 0), node(i + 1, j, 0), node(i + 1, j + 1, 0)});
          add_cell({node(i, j, 0), node(i + 1, j + 1, 0), node(i, j + 1, 0)});
          continue;
        }
        for (const auto& p : kPerm) {
          int at[3] = {i, j, k};
          std::vector<int64_t> cell{node(at[0], at[1], at[2])};
          for (int s = 0; s < 3; ++s) {
            ++at[p[s]];
            cell.push_back(node(at[0], at[1], at[2]));
          }
          add_cell(cell);
        }
      }
  m.nodes_per_cell = dim == 3 ? 4 : 3;
  m.source = "structured test mesh";
  return m;
}

// Simple cubic (square) lattice: no mesh, particle spacing h.
inline ParticleModel lattice(int dim, std::array<int, 3> n, double h, double thickness_m = 1.0) {
  ParticleModel m;
  m.dimension = dim;
  m.thickness_m = dim == 2 ? thickness_m : 1.0;
  for (int k = 0; k < (dim == 3 ? n[2] : 1); ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i) {
        m.position_m.insert(m.position_m.end(), {(i + 0.5) * h, (j + 0.5) * h, dim == 3 ? (k + 0.5) * h : 0.0});
        m.volume_m3.push_back(dim == 3 ? h * h * h : h * h * m.thickness_m);
        m.spacing_m.push_back(h);
        m.material_id.push_back(0);
      }
  m.source = "lattice test";
  return m;
}

// Concatenate meshes (separate bodies in one model).
inline ParticleModel merge(const std::vector<ParticleModel>& parts) {
  ParticleModel m = parts.front();
  for (size_t p = 1; p < parts.size(); ++p) {
    const int64_t offset = static_cast<int64_t>(m.mesh_nodes_m.size() / 3);
    for (auto v : parts[p].mesh_cells) m.mesh_cells.push_back(v + offset);
    m.mesh_nodes_m.insert(m.mesh_nodes_m.end(), parts[p].mesh_nodes_m.begin(), parts[p].mesh_nodes_m.end());
    m.position_m.insert(m.position_m.end(), parts[p].position_m.begin(), parts[p].position_m.end());
    m.volume_m3.insert(m.volume_m3.end(), parts[p].volume_m3.begin(), parts[p].volume_m3.end());
    m.material_id.insert(m.material_id.end(), parts[p].material_id.begin(), parts[p].material_id.end());
    m.spacing_m.insert(m.spacing_m.end(), parts[p].spacing_m.begin(), parts[p].spacing_m.end());
  }
  return m;
}

// Every family bond (i < j) for which cut(x_i, x_j) holds.
inline std::vector<int64_t> bonds_where(const ParticleModel& m, double horizon_m,
                                        const std::function<bool(const double*, const double*)>& cut) {
  const std::vector<double> horizon(m.size(), horizon_m);
  const auto fam = build_families(m.position_m, horizon);
  std::vector<int64_t> out;
  for (size_t i = 0; i < m.size(); ++i)
    for (int64_t k = fam.offsets[i]; k < fam.offsets[i + 1]; ++k) {
      const int64_t j = fam.neighbors[k];
      if (j > static_cast<int64_t>(i) && cut(&m.position_m[3 * i], &m.position_m[3 * j])) {
        out.push_back(static_cast<int64_t>(i));
        out.push_back(j);
      }
    }
  return out;
}

struct SyntheticOutput {
  long long step = 0;
  double time_s = 0.0;
  std::vector<double> displacement_m, velocity_m_s, damage;  // empty = zeros
  std::vector<int64_t> broken_bonds;
};

struct SyntheticRun {
  std::filesystem::path dir;
  ParticleModel model;
  double horizon_m = 0.0;
  double density_kg_m3 = 2500.0;
  std::vector<double> fracture_energy_J_m2{100.0};
  std::vector<int64_t> precrack_bonds;
  std::vector<SyntheticOutput> outputs;
  std::string particles_file = "particles.h5";   // as quoted in results.h5
  std::string content_id_override;                // provenance mismatch tests
  std::string model_name = "pmb";
};

inline void write_run(const SyntheticRun& run) {
  std::filesystem::create_directories(run.dir);
  const std::filesystem::path pf = run.dir / "particles.h5";
  write_particle_file(pf.string(), run.model);
  const ParticleModel written = read_particle_file(pf.string());
  const size_t n = written.size();
  h5::File f((run.dir / "results.h5").string(), h5::File::Mode::Create);
  f.set_attr("/", "format", std::string("breccia-results"));
  f.set_attr("/", "format_version", 2LL);
  f.set_attr("/", "particles_file", run.particles_file);
  f.set_attr("/", "particles_content_id", run.content_id_override.empty() ? written.content_id : run.content_id_override);
  f.set_attr("/", "dimension", static_cast<long long>(written.dimension));
  f.set_attr("/", "thickness_m", written.thickness_m);
  f.set_attr("/", "model", run.model_name);
  f.write("/particles/position", written.position_m, {n, 3});
  f.write("/particles/volume", written.volume_m3, {n});
  f.write("/particles/density", std::vector<double>(n, run.density_kg_m3), {n});
  f.write("/particles/horizon", std::vector<double>(n, run.horizon_m), {n});
  f.write("/particles/material_id", written.material_id, {n});
  f.write_strings("/materials/names", written.material_names);
  f.write("/materials/fracture_energy", run.fracture_energy_J_m2, {run.fracture_energy_J_m2.size()});
  f.write("/precrack_bonds", run.precrack_bonds, {run.precrack_bonds.size() / 2, 2});
  // The bond list as breccia-solve writes it: each family pair once from its lower index.
  // Here the families have no pad bonds, so every bond is within the horizon.
  const auto fam = build_families(written.position_m, std::vector<double>(n, run.horizon_m));
  std::vector<int64_t> offsets(n + 1, 0);
  std::vector<int32_t> partners;
  for (size_t i = 0; i < n; ++i) {
    for (int64_t k = fam.offsets[i]; k < fam.offsets[i + 1]; ++k)
      if (fam.neighbors[k] > static_cast<int32_t>(i)) partners.push_back(fam.neighbors[k]);
    offsets[i + 1] = static_cast<int64_t>(partners.size());
  }
  const size_t bytes = (partners.size() + 7) / 8;
  std::vector<uint8_t> all(bytes, 0);
  for (size_t b = 0; b < partners.size(); ++b) all[b / 8] |= static_cast<uint8_t>(1u << (b % 8));
  f.write("/bonds/offsets", offsets, {n + 1});
  f.write("/bonds/neighbors", partners, {partners.size()});
  f.write("/bonds/within_horizon", all, {bytes});
  f.set_attr("/", "output_count", static_cast<long long>(run.outputs.size()));
  for (size_t k = 0; k < run.outputs.size(); ++k) {
    const auto& o = run.outputs[k];
    char g[32];
    std::snprintf(g, sizeof g, "/output/%06zu", k);
    f.create_group(g);
    f.set_attr(g, "step", o.step);
    f.set_attr(g, "time_s", o.time_s);
    auto or_zero = [](const std::vector<double>& v, size_t size) { return v.empty() ? std::vector<double>(size, 0.0) : v; };
    f.write(std::string(g) + "/displacement", or_zero(o.displacement_m, 3 * n), {n, 3});
    f.write(std::string(g) + "/velocity", or_zero(o.velocity_m_s, 3 * n), {n, 3});
    f.write(std::string(g) + "/damage", or_zero(o.damage, n), {n});
    std::vector<uint8_t> broken(bytes, 0);
    for (size_t p = 0; p + 1 < o.broken_bonds.size(); p += 2) {
      const int64_t i = std::min(o.broken_bonds[p], o.broken_bonds[p + 1]);
      const int64_t j = std::max(o.broken_bonds[p], o.broken_bonds[p + 1]);
      const auto first = partners.begin() + offsets[i], last = partners.begin() + offsets[i + 1];
      const auto it = std::lower_bound(first, last, static_cast<int32_t>(j));
      if (it == last || *it != j) throw std::logic_error("synthetic broken bond is not a family bond");
      const size_t b = static_cast<size_t>(it - partners.begin());
      broken[b / 8] |= static_cast<uint8_t>(1u << (b % 8));
    }
    f.write(std::string(g) + "/broken", broken, {bytes});
  }
}

}  // namespace breccia::postproc::testing
