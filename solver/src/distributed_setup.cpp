#include "breccia/solver/distributed_setup.hpp"

#include <algorithm>
#include <optional>
#include <iterator>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "breccia/common/error.hpp"

namespace breccia::solver {

FamilySlice family_slice(int64_t n, int rank, int ranks) {
  if (ranks < 1 || rank < 0 || rank >= ranks || n < 0) throw std::invalid_argument("family_slice: rank in [0, ranks)");
  return {n * rank / ranks, n * (rank + 1) / ranks};
}

namespace {

// The window's particles' positions, horizons and one more per-particle array, in its order.
struct WindowArrays {
  std::vector<double> x0, horizon, other;
};
WindowArrays window_arrays(const PdSystem& s, const GeometricWindow& w, const std::vector<double>& other) {
  WindowArrays a;
  a.x0.resize(3 * w.index.size());
  a.horizon.resize(w.index.size());
  a.other.resize(w.index.size());
  for (size_t k = 0; k < w.index.size(); ++k) {
    const size_t i = static_cast<size_t>(w.index[k]);
    for (int c = 0; c < 3; ++c) a.x0[3 * k + c] = s.x0[3 * i + c];
    a.horizon[k] = s.horizon[i];
    a.other[k] = other[i];
  }
  return a;
}

}  // namespace

Families build_own_families(const PdSystem& s, const DistributedRows& rows, const std::vector<double>& pad,
                            int64_t* window_particles) {
  if (!rows.active) {
    if (window_particles) *window_particles = static_cast<int64_t>(s.n);
    return build_families(s.x0, s.horizon, pad);
  }
  if (rows.windowed) {  // the system is the window (plan_window_system): its rows, local partners kept
    if (window_particles) *window_particles = static_cast<int64_t>(s.n);
    return build_families(s.x0, s.horizon, pad, rows.window.row_begin, rows.window.row_end);
  }
  // The window plan_distributed_rows formed (its exchange's); a hand-made `rows` without one: formed here.
  GeometricWindow formed;
  const bool given = !rows.window.index.empty() || rows.end == rows.begin;
  if (!given) formed = geometric_window(s.x0, s.horizon, s.half_cell, s.dimension, rows.begin, rows.end);
  const GeometricWindow& w = given ? rows.window : formed;
  if (window_particles) *window_particles = static_cast<int64_t>(w.index.size());
  Families fam;
  {
    const WindowArrays a = window_arrays(s, w, pad);
    fam = build_families(a.x0, a.horizon, a.other, w.row_begin, w.row_end);
  }
  // Back to the whole system's indices: the rows outside the window's own range are empty,
  // and the window's order is the global one (ascending), so each row stays sorted.
  for (int32_t& j : fam.neighbors) j = w.index[static_cast<size_t>(j)];
  const int64_t entries = fam.offsets.back();
  std::vector<int64_t> offsets(s.n + 1, 0);
  for (int64_t i = rows.begin; i < rows.end; ++i) offsets[i + 1] = fam.offsets[w.row_begin + (i - rows.begin) + 1];
  for (size_t i = static_cast<size_t>(rows.end); i < s.n; ++i) offsets[i + 1] = entries;
  fam.offsets.swap(offsets);
  return fam;
}

namespace {

// The partition cut from every rank's slice of the family sizes, into `rows`: rank 0 receives
// the slices (concatenated in rank order: the whole system's offsets, which it keeps), cuts
// and sends every rank the cut and each rank's first entry (2 (ranks + 1) values): no other
// rank holds an array of the body's size. Every rank refuses too many ranks alike first.
Partition cut_partition(PdSystem& s, const DistributedSetup& d, const std::vector<int64_t>& slice_sizes,
                        DistributedRows& rows, size_t body_n) {
  try {
    require_ranks_fit(static_cast<int64_t>(body_n), d.ranks);
  } catch (const std::invalid_argument& e) {
    throw InputError(s.config.file, "mpirun -np", e.what(), "at most one rank per particle");
  }
  const std::vector<char> bytes = d.concat(slice_sizes.data(), slice_sizes.size(), sizeof(int64_t), false);
  std::vector<int64_t> cut;  // rank 0's: part.begin, then each rank's first entry and the total
  if (d.rank == 0) {
    std::vector<int64_t> sizes(bytes.size() / sizeof(int64_t));
    if (!bytes.empty()) std::memcpy(sizes.data(), bytes.data(), bytes.size());
    if (sizes.size() != body_n)
      throw std::logic_error("distributed set-up: the ranks' family sizes do not cover the particles");
    rows.full_offsets.assign(sizes.size() + 1, 0);
    for (size_t i = 0; i < sizes.size(); ++i) rows.full_offsets[i + 1] = rows.full_offsets[i] + sizes[i];
    cut = MortonRangePartitioner().partition(rows.full_offsets, d.ranks).begin;
    for (int r = 0; r <= d.ranks; ++r) cut.push_back(rows.full_offsets[cut[r]]);
  }
  cut = concat_over_ranks(d, cut);
  if (cut.size() != 2 * static_cast<size_t>(d.ranks + 1))
    throw std::logic_error("distributed set-up: rank 0's partition is malformed");
  Partition part;
  part.begin.assign(cut.begin(), cut.begin() + d.ranks + 1);
  rows.entry_begin.assign(cut.begin() + d.ranks + 1, cut.end());
  rows.active = true;
  rows.begin = part.begin[d.rank];
  rows.end = part.begin[d.rank + 1];
  s.distributed_rows = part.begin;
  return part;
}

// A window and its particles' file rows (in the window's order), as rank 0 sends them.
struct PlannedWindow {
  GeometricWindow window;
  std::vector<int64_t> file;
};

// Rank 0 (the whole body): each other rank r's geometric window of the rows [begin[r],
// begin[r + 1]) with its particles' file rows, sent to r; the other ranks: theirs, received.
// Collective (one all-to-all from rank 0). Message: row_begin, row_end, m, m indices, m rows.
PlannedWindow scatter_windows(const PdSystem& s, const DistributedSetup& d, const std::vector<int64_t>& begin) {
  std::vector<int64_t> out, counts(static_cast<size_t>(d.ranks), 0);
  if (d.rank == 0)
    for (int r = 1; r < d.ranks; ++r) {
      const GeometricWindow w = geometric_window(s.x0, s.horizon, s.half_cell, s.dimension, begin[r], begin[r + 1]);
      const size_t at = out.size();
      out.push_back(w.row_begin);
      out.push_back(w.row_end);
      out.push_back(static_cast<int64_t>(w.index.size()));
      out.insert(out.end(), w.index.begin(), w.index.end());
      for (const int32_t i : w.index) out.push_back(s.original_index[static_cast<size_t>(i)]);
      counts[static_cast<size_t>(r)] = static_cast<int64_t>(out.size() - at);
    }
  std::vector<int64_t> received;
  const std::vector<char> in = d.exchange(out.data(), counts, sizeof(int64_t), received);
  PlannedWindow p;
  if (d.rank == 0) return p;
  std::vector<int64_t> msg(in.size() / sizeof(int64_t));
  if (!in.empty()) std::memcpy(msg.data(), in.data(), in.size());
  if (msg.size() < 3 || msg.size() != 3 + 2 * static_cast<size_t>(msg[2]))
    throw std::logic_error("distributed set-up: a planned window from rank 0 is malformed");
  const size_t m = static_cast<size_t>(msg[2]);
  p.window.row_begin = msg[0];
  p.window.row_end = msg[1];
  p.window.index.assign(msg.begin() + 3, msg.begin() + 3 + static_cast<int64_t>(m));
  p.file.assign(msg.begin() + 3 + static_cast<int64_t>(m), msg.end());
  return p;
}

std::vector<int64_t> sorted_unique(std::vector<int64_t> v) {
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
  return v;
}

// The position of file row f among `held` (ascending).
size_t held_at(const std::vector<int64_t>& held, int64_t f) {
  const std::optional<size_t> at = held_position(held, f);
  if (!at) throw std::logic_error("distributed set-up: a planned file row was not read");
  return *at;
}

}  // namespace

DistributedRows plan_distributed_rows(PdSystem& s, const DistributedSetup& d) {
  DistributedRows rows;
  rows.end = static_cast<int64_t>(s.n);
  if (!d.active()) return rows;
  if (d.rank != 0) throw std::logic_error("plan_distributed_rows: rank 0's (the other ranks: plan_window_system)");
  // The row lengths the set-up will build, counted without a bond stored: the whole
  // system's offsets and the partition MortonRangePartitioner cuts from them (the one the
  // whole-system set-up's ranks cut). Each rank counts an equal slice of the particles
  // (family_slice) and the slices are concatenated in rank order: the same integers as
  // one count of every particle, so the same partition.
  // The slice's partners are all in its geometric window (geometric_window), so the count
  // runs on the window's particles alone (its cell list too): the same integers. Rank 0
  // forms every rank's window (the others hold no whole array: plan_window_system).
  std::vector<int64_t> slice_begin;
  for (int r = 0; r <= d.ranks; ++r)
    slice_begin.push_back(r == d.ranks ? static_cast<int64_t>(s.n) : family_slice(static_cast<int64_t>(s.n), r, d.ranks).begin);
  scatter_windows(s, d, slice_begin);
  std::vector<int64_t> slice_sizes;
  {
    const GeometricWindow w = geometric_window(s.x0, s.horizon, s.half_cell, s.dimension, slice_begin[0], slice_begin[1]);
    const WindowArrays a = window_arrays(s, w, s.half_cell);
    slice_sizes = family_sizes(a.x0, a.horizon, a.other, s.dimension, s.config.partial_volume, w.row_begin, w.row_end);
  }
  const Partition part = cut_partition(s, d, slice_sizes, rows, s.n);
  scatter_windows(s, d, part.begin);
  // The rows' window (every partner of the rows: geometric_window) and how the owners'
  // values reach it (exchange_owned), formed once here for the family build and every pass.
  rows.window = geometric_window(s.x0, s.horizon, s.half_cell, s.dimension, rows.begin, rows.end);
  rows.exchange = window_exchange(d, part.begin, rows.window);
  return rows;
}

DistributedRows plan_window_system(PdSystem& s, const DistributedSetup& d, const ReadFileRows& read,
                                   const ValuesOfRow& values) {
  if (!setup_on_window(d)) throw std::logic_error("plan_window_system: a rank other than 0 of a distributed set-up");
  DistributedRows rows;
  s.body_n = s.n;
  // The family sizes of this rank's slice, on the slice's window as rank 0 formed it: its
  // particles' file rows read, their positions, horizons and cells in the window's order.
  std::vector<int64_t> slice_sizes;
  {
    const PlannedWindow p = scatter_windows(s, d, {});
    ParticleModel m;
    const std::vector<int64_t> held = sorted_unique(p.file);
    read(held, {}, m);
    s.setup_file_rows = {static_cast<int64_t>(held.size())};
    const size_t w = p.file.size();
    std::vector<double> x0(3 * w), horizon(w), half_cell(w);
    for (size_t k = 0; k < w; ++k) {
      const size_t r = held_at(held, p.file[k]);
      for (int c = 0; c < 3; ++c) x0[3 * k + c] = m.position_m[3 * r + c];
      const RowValues v = values(m, r);
      horizon[k] = v.horizon;
      half_cell[k] = v.half_cell;
    }
    slice_sizes = family_sizes(x0, horizon, half_cell, s.dimension, s.config.partial_volume, p.window.row_begin,
                               p.window.row_end);
  }
  const Partition part = cut_partition(s, d, slice_sizes, rows, s.body_n);
  // The window system (as a cut of the whole body would leave it): the rows' window's
  // particles in its order, from their file rows; the particle model holds those rows
  // (ascending) and the facets' mesh cells, its sets their members among them.
  PlannedWindow p = scatter_windows(s, d, part.begin);
  ParticleModel& pm = s.particles;
  std::vector<int64_t> cells;
  if (pm.nodes_per_cell > 0)
    for (const SurfaceFacets& sf : pm.surfaces) cells.insert(cells.end(), sf.particle.begin(), sf.particle.end());
  read(sorted_unique(p.file), sorted_unique(std::move(cells)), pm);
  s.setup_file_rows[0] = std::max<int64_t>(s.setup_file_rows[0], static_cast<int64_t>(pm.size()));
  const size_t w = p.file.size();
  s.x0.resize(3 * w);
  s.volume.resize(w);
  s.density.resize(w);
  s.material.resize(w);
  s.half_cell.resize(w);
  s.horizon.resize(w);
  for (size_t k = 0; k < w; ++k) {
    const size_t r = held_at(pm.held_rows, p.file[k]);
    for (int c = 0; c < 3; ++c) s.x0[3 * k + c] = pm.position_m[3 * r + c];
    s.volume[k] = pm.volume_m3[r];
    const RowValues v = values(pm, r);
    s.material[k] = v.material;
    s.density[k] = v.density;
    s.half_cell[k] = v.half_cell;
    s.horizon[k] = v.horizon;
  }
  for (ParticleSet& set : pm.sets) {
    std::vector<int64_t> held;
    std::set_intersection(set.indices.begin(), set.indices.end(), pm.held_rows.begin(), pm.held_rows.end(),
                          std::back_inserter(held));
    if (set.whole_count < 0) set.whole_count = static_cast<int64_t>(set.indices.size());
    set.indices.swap(held);
  }
  s.original_index = std::move(p.file);
  s.window_global = p.window.index;
  s.n = w;
  rows.window = std::move(p.window);
  rows.windowed = true;
  rows.exchange = window_exchange(d, part.begin, rows.window);
  return rows;
}

bool setup_on_window(const DistributedSetup& d) { return d.active() && d.rank != 0; }

namespace {

struct Bytes {
  std::vector<char> b;
  template <class T>
  void put(const T& v) {
    const char* p = reinterpret_cast<const char*>(&v);
    b.insert(b.end(), p, p + sizeof(T));
  }
  template <class T>
  void put(const std::vector<T>& v) {
    put<uint64_t>(v.size());
    const char* p = reinterpret_cast<const char*>(v.data());
    b.insert(b.end(), p, p + v.size() * sizeof(T));
  }
  void put(const std::string& v) { put(std::vector<char>(v.begin(), v.end())); }
};

struct Reader {
  const std::vector<char>& b;
  size_t at = 0;
  void take(void* out, size_t bytes) {
    if (at + bytes > b.size()) throw std::logic_error("distributed set-up: rank 0's body plan is short");
    if (bytes) std::memcpy(out, b.data() + at, bytes);
    at += bytes;
  }
  template <class T>
  void get(T& v) { take(&v, sizeof(T)); }
  template <class T>
  void get(std::vector<T>& v) {
    uint64_t m = 0;
    get(m);
    v.resize(m);
    take(v.data(), m * sizeof(T));
  }
  void get(std::string& v) {
    std::vector<char> c;
    get(c);
    v.assign(c.begin(), c.end());
  }
};

template <class Io, class Plan>
void body_plan_fields(Io& io, Plan& p) {
  // (one list of the fields for both ways)
  io(p.refused, p.n, p.fill_horizon, p.one_horizon, p.uniform, p.max_horizon, p.max_half_cell, p.median_horizon,
     p.median_half_cell, p.f32_origin, p.graded_refused, p.graded_message, p.content_id, p.set_sizes, p.known_file,
     p.known_internal);
}

}  // namespace

void send_body_plan(const DistributedSetup& d, const BodyPlan& p) {
  if (d.rank != 0) throw std::logic_error("send_body_plan: rank 0's");
  Bytes out;
  auto io = [&](const auto&... v) { (out.put(v), ...); };
  body_plan_fields(io, p);
  out.put<uint64_t>(p.layers.size());
  for (const BodyPlan::Layer& l : p.layers) io(l.taken, l.refused, l.message, l.layer.depth, l.layer.volume, l.layer.particles);
  d.concat(out.b.data(), out.b.size(), 1, true);
}

BodyPlan receive_body_plan(const DistributedSetup& d) {
  if (d.rank == 0) throw std::logic_error("receive_body_plan: the ranks other than 0");
  const std::vector<char> in = d.concat(nullptr, 0, 1, true);
  Reader r{in};
  BodyPlan p;
  auto io = [&](auto&... v) { (r.get(v), ...); };
  body_plan_fields(io, p);
  uint64_t layers = 0;
  r.get(layers);
  p.layers.resize(layers);
  for (BodyPlan::Layer& l : p.layers) io(l.taken, l.refused, l.message, l.layer.depth, l.layer.volume, l.layer.particles);
  if (r.at != in.size()) throw std::logic_error("distributed set-up: rank 0's body plan is long");
  return p;
}


std::vector<int64_t> count_by_owner(const std::vector<int64_t>& part_begin, const std::vector<int32_t>& halo) {
  if (part_begin.size() < 2) throw std::invalid_argument("count_by_owner: a partition of at least one rank");
  std::vector<int64_t> counts(part_begin.size() - 1, 0);
  size_t r = 0;
  for (size_t q = 0; q < halo.size(); ++q) {
    if (q > 0 && halo[q] <= halo[q - 1]) throw std::invalid_argument("count_by_owner: a halo not ascending");
    while (r + 1 < part_begin.size() && halo[q] >= part_begin[r + 1]) ++r;
    if (r + 1 == part_begin.size() || halo[q] < part_begin[r]) throw std::invalid_argument("count_by_owner: a particle outside the partition");
    ++counts[r];
  }
  return counts;
}

WindowExchange window_exchange(const DistributedSetup& d, const std::vector<int64_t>& part_begin,
                               const GeometricWindow& w) {
  WindowExchange x;
  x.halo.reserve(w.halo());
  x.halo.insert(x.halo.end(), w.index.begin(), w.index.begin() + w.row_begin);
  x.halo.insert(x.halo.end(), w.index.begin() + w.row_end, w.index.end());
  x.halo_counts = count_by_owner(part_begin, x.halo);
  if (x.halo_counts[static_cast<size_t>(d.rank)] != 0)
    throw std::logic_error("distributed set-up: a window's halo holds one of the rank's own rows");
  // Each owner is told which of its particles this window holds: those it sends here.
  const std::vector<char> asked = d.exchange(x.halo.data(), x.halo_counts, sizeof(int32_t), x.send_counts);
  x.send.resize(asked.size() / sizeof(int32_t));
  if (!asked.empty()) std::memcpy(x.send.data(), asked.data(), asked.size());
  const int64_t begin = part_begin[static_cast<size_t>(d.rank)], end = part_begin[static_cast<size_t>(d.rank) + 1];
  for (const int32_t i : x.send)
    if (i < begin || i >= end) throw std::logic_error("distributed set-up: a rank asked for a particle it does not own");
  return x;
}

void require_partners_in_window(const DistributedRows& rows, const std::vector<int64_t>& offsets,
                                const std::vector<int32_t>& neighbor) {
  if (!rows.active || rows.end == rows.begin) return;
  if (rows.windowed) {  // a window system's partners are local indices: each must be one of its particles
    const int64_t held = static_cast<int64_t>(rows.window.index.size());
    for (int64_t i = rows.window.row_begin; i < rows.window.row_end; ++i)
      for (int64_t k = offsets[i]; k < offsets[i + 1]; ++k)
        if (neighbor[k] < 0 || neighbor[k] >= held)
          throw std::logic_error("distributed set-up: a partner of local row " + std::to_string(i) +
                                 " is outside the rank's window system (" + std::to_string(held) + " particles)");
    return;
  }
  // The window's particles as bits over its span of global indices (at most N / 8 bytes, for
  // the check alone): one test per entry, not a search.
  const std::vector<int32_t>& index = rows.window.index;  // ascending
  const int64_t first = index.empty() ? 0 : index.front(), span = index.empty() ? 0 : index.back() - first + 1;
  std::vector<uint64_t> held(static_cast<size_t>((span + 63) / 64), 0);
  for (const int32_t j : index) held[static_cast<size_t>((j - first) / 64)] |= uint64_t{1} << ((j - first) % 64);
  auto in_window = [&](int64_t j) {
    return j >= first && j - first < span && (held[static_cast<size_t>((j - first) / 64)] >> ((j - first) % 64) & 1u);
  };
  for (int64_t i = rows.begin; i < rows.end; ++i)
    for (int64_t k = offsets[i]; k < offsets[i + 1]; ++k)
      if (!in_window(neighbor[k]))
        throw std::logic_error("distributed set-up: particle " + std::to_string(neighbor[k]) + ", a partner of row " +
                               std::to_string(i) + ", is outside the rank's geometric window (" +
                               std::to_string(index.size()) + " particles): its owner's values would not reach it");
}

namespace {

// Every rank's entries of a per-entry array (its rows are one run of the whole system's
// entries, in rank order), on every rank or on rank 0 only.
template <class T, class A>
void gather_entries(const DistributedSetup& d, std::vector<T, A>& a, bool everyone) {
  std::vector<char> bytes = d.concat(a.data(), a.size(), sizeof(T), everyone);
  std::vector<T, A> whole(bytes.size() / sizeof(T));
  if (!bytes.empty()) std::memcpy(static_cast<void*>(whole.data()), bytes.data(), bytes.size());
  a.swap(whole);
}

}  // namespace

MaterialSums sum_marked_by_material(const DistributedSetup& d, const DistributedRows& rows,
                                    const std::vector<uint8_t>& marked, const std::vector<int32_t>& material,
                                    const std::vector<double>& values, int dims, size_t materials) {
  std::vector<int32_t> which;  // the marked particles' materials and values, in index order
  std::vector<double> value;
  for (size_t i = 0; i < marked.size(); ++i)
    if (marked[i]) {
      which.push_back(material[i]);
      value.insert(value.end(), &values[3 * i], &values[3 * i] + 3);
    }
  if (rows.active) {
    which = concat_over_ranks(d, which);
    value = concat_over_ranks(d, value);
  }
  MaterialSums out{std::vector<double>(materials, 0.0), std::vector<int>(materials, 0)};
  for (size_t q = 0; q < which.size(); ++q)
    for (int a = 0; a < dims; ++a) {
      out.sum[which[q]] += value[3 * q + a];
      ++out.count[which[q]];
    }
  return out;
}

void finish_distributed_setup(PdSystem& s, const DistributedRows& rows, const DistributedSetup& d) {
  if (!rows.active) return;
  const size_t own_entries = s.state.size();
  const size_t setup_offsets = s.offsets.size();
  if (s.offsets.back() != static_cast<int64_t>(own_entries) ||
      rows.entry_begin[d.rank + 1] - rows.entry_begin[d.rank] != static_cast<int64_t>(own_entries))
    throw std::logic_error("distributed set-up: a rank's rows differ from the counted family sizes");
  // What each rank's set-up built, to every rank (summary.json): its own rows' entries alone.
  s.setup_candidate_entries = concat_over_ranks(d, s.setup_candidate_entries);
  s.setup_kept_entries = concat_over_ranks(d, s.setup_kept_entries);
  s.setup_window_particles = concat_over_ranks(d, s.setup_window_particles);
  s.setup_system_particles = concat_over_ranks(d, s.setup_system_particles);
  s.setup_file_rows = concat_over_ranks(d, s.setup_file_rows);
  // Rank 0's writers read the bond list of results.h5 (partners, and which halves exist),
  // where it writes the files alone (serial HDF5).
  const bool writer_bonds = root_gathers_bond_list(s.config);
  // The force pass that ended the stable-step estimate filled the fields of this rank's
  // particles in the rank's system (the owners' values, which the first output writes: a
  // pre-crack's damage; LPS's dilatation and the fast path's two factors, correspondence's
  // deformation gradient, force tensor and non-affine energy: kForcePassFields) and the
  // forces; its ghosts took their owners' values there, and rank 0 gathered them whole into
  // this system for its writers (mpi_stable_step_forces): the other ranks hold none here.
  {
    const std::vector<double> all = concat_over_ranks(d, std::vector<double>{s.dissipated_energy});
    double sum = 0.0;  // bonds broken by that pass: in rank order (one process sums in its own)
    for (const double v : all) sum += v;
    s.dissipated_energy = sum;
  }
  // Collective: every rank takes the same branches (the case decides them, not the rank).
  // The bond states to rank 0 alone (for_each_bond_state_array): the other ranks' own rows are
  // in their systems already, the same bits (the estimate's last pass copied them here from
  // there). A rate law's onsets are state (restrict_to_rank_taking_bonds left the rank's own
  // here); so are a gas load's entered cracks (checkpoint.h5's /gas/in_crack), whose
  // `halves` moved into the rank's system with the bonds (set-up only).
  // With parallel HDF5 no writer reads them whole (each rank writes its rows and forms its
  // part of the broken bits: mpi_backend.cpp), so they are let go on every rank.
#ifdef BRECCIA_PARALLEL_HDF5
  const bool staged = false;
  for_each_bond_state_array(s, [](auto& a) { std::remove_reference_t<decltype(a)>().swap(a); });
#else
  const bool staged = d.rank == 0;
  for_each_bond_state_array(s, [&](auto& a) { gather_entries(d, a, false); });
#endif
  // The stable-step estimate cut the rank's system and took the coefficients with it
  // (restrict_to_rank_taking_bonds): without that hook the ranks would have no bonds.
  if (!s.xi_len.empty())
    throw std::logic_error("distributed set-up without the stable-step hook that cuts the rank's system");
  if (writer_bonds) {
    // A window system's partners are its local indices: rank 0's list holds internal ones.
    if (!s.window_global.empty())
      for (int32_t& j : s.neighbor) j = s.window_global[static_cast<size_t>(j)];
    gather_entries(d, s.neighbor, false);
    gather_entries(d, s.vol_own, false);    // empty where the own counts serve (pd_system.hpp)
    gather_entries(d, s.own_count, false);  // empty with the analytic partial volume
    // Shared dual halves (pd_system.hpp k_dual_halves): the own moduli, which the rank kept here.
    gather_entries(d, s.dual_halves_shared ? s.k_own : s.k_dual, false);
  }
  // The row offsets kept for the run: rank 0 the whole system's (its writers' staging), the
  // other ranks none (their rows' are their systems'): each rank's entry range and the total
  // are s.distributed_entries (bond_count).
  s.offsets = rows.full_offsets;
  s.distributed_entries = rows.entry_begin;
  // The longest row offsets this rank held from the cut on (summary.json): the set-up
  // system's (its rows' window on the ranks other than 0), the cut's, the kept ones.
  s.setup_offsets_rows = concat_over_ranks(
      d, std::vector<int64_t>{static_cast<int64_t>(std::max({setup_offsets, rows.full_offsets.size(), s.offsets.size()}))});
  for_each_bond_state_array(s, [&](auto& a) {
    if (a.size() != (staged ? s.bond_count() : 0)) throw std::logic_error("distributed set-up: the gathered bond states");
  });
}

}  // namespace breccia::solver
