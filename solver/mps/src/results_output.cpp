#include "breccia/mps/results_output.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "breccia/common/error.hpp"
#include "breccia/common/particle_file.hpp"
#include "breccia/mps/particles.hpp"
#include "breccia/mps/simulation.hpp"
#include "breccia/mps/solid.hpp"

namespace breccia::mps {
namespace {

void set_bit(std::vector<uint8_t>& bits, int64_t b) { bits[b >> 3] |= static_cast<uint8_t>(1u << (b & 7)); }

// Whether the pair (i, j) is in the CSR row of i.
bool has_pair(const BondList& bonds, long long i, int j) {
  for (long long k = bonds.offset[i]; k < bonds.offset[i + 1]; ++k)
    if (bonds.neighbour[k] == j) return true;
  return false;
}

// The outermost particle layer on each face of a lattice box as the sets and surfaces a PD
// lattice's particles.h5 has (xmin, xmax, ymin, ymax[, zmin, zmax]; facets h x h, 2D h x t).
void add_lattice_faces(ParticleModel& m, double h) {
  const int d = m.dimension;
  const size_t n = m.size();
  const char* names[6] = {"xmin", "xmax", "ymin", "ymax", "zmin", "zmax"};
  for (int f = 0; f < 2 * d; ++f) {
    const int axis = f / 2;
    const double sign = (f % 2) ? 1.0 : -1.0;
    double edge = sign * -1e300;
    for (size_t i = 0; i < n; ++i) edge = sign > 0 ? std::max(edge, m.position_m[3 * i + axis]) : std::min(edge, m.position_m[3 * i + axis]);
    ParticleSet set{names[f], {}};
    SurfaceFacets facets;
    facets.name = names[f];
    for (size_t i = 0; i < n; ++i) {
      if (std::abs(m.position_m[3 * i + axis] - edge) > 0.25 * h) continue;
      set.indices.push_back(static_cast<int64_t>(i));
      facets.area_m2.push_back(d == 3 ? h * h : h * m.thickness_m);
      for (int k = 0; k < 3; ++k) {
        facets.normal.push_back(k == axis ? sign : 0.0);
        facets.centroid_m.push_back(m.position_m[3 * i + k] + (k == axis ? 0.5 * h * sign : 0.0));
      }
      facets.particle.push_back(static_cast<int64_t>(i));
    }
    m.sets.push_back(std::move(set));
    m.surfaces.push_back(std::move(facets));
  }
}

// A lattice or bodies specimen as particles.h5: positions, volumes, the nominal spacing (the
// lattice faces of breccia-post's crack surfaces need it), one material; a lattice gets the
// face sets and surfaces of a PD lattice, bodies one set per body.
ParticleModel cloud_model(const ParticleCloud& cloud, const std::string& material, const CaseSpec& spec) {
  ParticleModel m;
  m.dimension = cloud.dimension;
  m.thickness_m = cloud.dimension == 2 ? cloud.thickness_m : 1.0;
  m.position_m = cloud.position_m;
  m.volume_m3 = cloud.volume_m3;
  m.spacing_m.assign(m.volume_m3.size(), cloud.spacing_m);
  m.material_id.assign(m.volume_m3.size(), 0);
  m.material_names = {material};
  for (size_t s = 0; s < cloud.set_names.size(); ++s) m.sets.push_back({cloud.set_names[s], cloud.set_members[s]});
  if (spec.lattice) add_lattice_faces(m, cloud.spacing_m);
  m.source = std::string(spec.bodies ? "mps bodies" : "mps lattice") + " of " + spec.file;
  m.content_id = compute_content_id(m);
  return m;
}

}  // namespace

MpsResultsWriter::MpsResultsWriter(const std::string& h5_path, const std::string& out_dir, const CaseSpec& spec,
                                   const std::string& case_file, const std::string& content_id, const Simulation& sim)
    : out_dir_(out_dir) {
  if (spec.cracks.empty()) {
    open(h5_path, spec, case_file, content_id, sim.dimension(), sim.thickness_m(), sim.position_m(), sim.volume_m3(),
         sim.spacing_m(), sim.bonds(), sim.bonds());
    return;
  }
  // The crack removed the stencil bonds across it: the reference stencil, rebuilt as the
  // simulation built it before the cut (same cloud, re and periodicity), holds them.
  const ParticleCloud cloud = build_particle_cloud(spec);
  const BondList reference = build_bonds(cloud.dimension, cloud.position_m, spec.re_over_spacing * cloud.spacing_m,
                                         cloud.periodic);
  open(h5_path, spec, case_file, content_id, sim.dimension(), sim.thickness_m(), sim.position_m(), sim.volume_m3(),
       sim.spacing_m(), reference, sim.bonds());
}

MpsResultsWriter::MpsResultsWriter(const std::string& h5_path, const std::string& out_dir, const CaseSpec& spec,
                                   const std::string& case_file, const std::string& content_id, const Solid& sim)
    : out_dir_(out_dir) {
  // Bonds between bodies were never made; cut bonds keep their place in the CSR (weight 0).
  open(h5_path, spec, case_file, content_id, sim.dimension(), sim.thickness_m(), sim.position_m(), sim.volume_m3(),
       sim.spacing_m(), sim.bonds(), sim.bonds());
  fields_.push_back({"stress", 6});
  fields_.push_back({"eq_plastic_strain", 1});
  if (sim.fracture()) fields_.push_back({"fragment", 1, true});
}

MpsResultsWriter::~MpsResultsWriter() = default;

void MpsResultsWriter::open(const std::string& h5_path, const CaseSpec& spec, const std::string& case_file,
                            const std::string& content_id, int dimension, double thickness_m,
                            const std::vector<double>& position_m, const std::vector<double>& volume_m3,
                            double spacing_m, const BondList& reference, const BondList& current) {
  namespace fs = std::filesystem;
  n_ = volume_m3.size();
  const MaterialSpec& mat = spec.material;
  std::string particles_file = spec.particle_file, particles_id = content_id;
  if (particles_file.empty()) {
    // As for a PD lattice: the model built from the case file, beside the results.
    const ParticleModel model = cloud_model(build_particle_cloud(spec), mat.name, spec);
    if (model.position_m != position_m || model.volume_m3 != volume_m3)
      throw RunError("mps: the particles rebuilt for particles.h5 differ from the run's (internal error)");
    particles_file = solver::write_particles_beside_results(out_dir_, model);
    particles_id = model.content_id;
  }
  file_ = std::make_unique<h5::File>(h5_path, h5::File::Mode::Create);
  const h5::File& f = *file_;
  solver::write_results_identity(f, {fs::absolute(particles_file).string(), particles_id, dimension, thickness_m, "mps",
                                     fs::absolute(case_file).string()});
  const double re = spec.re_over_spacing * spacing_m;
  f.write("/particles/position", position_m, {n_, 3});
  f.write("/particles/volume", volume_m3, {n_});
  f.write("/particles/density", std::vector<double>(n_, mat.density_kg_m3), {n_});
  f.write("/particles/horizon", std::vector<double>(n_, re), {n_});
  f.write("/particles/material_id", std::vector<int32_t>(n_, 0), {n_});
  f.write_strings("/materials/names", {mat.name});
  // No /materials/fracture_energy: MPS fracture is a strength criterion without a fracture
  // energy, so breccia-post reports no G0 x area for it.
  bonds_ = solver::half_bond_list_of(reference.offset, reference.neighbour);
  reference_entries_ = reference.size();
  std::vector<int64_t> precrack;
  for (size_t i = 0; i < n_; ++i)
    for (int64_t b = bonds_.offsets[i]; b < bonds_.offsets[i + 1]; ++b) {
      set_bit(bonds_.within_horizon, b);
      if (&reference != &current && !has_pair(current, static_cast<long long>(i), static_cast<int>(bonds_.neighbors[b]))) {
        set_bit(bonds_.precrack, b);
        precrack.push_back(static_cast<int64_t>(i));
        precrack.push_back(bonds_.neighbors[b]);
      }
    }
  f.write("/precrack_bonds", precrack, {precrack.size() / 2, 2});
  solver::write_results_bonds(f, bonds_);
  f.create_group("/output");
  fields_ = {{"displacement", 3}, {"velocity", 3}, {"damage", 1}};
  f.flush();
}

void MpsResultsWriter::write_common(long long step, double time_s, const std::array<const std::vector<double>*, 3>& u,
                                    const std::array<const std::vector<double>*, 3>& v,
                                    const std::vector<double>& damage, const std::vector<uint8_t>& broken,
                                    int64_t broken_count) {
  const h5::File& f = *file_;
  const int index = output_count();
  const std::string g = solver::results_output_group(index);
  std::vector<double> u3(3 * n_), v3(3 * n_);
  for (size_t i = 0; i < n_; ++i)
    for (int a = 0; a < 3; ++a) {
      u3[3 * i + a] = (*u[a])[i];
      v3[3 * i + a] = (*v[a])[i];
    }
  f.write(g + "/displacement", u3, {n_, 3});
  f.write(g + "/velocity", v3, {n_, 3});
  f.write(g + "/damage", damage, {n_});
  solver::finish_results_output(f, index, step, time_s, broken, broken_count);
  times_.push_back(time_s);
}

std::function<void()> MpsResultsWriter::xdmf_writer() const {
  return [path = out_dir_ + "/results.xdmf", n = n_, times = times_, fields = fields_] {
    solver::write_results_xdmf(path, n, times, fields);
  };
}

void MpsResultsWriter::write(const Simulation& sim) {
  // The displacement formulation has no fracture: nothing is broken, damage is 0.
  write_common(sim.steps(), sim.time_s(), {&sim.displacement(0), &sim.displacement(1), &sim.displacement(2)},
               {&sim.velocity(0), &sim.velocity(1), &sim.velocity(2)}, std::vector<double>(n_, 0.0),
               std::vector<uint8_t>(bonds_.within_horizon.size(), 0), 0);
}

void MpsResultsWriter::write(const Solid& sim) {
  const h5::File& f = *file_;
  const std::string g = solver::results_output_group(output_count());
  std::vector<double> stress(6 * n_);
  for (size_t i = 0; i < n_; ++i) {
    const SymTensor& t = sim.stress_pa()[i];
    const double c[6] = {t.xx, t.yy, t.zz, t.xy, t.yz, t.zx};
    for (int k = 0; k < 6; ++k) stress[6 * i + k] = c[k];
  }
  f.write(g + "/stress", stress, {n_, 6});
  f.write(g + "/eq_plastic_strain", sim.eq_plastic_strain(), {n_});
  std::vector<uint8_t> broken(bonds_.within_horizon.size(), 0);
  int64_t broken_count = 0;
  std::vector<double> damage(n_, 0.0);
  if (const FractureModel* fr = sim.fracture()) {
    const BondList& bonds = sim.bonds();
    if (bonds.size() != reference_entries_ || bonds.offset.size() != n_ + 1)
      throw RunError("mps: the bond list changed shape during the run; results.h5 indexes the reference list");
    // A cut bond has weight 0 in both directions; its entry from the lower index decides.
    for (size_t b = 0; b < bonds_.entry.size(); ++b)
      if (bonds.weight[bonds_.entry[b]] == 0.0) {
        set_bit(broken, static_cast<int64_t>(b));
        ++broken_count;
      }
    damage = fr->damage(bonds);
    const std::vector<int> labels = FractureModel::fragment_labels(bonds);
    f.write(g + "/fragment", std::vector<int32_t>(labels.begin(), labels.end()), {n_});
  }
  write_common(sim.steps(), sim.time_s(), {&sim.displacement(0), &sim.displacement(1), &sim.displacement(2)},
               {&sim.velocity(0), &sim.velocity(1), &sim.velocity(2)}, damage, broken, broken_count);
}

void MpsResultsWriter::mark_complete() {
  file_->set_attr("/", "complete", 1LL);
  file_->flush();
}

}  // namespace breccia::mps
