#include "breccia/solver/outputs.hpp"

#include <omp.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "breccia/common/csv.hpp"
#include "breccia/common/error.hpp"
#include "breccia/common/output_file.hpp"
#include "breccia/common/particle_file.hpp"
#include "breccia/solver/lattice_model.hpp"
#include "breccia/solver/load_kernels.hpp"
#include "breccia/solver/pd_kernels.hpp"

namespace breccia::solver {
namespace {

// Internal-order 3N array -> file order.
std::vector<double> to_file_order3(const PdSystem& s, const std::vector<double>& a) {
  std::vector<double> out(3 * s.n);
  for (size_t k = 0; k < s.n; ++k)
    for (int d = 0; d < 3; ++d) out[3 * static_cast<size_t>(s.original_index[k]) + d] = a[3 * k + d];
  return out;
}

std::vector<double> to_file_order(const PdSystem& s, const std::vector<double>& a) {
  std::vector<double> out(s.n);
  for (size_t k = 0; k < s.n; ++k) out[static_cast<size_t>(s.original_index[k])] = a[k];
  return out;
}

bool is_precrack(const std::vector<std::pair<int64_t, int64_t>>& precrack_pairs, int64_t fi, int64_t fj) {
  return std::binary_search(precrack_pairs.begin(), precrack_pairs.end(), std::make_pair(fi, fj));
}

// Broken by fracture, seen from bond entry k: a half that never existed (outside that
// horizon) is not a broken bond.
bool fracture_broken(const PdSystem& s, int64_t k) {
  const uint8_t st = s.state[k];
  if (st == (kOwnIntact | kDualIntact)) return false;
  const bool own_broken = s.own_half_exists(k) && !(st & kOwnIntact);
  const bool dual_broken = s.k_dual_halves()[k] > 0 && !(st & kDualIntact);
  return own_broken || dual_broken;
}

bool bit(const std::vector<uint8_t>& bits, int64_t b) { return (bits[b >> 3] >> (b & 7)) & 1; }

}  // namespace

std::vector<int64_t> broken_pairs(const PdSystem& s) {
  std::vector<std::pair<int64_t, int64_t>> pairs;
  for (size_t i = 0; i < s.n; ++i)
    for (int64_t k = s.offsets[i]; k < s.offsets[i + 1]; ++k) {
      const int64_t fi = s.original_index[i], fj = s.original_index[s.neighbor[k]];
      if (fi >= fj || !fracture_broken(s, k)) continue;
      if (is_precrack(s.precrack_pairs, fi, fj)) continue;
      pairs.emplace_back(fi, fj);
    }
  std::sort(pairs.begin(), pairs.end());
  std::vector<int64_t> flat;
  flat.reserve(2 * pairs.size());
  for (auto& p : pairs) {
    flat.push_back(p.first);
    flat.push_back(p.second);
  }
  return flat;
}

namespace {
// Row i's partners of higher file index, as (partner's file index, entry) sorted by file
// index: its row of the file's bond list (half_bond_list, broken_bond_positions).
void higher_partners_by_file_index(const PdSystem& s, size_t i, std::vector<std::pair<int64_t, int64_t>>& row) {
  const int64_t fi = s.original_index[i];
  row.clear();
  for (int64_t k = s.offsets[i]; k < s.offsets[i + 1]; ++k) {
    const int64_t fj = s.original_index[s.neighbor[k]];
    if (fi < fj) row.emplace_back(fj, k);
  }
  std::sort(row.begin(), row.end());
}

// The fragment graph's bond test (half_bond_list says why): the pair (i, j), i the lower file
// index, within either end's horizon. The same arithmetic on the same doubles wherever the
// list is formed (a rank's x0 holds the particle file's positions, bit for bit: setup_system).
bool within_either_horizon(const double* xi, const double* xj, double horizon_i, double horizon_j) {
  double r2 = 0.0;
  for (int d = 0; d < 3; ++d) {
    const double e = xj[d] - xi[d];
    r2 += e * e;
  }
  return r2 <= horizon_i * horizon_i || r2 <= horizon_j * horizon_j;
}

}  // namespace

std::vector<int64_t> half_bond_counts(const PdSystem& r, size_t owned) {
  std::vector<int64_t> counts(owned, 0);
#pragma omp parallel for schedule(dynamic, 1024)
  for (size_t i = 0; i < owned; ++i) {
    const int64_t fi = r.original_index[i];
    for (int64_t k = r.offsets[i]; k < r.offsets[i + 1]; ++k)
      if (fi < r.original_index[r.neighbor[k]]) ++counts[i];
  }
  return counts;
}

HalfBondList half_bond_list(const PdSystem& s) {
  const size_t n = s.n;
  HalfBondList h;
  h.offsets.assign(n + 1, 0);
  {
    const std::vector<int64_t> counts = half_bond_counts(s, n);
    for (size_t i = 0; i < n; ++i) h.offsets[s.original_index[i] + 1] = counts[i];
  }
  for (size_t i = 0; i < n; ++i) h.offsets[i + 1] += h.offsets[i];
  const size_t b = static_cast<size_t>(h.offsets[n]);
  h.neighbors.resize(b);
  h.entry.resize(b);
#pragma omp parallel
  {
    std::vector<std::pair<int64_t, int64_t>> row;
#pragma omp for schedule(dynamic, 1024)
    for (size_t i = 0; i < n; ++i) {  // each internal row fills its own file row
      higher_partners_by_file_index(s, i, row);
      const int64_t first = h.offsets[s.original_index[i]];
      for (size_t r = 0; r < row.size(); ++r) {
        h.neighbors[first + r] = row[r].first;
        h.entry[first + r] = row[r].second;
      }
    }
  }
  // The fragment graph of breccia-post is the families of build_families(position, horizon)
  // without pads; the same test, same arithmetic, on the same file-order doubles, so that it
  // is exactly that graph (the pad bonds beyond it hold only a sliver of partial volume).
  std::vector<double> horizon(n);
  for (size_t k = 0; k < n; ++k) horizon[static_cast<size_t>(s.original_index[k])] = s.horizon[k];
  const std::vector<double>& x = s.particles.position_m;
  h.within_horizon.assign((b + 7) / 8, 0);
  h.precrack.assign((b + 7) / 8, 0);
  // Rows in parallel: a row's bits are gathered a byte at a time; a byte that lies wholly in
  // the row is stored, one shared with the rows beside it is OR-ed in atomically.
#pragma omp parallel for schedule(dynamic, 1024)
  for (size_t i = 0; i < n; ++i) {
    const int64_t begin = h.offsets[i], end = h.offsets[i + 1];
    uint8_t within = 0, precrack = 0;
    const auto flush = [&](int64_t byte) {
      const bool own = 8 * byte >= begin && 8 * byte + 8 <= end;
      for (auto [bits, value] : {std::pair{&h.within_horizon, within}, std::pair{&h.precrack, precrack}}) {
        if (value == 0) continue;
        if (own) (*bits)[byte] = value;
        else std::atomic_ref<uint8_t>((*bits)[byte]).fetch_or(value, std::memory_order_relaxed);
      }
      within = precrack = 0;
    };
    for (int64_t at = begin; at < end; ++at) {
      if (at > begin && (at & 7) == 0) flush((at >> 3) - 1);
      const size_t j = static_cast<size_t>(h.neighbors[at]);
      if (within_either_horizon(&x[3 * i], &x[3 * j], horizon[i], horizon[j])) within |= static_cast<uint8_t>(1u << (at & 7));
      if (!s.precrack_pairs.empty() && is_precrack(s.precrack_pairs, static_cast<int64_t>(i), static_cast<int64_t>(j)))
        precrack |= static_cast<uint8_t>(1u << (at & 7));
    }
    if (end > begin) flush((end - 1) >> 3);
  }
  return h;
}

std::vector<uint8_t> broken_bits(const PdSystem& s, const HalfBondList& h, int64_t* broken_count) {
  const int64_t b = static_cast<int64_t>(h.neighbors.size());
  const int64_t bytes = (b + 7) / 8;
  std::vector<uint8_t> bits(static_cast<size_t>(bytes), 0);
  int64_t total = 0;
#pragma omp parallel for schedule(static) reduction(+ : total)
  for (int64_t q = 0; q < bytes; ++q) {
    uint8_t byte = 0;
    for (int64_t at = 8 * q; at < std::min(b, 8 * q + 8); ++at)
      if (fracture_broken(s, h.entry[at]) && !bit(h.precrack, at)) {
        byte |= static_cast<uint8_t>(1u << (at & 7));
        ++total;
      }
    bits[q] = byte;
  }
  if (broken_count) *broken_count = total;
  return bits;
}

std::vector<int64_t> broken_bond_positions(const PdSystem& r, size_t owned, const std::vector<int64_t>& row_first,
                                           const std::vector<std::pair<int64_t, int64_t>>& precrack_pairs) {
  std::vector<int64_t> positions;
  std::vector<std::pair<int64_t, int64_t>> row;
  for (size_t i = 0; i < owned; ++i) {
    const int64_t fi = r.original_index[i];
    higher_partners_by_file_index(r, i, row);
    for (size_t q = 0; q < row.size(); ++q)
      if (fracture_broken(r, row[q].second) && !is_precrack(precrack_pairs, fi, row[q].first))
        positions.push_back(row_first[i] + static_cast<int64_t>(q));
  }
  return positions;
}

FileBondRows file_bond_rows(const PdSystem& r, size_t owned, const std::vector<int64_t>& row_first) {
  std::vector<std::pair<int64_t, size_t>> order(owned);  // (file index, row): the file's order
  for (size_t i = 0; i < owned; ++i) order[i] = {r.original_index[i], i};
  std::sort(order.begin(), order.end());
  FileBondRows out;
  std::vector<std::pair<int64_t, int64_t>> row;
  int64_t end = 0;  // the last row's end: the next row of higher file index starts there or later
  for (const auto& [fi, i] : order) {
    higher_partners_by_file_index(r, i, row);
    const int64_t first = row_first[i];
    if (first < end) throw std::logic_error("file_bond_rows: a row's place overlaps the row before it");
    end = first + static_cast<int64_t>(row.size());
    if (row.empty()) continue;
    if (!out.runs.empty() && static_cast<int64_t>(out.runs.back().first + out.runs.back().rows) == first)
      out.runs.back().rows += row.size();
    else
      out.runs.push_back({static_cast<hsize_t>(first), row.size()});
    for (size_t q = 0; q < row.size(); ++q) {
      const size_t j = static_cast<size_t>(r.neighbor[row[q].second]);
      out.neighbors.push_back(row[q].first);
      if (!within_either_horizon(&r.x0[3 * i], &r.x0[3 * j], r.horizon[i], r.horizon[j]))
        out.beyond_horizon.push_back(first + static_cast<int64_t>(q));
    }
  }
  return out;
}

ResultsWriter::ResultsWriter(const PdSystem& s, const std::string& out_dir, bool restart) : dir_(out_dir) {
  // A distributed set-up's global system without the partners (parallel HDF5): each rank
  // forms and writes its rows of the list (write_bonds_together).
  const bool ranks_hold_bonds = !s.distributed_rows.empty() && s.neighbor.size() != s.bond_count();
  std::filesystem::create_directories(out_dir);
  const std::string path = out_dir + "/results.h5";
  if (restart && std::filesystem::exists(path)) {
    file_ = std::make_unique<h5::File>(path, h5::File::Mode::ReadWrite);
    if (file_->attr_string("/", "particles_content_id") != s.particles.content_id)
      throw InputError(path, "/@particles_content_id", "belongs to a different particle model",
                       "the results of this case (or a fresh output directory)");
    if (file_->attr_int("/", "format_version") != kResultsFormatVersion)
      throw InputError(path, "/@format_version", std::to_string(file_->attr_int("/", "format_version")),
                       std::to_string(kResultsFormatVersion) + " (results of this breccia-solve; use a fresh output directory)");
    unchecked_bonds_ = file_->exists("/bonds/neighbors") ? static_cast<int64_t>(file_->dims("/bonds/neighbors").at(0)) : -2;
    if (!ranks_hold_bonds) bonds_ = half_bond_list(s);
    // A distributed run's ranks check together (mpi_backend.cpp): an error on rank 0 alone
    // here would leave the others waiting in the run's first collective.
    if (s.distributed_rows.empty()) check_bond_count(bond_list_size());
    // Keep outputs up to the checkpoint; later ones are recomputed.
    const int stored = static_cast<int>(file_->attr_int("/", "output_count"));
    for (int k = 0; k < stored; ++k) {
      const std::string g = results_output_group(k);
      if (file_->attr_int(g, "step") > s.step) {
        H5Ldelete(file_->id(), g.c_str(), H5P_DEFAULT);
      } else {
        // results.xdmf lists this run's fields for every group: a kept group must hold them
        // (a restart with more output.fields pointed ParaView at datasets that do not exist).
        for (const ResultsField& f : results_fields(s))
          if (!file_->exists(g + "/" + f.name))
            throw InputError(path, g + "/" + f.name, "missing: the run being continued did not write this field",
                             "the output.fields of the run the checkpoint belongs to (or a fresh output directory)");
        count_ = k + 1;
        times_.push_back(file_->attr_double(g, "time_s"));
      }
    }
    file_->set_attr("/", "output_count", static_cast<long long>(count_));
    file_->set_attr("/", "complete", 0LL);
    // results.xdmf at once for the groups kept: it listed the ones just removed until the next
    // output, and for good if the restarted run stopped before one.
    write_xdmf(s);
    return;
  }
  file_ = std::make_unique<h5::File>(path, h5::File::Mode::Create);
  h5::File& f = *file_;
  // A lattice built from the case file has no particles.h5 yet: one is written beside the
  // results, of the whole lattice, made again where this system holds a part of it or none
  // (a distributed run's rank 0: the set-up's window, or let go: run_case).
  std::string particles_file = s.config.particles_path;
  if (particles_file.empty()) {
    if (s.particles.held_rows.empty() && s.particles.size() == s.whole_n())
      particles_file = write_particles_beside_results(out_dir, s.particles);
    else if (s.config.lattice)
      particles_file = write_particles_beside_results(out_dir, lattice_model(*s.config.lattice));
    else
      throw std::logic_error("results.h5: no particle file, and a part of the particle model");
  }
  write_results_identity(f, {std::filesystem::absolute(particles_file).string(), s.particles.content_id, s.dimension,
                             s.thickness, s.config.model_name, std::filesystem::absolute(s.config.file).string()});
#ifdef BRECCIA_PARALLEL_HDF5
  // A distributed run: every rank writes its own rows (write_particles_together).
  particles_pending_ = !s.distributed_rows.empty();
#endif
  if (!particles_pending_) {
    const size_t n = s.n;
    std::vector<double> density(n), horizon(n);
    std::vector<int32_t> material(n);
    for (size_t k = 0; k < n; ++k) {
      const size_t fi = static_cast<size_t>(s.original_index[k]);
      density[fi] = s.density[k];
      horizon[fi] = s.horizon[k];
      material[fi] = s.material[k];
    }
    f.write("/particles/position", s.particles.position_m, {n, 3});
    f.write("/particles/volume", s.particles.volume_m3, {n});
    f.write("/particles/density", density, {n});
    f.write("/particles/horizon", horizon, {n});
    f.write("/particles/material_id", material, {n});
  }
  std::vector<std::string> names;
  std::vector<double> g0;
  for (const auto& m : s.config.materials) {
    names.push_back(m.name);
    g0.push_back(m.fracture_energy);
  }
  f.write_strings("/materials/names", names);
  f.write("/materials/fracture_energy", g0, {g0.size()});
  std::vector<int64_t> pre;
  for (auto& p : s.precrack_pairs) {
    pre.push_back(p.first);
    pre.push_back(p.second);
  }
  f.write("/precrack_bonds", pre, {pre.size() / 2, 2});
  if (ranks_hold_bonds) {
    bonds_pending_ = true;
  } else {
    bonds_ = half_bond_list(s);
    write_results_bonds(f, bonds_);
  }
  f.create_group("/output");
  f.flush();
}

void ResultsWriter::check_bond_count(int64_t bonds) {
  if (unchecked_bonds_ == -1) return;  // a new file, or checked
  if (unchecked_bonds_ != bonds)
    throw InputError(dir_ + "/results.h5", "/bonds/neighbors", "missing or a different bond count",
                     std::to_string(bonds) + " bonds, as this case builds");
  unchecked_bonds_ = -1;
}

std::vector<ResultsField> results_fields(const PdSystem& s) {
  std::vector<ResultsField> out{{"displacement", 3, &PdSystem::u}, {"velocity", 3, &PdSystem::v}, {"damage", 1, &PdSystem::damage}};
  const ResultsField optional[] = {{"stretch", 1, &PdSystem::max_stretch},
                                   {"dilatation", 1, &PdSystem::dilatation},
                                   {"strain_energy_density", 1, &PdSystem::energy_density}};
  for (const ResultsField& f : optional)
    if (std::find(s.config.fields.begin(), s.config.fields.end(), f.name) != s.config.fields.end()) out.push_back(f);
  return out;
}

namespace {
std::vector<hsize_t> field_dims(size_t n, int components) {
  return components == 1 ? std::vector<hsize_t>{n} : std::vector<hsize_t>{n, static_cast<hsize_t>(components)};
}
}  // namespace

void ResultsWriter::write(const PdSystem& s) {
  if (bonds_.offsets.empty())  // the ranks hold the list and the bond states: write_together
    throw std::logic_error("results.h5: an output group written alone where the ranks hold the bond list");
  if (!file_) file_ = std::make_unique<h5::File>(dir_ + "/results.h5", h5::File::Mode::ReadWrite);
  h5::File& f = *file_;
  const std::string g = results_output_group(count_);
  const size_t n = s.n;
  for (const ResultsField& field : results_fields(s))
    f.write(g + "/" + field.name, field.components == 3 ? to_file_order3(s, s.*field.values) : to_file_order(s, s.*field.values),
            field_dims(n, field.components));
  int64_t broken_count = 0;
  const std::vector<uint8_t> broken = broken_bits(s, bonds_, &broken_count);
  finish_results_output(f, count_, static_cast<long long>(s.step), s.time, broken, broken_count);
  count_output(s);
}

void ResultsWriter::count_output(const PdSystem& s) {
  ++count_;
  times_.push_back(s.time);
  write_xdmf(s);
}

#ifdef BRECCIA_PARALLEL_HDF5
void ResultsWriter::write_together(const PdSystem& s, ResultsWriter* w, const std::string& out_dir, size_t file_first,
                                   size_t file_count, const std::vector<std::vector<double>>& rows,
                                   const std::vector<uint8_t>& broken_block, size_t broken_first, size_t broken_bytes,
                                   long long broken_count, MPI_Comm comm) {
  // The root: the group's index, then its own handle closed, since the ranks open the file
  // together (one open per process).
  long long index = 0;
  if (w) {
    index = w->count_;
    w->file_.reset();
  }
  MPI_Bcast(&index, 1, MPI_LONG_LONG, 0, comm);
  {
    h5::File f(out_dir + "/results.h5", h5::File::Mode::ReadWrite, comm);
    const std::string g = results_output_group(static_cast<int>(index));
    const std::vector<ResultsField> fields = results_fields(s);
    for (size_t k = 0; k < fields.size(); ++k)
      f.write_rows(g + "/" + fields[k].name, rows[k].data(), file_first, file_count, field_dims(s.whole_n(), fields[k].components));
    // /broken as finish_results_output writes the whole bits (the same dataset), by blocks.
    f.write_rows(g + "/broken", broken_block.data(), broken_first, broken_block.size(), {broken_bytes});
    finish_results_output_attributes(f, static_cast<int>(index), static_cast<long long>(s.step), s.time, broken_count);
  }
  if (w) w->count_output(s);
}

void ResultsWriter::write_bonds_together(ResultsWriter* w, const std::string& out_dir,
                                         const std::vector<int64_t>& offsets_block, size_t offsets_first,
                                         size_t offsets_rows, int64_t bonds_total, const FileBondRows& mine,
                                         const std::vector<uint8_t>& within_horizon, size_t within_first,
                                         MPI_Comm comm) {
  if (w) {  // the root's own handle closed: the ranks open the file together
    w->file_.reset();
    w->bonds_pending_ = false;
  }
  h5::File f(out_dir + "/results.h5", h5::File::Mode::ReadWrite, comm);
  const size_t bonds = static_cast<size_t>(bonds_total);
  // The datasets and their order as write_results_bonds writes them.
  f.write_rows("/bonds/offsets", offsets_block.data(), offsets_first, offsets_block.size(), {offsets_rows});
  f.write_runs("/bonds/neighbors", mine.neighbors.data(), mine.runs, {bonds}, h5::Filter::ScaleOffset);
  f.write_rows("/bonds/within_horizon", within_horizon.data(), within_first, within_horizon.size(), {(bonds + 7) / 8});
}

void ResultsWriter::write_particles_together(ResultsWriter* w, const std::string& out_dir, size_t file_first,
                                             size_t file_count, const std::vector<std::vector<double>>& rows,
                                             size_t whole_n, MPI_Comm comm) {
  if (w) {  // the root's own handle closed: the ranks open the file together
    w->file_.reset();
    w->particles_pending_ = false;
  }
  h5::File f(out_dir + "/results.h5", h5::File::Mode::ReadWrite, comm);
  // The datasets, their types and order as the constructor writes them of the whole arrays.
  f.write_rows("/particles/position", rows.at(0).data(), file_first, file_count, {whole_n, 3});
  f.write_rows("/particles/volume", rows.at(1).data(), file_first, file_count, {whole_n});
  f.write_rows("/particles/density", rows.at(2).data(), file_first, file_count, {whole_n});
  f.write_rows("/particles/horizon", rows.at(3).data(), file_first, file_count, {whole_n});
  const std::vector<int32_t> material(rows.at(4).begin(), rows.at(4).end());
  f.write_rows("/particles/material_id", material.data(), file_first, file_count, {whole_n});
}
#endif

void ResultsWriter::write_xdmf(const PdSystem& s) const {
  std::vector<XdmfField> fields;
  for (const ResultsField& f : results_fields(s)) fields.push_back({f.name, f.components});
  write_results_xdmf(dir_ + "/results.xdmf", s.whole_n(), times_, fields);
}

std::pair<double, int64_t> nearest_particle(const double* x0, size_t count, const Vec3& position) {
  int64_t best = 0;
  double best_d2 = 1e300;
  for (size_t i = 0; i < count; ++i) {
    double d2 = 0;
    for (int d = 0; d < 3; ++d) d2 += std::pow(x0[3 * i + d] - position[d], 2);
    if (d2 < best_d2) {
      best_d2 = d2;
      best = static_cast<int64_t>(i);
    }
  }
  return {best_d2, best};
}

std::vector<IndenterTerm> indenter_terms(const PdSystem& s, size_t count, int64_t first) {
  const IndenterSpec& ind = s.config.indenter;
  // Each thread its static block of the particles, the blocks joined in order: index order.
  std::vector<std::vector<IndenterTerm>> blocks(static_cast<size_t>(omp_get_max_threads()));
#pragma omp parallel num_threads(static_cast<int>(blocks.size()))
  {
    const size_t t = static_cast<size_t>(omp_get_thread_num()), threads = static_cast<size_t>(omp_get_num_threads());
    for (size_t i = count * t / threads; i < count * (t + 1) / threads; ++i) {
      IndenterTerm term{first + static_cast<int64_t>(i), {0.0, 0.0, 0.0}};
      indenter_force(s.x0.data(), s.u.data(), static_cast<int64_t>(i), s.indenter_position, ind.radius, ind.stiffness,
                     term.f);
      if (term.f[0] == 0.0 && term.f[1] == 0.0 && term.f[2] == 0.0) continue;  // out of contact
      for (double& c : term.f) c *= s.volume[i];
      blocks[t].push_back(term);
    }
  }
  std::vector<IndenterTerm> out;
  for (const std::vector<IndenterTerm>& b : blocks) out.insert(out.end(), b.begin(), b.end());
  return out;
}

void indenter_reaction(const std::vector<IndenterTerm>& terms, double out[3]) {
  // The particles out of contact add zeros, which change no sum (it starts from +0 and no
  // subtraction gives -0), so the terms alone give every particle's sum in index order.
  out[0] = out[1] = out[2] = 0.0;
  for (const IndenterTerm& t : terms)
    for (int d = 0; d < 3; ++d) out[d] -= t.f[d];
}

HistoryWriter::HistoryWriter(const PdSystem& s, const std::string& out_dir, bool append) {
  std::filesystem::create_directories(out_dir);
  const std::string path = out_dir + "/history.csv";
  // A distributed run's backend finds the probes over the ranks and hands their values to
  // write (HistoryParticles): its rank 0 searches no whole positions here (-1).
  const bool whole = s.distributed_rows.empty();
  for (const auto& p : s.config.probes)
    probes_.emplace_back(whole ? static_cast<int32_t>(nearest_particle(s.x0.data(), s.n, p.position).second) : -1,
                         p.field == "velocity" ? 1 : 0);
  if (append && std::filesystem::exists(path)) {
    // Drop rows after the checkpoint step so the history continues seamlessly.
    std::ifstream in(path);
    std::string line, kept;
    bool header = true;
    while (std::getline(in, line)) {
      if (!header && std::stoll(split_csv_line(line, 2)[0]) > s.step) break;  // column 1: step
      kept += line + "\n";
      header = false;
    }
    in.close();
    write_text_file(path, kept);
    file_ = std::fopen(path.c_str(), "a");
  } else {
    file_ = std::fopen(path.c_str(), "w");
    if (!file_) throw RunError("cannot write " + path);
    std::fprintf(file_, "step,time_s,kinetic_J,strain_J,external_work_J,dissipated_J,total_J,max_damage,broken_bonds");
    if (s.config.indenter.enabled) std::fprintf(file_, ",indenter_force_x_N,indenter_force_y_N,indenter_force_z_N");
    if (s.gas.active)
      std::fprintf(file_, ",gas_pressure_Pa,cavity_volume_m3,crack_gas_volume_m3,gas_work_J,gas_mass_fraction,"
                          "gas_vented,gas_wetted_particles,gas_vent_area_m2");
    const char* comp[2][3] = {{"ux", "uy", "uz"}, {"vx", "vy", "vz"}};
    for (size_t p = 0; p < probes_.size(); ++p)
      for (int d = 0; d < 3; ++d)
        std::fprintf(file_, ",probe_%s_%s", s.config.probes[p].name.c_str(), comp[probes_[p].second][d]);
    std::fprintf(file_, "\n");
  }
  if (!file_) throw RunError("cannot write " + path);
}

HistoryWriter::~HistoryWriter() {
  if (file_) std::fclose(file_);
}

void HistoryWriter::write(const PdSystem& s, const Energies& e, const HistoryParticles* particles) {
  // Broken bonds counted as pairs: each pair has two entries, each with up to two halves.
  std::fprintf(file_, "%lld,%.9e,%.9e,%.9e,%.9e,%.9e,%.9e,%.6f,%lld", s.step, s.time, e.kinetic, e.strain,
               s.external_work, s.dissipated_energy, e.kinetic + e.strain + s.dissipated_energy - s.external_work,
               e.max_damage, e.broken_half_bonds / 2);
  if (s.config.indenter.enabled) {
    // The force the particles exert on the indenter at this step's position.
    double f[3];
    if (particles) std::copy(particles->indenter, particles->indenter + 3, f);
    else indenter_reaction(indenter_terms(s, s.n, 0), f);
    std::fprintf(file_, ",%.9e,%.9e,%.9e", f[0], f[1], f[2]);
  }
  if (s.gas.active) {
    const GasState& g = s.gas;
    long long wetted = e.gas_wetted;  // a distributed run's sum over its ranks
    if (wetted < 0) {
      wetted = 0;
      for (double t : g.arrival) wetted += t < 1e300;
    }
    std::fprintf(file_, ",%.9e,%.9e,%.9e,%.9e,%.9e,%d,%lld,%.9e", g.pressure, g.volume, g.crack_volume, g.work,
                 g.mass_fraction, g.vented ? 1 : 0, wetted, g.outflow_area());
  }
  for (size_t p = 0; p < probes_.size(); ++p) {
    const auto [i, kind] = probes_[p];
    if (!particles && i < 0) throw std::logic_error("history: a distributed run's probe values were not handed over");
    const double* src = particles ? &particles->probes.at(3 * p) : &(kind ? s.v : s.u)[3 * static_cast<size_t>(i)];
    for (int d = 0; d < 3; ++d) std::fprintf(file_, ",%.9e", src[d]);
  }
  std::fprintf(file_, "\n");
  std::fflush(file_);
}

namespace {

// The doubles of the first `count` elements of a float or double array.
template <class T, class A> std::vector<double> doubles_of(const std::vector<T, A>& a, size_t count) {
  return std::vector<double>(a.begin(), a.begin() + static_cast<std::ptrdiff_t>(count));
}

// checkpoint.h5's content: the scalars and small arrays from s, the per-particle and per-entry
// arrays row by row from `mine` (the whole arrays when one process writes). Which datasets
// and their sizes come from what every rank holds alike (the particle and bond counts, the
// case, the rank's own rows): a distributed run's ranks other than 0 hold none of the whole
// arrays (release_global_for_loop, rank_system.hpp).
void write_checkpoint_content(const h5::File& f, const PdSystem& s, const CheckpointRows& mine) {
  {
    f.set_attr("/", "format", std::string("breccia-checkpoint"));
    f.set_attr("/", "particles_content_id", s.particles.content_id);
    f.set_attr("/", "case_file", s.config.file);
    f.set_attr("/", "step", static_cast<long long>(s.step));
    f.set_attr("/", "time_s", s.time);
    f.set_attr("/", "dt_s", s.dt);
    f.set_attr("/", "external_work_J", s.external_work);
    f.set_attr("/", "dissipated_J", s.dissipated_energy);
    f.set_attr("/", "bond_count", static_cast<long long>(s.bond_count()));
    f.set_attr("/", "model", s.config.model_name);
    const size_t n = s.whole_n();  // a window system's (PdSystem::window_global) too
    const PdSystem& r = *mine.rows;
    const size_t p0 = mine.particle_first, pc = mine.particle_count, e0 = mine.entry_first, ec = mine.entry_count;
    f.write_rows("/u", r.u.data(), p0, pc, {n, 3});
    f.write_rows("/v", r.v.data(), p0, pc, {n, 3});
    f.write_rows("/a", r.a.data(), p0, pc, {n, 3});
    f.write_rows("/force", r.force.data(), p0, pc, {n, 3});
    f.write_rows("/body", r.body.data(), p0, pc, {n, 3});
    const size_t entries = s.bond_count();
    f.write_rows("/bond_state", r.state.data(), e0, ec, {entries});
    if (s.config.softening)  // softening bonds (their damage is held exactly then: setup_system)
      f.write_rows("/bond_damage", r.bond_damage.data(), e0, ec, {entries});  // float32, as held
    if (s.config.strength_rate != StrengthRateLaw::None)  // the onsets softening bonds were given at their rate
      f.write_rows("/bond_onset", r.s_onset.data(), e0, ec, {entries});
    if (!r.min_stretch.empty()) {  // every rank owns a particle: held alike  // compressive enhancement: the s_min this step's pass read, and its own
      f.write_rows("/min_stretch_previous", doubles_of(r.min_stretch, pc).data(), p0, pc, {n});
      f.write_rows("/min_stretch", doubles_of(r.min_stretch_next, pc).data(), p0, pc, {n});
    }
    std::vector<double> ind(s.indenter_position, s.indenter_position + 3);
    f.write("/indenter_position", ind, {3});
    if (s.gas.active) {  // the gas's state: its scalars, the frozen wall shares, the front
      const GasState& g = s.gas;
      const std::vector<double> scalars{g.volume,       g.wall_volume, g.crack_volume, g.pressure, g.pressure_abs,
                                        g.mass_fraction, g.work,        g.vented ? 1.0 : 0.0, g.vent_time,
                                        g.peak_pressure, g.spent ? 1.0 : 0.0, g.crack_vent_area, g.debris_volume};
      f.write("/gas/scalars", scalars, {scalars.size()});
      // Per facet particle, particle and entry: the rows of `mine` (a rank's own gas arrays).
      const GasState& rg = r.gas;
      const size_t f0 = mine.facet_first, fc = mine.facet_count;
      // (the whole body's facet particles: a window system holds its window's, PdSystem::whole_facet_particles)
      const size_t facets = s.whole_facet_particles.empty() ? g.wall_dv.size() : s.whole_facet_particles.size();
      f.write_rows("/gas/wall_dv", rg.wall_dv.data(), f0, fc, {facets});
      f.write_rows("/gas/wall_on", rg.wall_on.data(), f0, fc, {facets});
      if (g.crack_entry) {
        f.write_rows("/gas/arrival", rg.arrival.data(), p0, pc, {n});
        f.write_rows("/gas/in_crack", rg.in_crack.data(), e0, ec, {entries});  // which cracks the work follows
        if (g.crack_pass_every > 1) {  // between two crack passes: the vectors the volume follows
          f.write_rows("/gas/push", rg.push.data(), p0, pc, {n, 3});
          const std::vector<double> pass{static_cast<double>(g.crack_pass_countdown), g.crack_pass_done ? 1.0 : 0.0,
                                         static_cast<double>(g.crack_pass_interval)};
          f.write("/gas/crack_pass", pass, {pass.size()});
        }
      }
    }
  }
}

}  // namespace

void write_checkpoint(const PdSystem& s, const std::string& path) {
  OutputFile out(path);
  {
    h5::File f(out.temp_path().string(), h5::File::Mode::Create);
    // The gas's wall shares, one per facet particle (setup_gas): a distributed run's rank 0
    // writes this file with serial HDF5 after its facet lists were let go (release_global_for_loop).
    write_checkpoint_content(f, s, {&s, 0, s.n, 0, s.bond_count(), 0, s.gas.wall_dv.size()});
  }
  out.commit();
}

#ifdef BRECCIA_PARALLEL_HDF5
void write_checkpoint(const PdSystem& s, const std::string& path, const CheckpointRows& mine, MPI_Comm comm,
                      bool root) {
  std::unique_ptr<OutputFile> out;  // the root's: it alone renames (or, failing, removes) the file
  if (root) out = std::make_unique<OutputFile>(path);
  {
    h5::File f(OutputFile::temp_path_of(path).string(), h5::File::Mode::Create, comm);
    write_checkpoint_content(f, s, mine);
  }  // closing is collective: every rank's rows are in the file before the root renames it
  if (out) out->commit();
}
#endif

CheckpointedPassState::CheckpointedPassState(const PdSystem& s)
    : dissipated_(s.dissipated_energy), force_(s.force), keep_bonds_(s.config.strength_rate != StrengthRateLaw::None) {
  if (keep_bonds_) state_ = s.state, damage_ = s.bond_damage, onset_ = s.s_onset, ultimate_ = s.s0_own;
}

void CheckpointedPassState::restore(PdSystem& s) {
  if (keep_bonds_)
    s.state = std::move(state_), s.bond_damage = std::move(damage_), s.s_onset = std::move(onset_),
    s.s0_own = std::move(ultimate_);
  s.dissipated_energy = dissipated_;
  s.force = std::move(force_);
}

void ResultsWriter::mark_complete() {
  if (file_) {
    file_->set_attr("/", "complete", 1LL);
    return;
  }
  h5::File(dir_ + "/results.h5", h5::File::Mode::ReadWrite).set_attr("/", "complete", 1LL);
}

void read_checkpoint(PdSystem& s, const std::string& path, int rank) {
  if (!std::filesystem::exists(path)) throw InputError(path, "", "checkpoint file does not exist", "a checkpoint.h5");
  h5::File f(path, h5::File::Mode::Read);
  if (!f.has_attr("/", "format") || f.attr_string("/", "format") != "breccia-checkpoint")
    throw InputError(path, "/@format", "not a Breccia checkpoint", "a checkpoint.h5 written by breccia-solve");
  if (f.attr_string("/", "particles_content_id") != s.particles.content_id)
    throw InputError(path, "/@particles_content_id", "was written for a different particle model",
                     "a checkpoint of this case");
  if (static_cast<size_t>(f.attr_int("/", "bond_count")) != s.bond_count())
    throw InputError(path, "/@bond_count", "bond count differs from this case's families",
                     "a checkpoint of the same case (horizon and model unchanged)");
  // The model's state is read as this case's model's (checkpoints before the attribute: unchecked).
  if (f.has_attr("/", "model") && f.attr_string("/", "model") != s.config.model_name)
    throw InputError(path, "/@model", "'" + f.attr_string("/", "model") + "', this case's is '" + s.config.model_name + "'",
                     "a checkpoint of this case (model unchanged)");
  s.step = f.attr_int("/", "step");
  s.time = f.attr_double("/", "time_s");
  // The run goes on with the checkpoint's step (the same bits as a straight run), which this
  // case's particles must still bear: a case made stiffer or finer since would blow up a few
  // steps in, judged unstable (exit 3), where a fresh run with that step is refused (exit 2).
  const double dt_file = f.attr_double("/", "dt_s");
  if (s.config.check_stability && s.stable_dt > 0 && dt_file > s.stable_dt)
    throw InputError(path, "/@dt_s",
                     short_number(dt_file) + " s, above this case's stable step " + short_number(s.stable_dt) + " s",
                     "a checkpoint of this case (the material, spacing or model changed since it was written?)");
  s.dt = dt_file;
  s.external_work = f.attr_double("/", "external_work_J");
  s.dissipated_energy = f.attr_double("/", "dissipated_J");
  // The per-particle and per-entry arrays: a distributed set-up's rank reads its owned rows
  // alone (one run of the file's rows and one of its entries: both are in internal order,
  // whatever the rank count that wrote the file), which its system takes (copy_rank_state);
  // its ghosts' values come from their owners (the time loop's backend exchanges them,
  // mpi_backend.cpp). Rank 0 of a build without parallel HDF5 reads them whole (its writers'
  // staging).
  size_t row_first = 0, row_count = s.whole_n();
  size_t entry_first = 0, entry_count = s.bond_count();
#ifndef BRECCIA_PARALLEL_HDF5
  if (rank != 0)
#endif
    if (!s.distributed_rows.empty()) {
      if (s.distributed_entries.size() != s.distributed_rows.size())
        throw std::logic_error("read_checkpoint: a distributed set-up's entry ranges are missing");
      row_first = static_cast<size_t>(s.distributed_rows[rank]);
      row_count = static_cast<size_t>(s.distributed_rows[rank + 1]) - row_first;
      entry_first = static_cast<size_t>(s.distributed_entries[rank]);
      entry_count = static_cast<size_t>(s.distributed_entries[rank + 1]) - entry_first;
    }
  s.restart_rows = {static_cast<int64_t>(row_count)};  // summary.json's restart_rows_per_rank
  auto particle_rows = [&](const std::string& dataset, size_t width) {
    const std::vector<hsize_t> d = f.dims(dataset);
    if (d.empty() || d[0] != s.whole_n() || (d.size() == 1 ? 1 : d[1]) != width)
      throw InputError(path, dataset, "sized for other particles", "a checkpoint of this case");
    return f.read_double_rows(dataset, row_first, row_count);
  };
  s.u = particle_rows("/u", 3);
  s.v = particle_rows("/v", 3);
  s.a = particle_rows("/a", 3);
  s.force = particle_rows("/force", 3);
  s.body = particle_rows("/body", 3);
  auto entries_sized = [&](const std::string& dataset) {
    const std::vector<hsize_t> d = f.dims(dataset);
    if (d.size() != 1 || d[0] != s.bond_count())
      throw InputError(path, dataset, "sized for other families", "a checkpoint of this case");
  };
  auto entry_bytes = [&](const std::string& dataset) {
    entries_sized(dataset);
    return f.read_uint8_rows(dataset, entry_first, entry_count);
  };
  auto entry_floats = [&](const std::string& dataset) {
    entries_sized(dataset);
    const std::vector<double> d = f.read_double_rows(dataset, entry_first, entry_count);
    return std::vector<float>(d.begin(), d.end());
  };
  s.state = entry_bytes("/bond_state");
  if (s.config.softening) {  // softening bonds: partial damage is state
    if (!f.exists("/bond_damage"))
      throw InputError(path, "/bond_damage", "missing (written without materials[].tensile_strength)",
                       "a checkpoint of this case with the same materials");
    const std::vector<float> damage = entry_floats("/bond_damage");
    s.bond_damage.assign(damage.begin(), damage.end());
  }
  if (s.config.strength_rate != StrengthRateLaw::None) {
    if (!f.exists("/bond_onset"))
      throw InputError(path, "/bond_onset", "missing (written without materials[].strength_rate)",
                       "a checkpoint of this case with the same materials");
    // The ultimates of the raised laws are not written: each is the set-up's scaled as its
    // onset was (pd_kernels.hpp raised_ultimate), rebuilt here from the set-up's values where
    // this system holds them (a distributed set-up's ranks hold their rows' ultimates:
    // copy_rank_state rebuilds those from the rows read here).
    take_raised_onsets(s.s_onset, s.s0_own, entry_floats("/bond_onset"));
  }
  if (!s.min_stretch.empty()) {
    if (!f.exists("/min_stretch_previous"))
      throw InputError(path, "/min_stretch_previous", "missing (written without model.compressive_enhancement)",
                       "a checkpoint of this case with the same fracture rule");
    // The pass below recomputes the checkpointed step's forces with the s_min that step read
    // and writes the step's own again (commit_min_stretch, pd_system.hpp).
    const auto previous = particle_rows("/min_stretch_previous", 1);
    const auto own = particle_rows("/min_stretch", 1);
    s.min_stretch.assign(previous.begin(), previous.end());
    s.min_stretch_next.assign(own.begin(), own.end());
  }
  const auto ind = f.read_doubles("/indenter_position");
  for (int d = 0; d < 3; ++d) s.indenter_position[d] = ind[d];
  if (s.gas.active) {
    GasState& g = s.gas;
    if (!f.exists("/gas/scalars"))
      throw InputError(path, "/gas/scalars", "missing (written without a gas load)", "a checkpoint of this case");
    const auto sc = f.read_doubles("/gas/scalars");
    auto wall = f.read_doubles("/gas/wall_dv");
    // A window system's wall shares are its window's facet particles' (PdSystem::
    // whole_facet_particles): their rows of the whole list, in order.
    const bool window = !s.whole_facet_particles.empty();
    std::vector<size_t> rows;
    if (window)
      for (const int32_t p : s.facets.particle) {
        const int32_t i = s.window_global[static_cast<size_t>(p)];
        const auto at = std::lower_bound(s.whole_facet_particles.begin(), s.whole_facet_particles.end(), i);
        rows.push_back(static_cast<size_t>(at - s.whole_facet_particles.begin()));
      }
    auto window_rows = [&](auto whole) {
      if (!window) return whole;
      decltype(whole) out(rows.size());
      for (size_t q = 0; q < rows.size(); ++q) out[q] = whole[rows[q]];
      return out;
    };
    // 12 scalars: written before the debris entries' frozen volume (none then).
    if ((sc.size() != 12 && sc.size() != 13) ||
        wall.size() != (window ? s.whole_facet_particles.size() : g.wall_dv.size()))
      throw InputError(path, "/gas", "gas state of another cavity", "a checkpoint of this case");
    wall = window_rows(std::move(wall));
    g.volume = sc[0], g.wall_volume = sc[1], g.crack_volume = sc[2], g.pressure = sc[3], g.pressure_abs = sc[4];
    g.mass_fraction = sc[5], g.work = sc[6], g.vented = sc[7] != 0.0, g.vent_time = sc[8];
    g.peak_pressure = sc[9], g.spent = sc[10] != 0.0, g.crack_vent_area = sc[11];
    g.debris_volume = sc.size() > 12 ? sc[12] : 0.0;
    g.wall_dv = wall;
    if (!f.exists("/gas/wall_on"))
      throw InputError(path, "/gas/wall_on", "missing (written by an older breccia-solve)",
                       "a checkpoint of this case written by this version");
    g.wall_on = window_rows(f.read_uint8("/gas/wall_on"));
    if (g.crack_entry) {
      g.arrival = particle_rows("/gas/arrival", 1);
      g.arrival_next = g.arrival;
      if (!f.exists("/gas/in_crack"))
        throw InputError(path, "/gas/in_crack", "missing (written by an older breccia-solve)",
                         "a checkpoint of this case written by this version");
      g.in_crack = entry_bytes("/gas/in_crack");
      if (g.crack_pass_every > 1) {
        if (!f.exists("/gas/push") || !f.exists("/gas/crack_pass"))
          throw InputError(path, "/gas/push", "missing (a checkpoint of a run with crack_pass_every 1)",
                           "a checkpoint of this case with its crack_pass_every");
        g.push = particle_rows("/gas/push", 3);
        const auto pass = f.read_doubles("/gas/crack_pass");
        if (pass.size() != 3)
          throw InputError(path, "/gas/crack_pass", "not 3 values", "a checkpoint of this case");
        g.crack_pass_countdown = static_cast<int>(pass[0]);
        g.crack_pass_done = pass[1] != 0.0;
        g.crack_pass_interval = static_cast<int>(pass[2]);
      }
    }
  }
  // A distributed set-up's global system holds no bonds: each rank's system makes this pass
  // on its particles when the time loop's backend takes it (mpi_backend.cpp).
  if (!s.distributed_rows.empty()) {
    s.derived_fields_pending = true;
    return;
  }
  // Derived per-particle fields (damage, energy) at the restored state; no bond can break
  // here because the stretches are those already checked at the checkpointed step.
  // With a rate law the bond state is kept as checkpointed (CheckpointedPassState says why).
  CheckpointedPassState checkpointed(s);
  cpu_compute_forces(s);
  checkpointed.restore(s);
}

}  // namespace breccia::solver
