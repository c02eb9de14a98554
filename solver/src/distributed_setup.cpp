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

FamilySlice file_block(int64_t n, int rank, int ranks) { return family_slice(n, rank, ranks); }

BoundingBox body_bounding_box(const DistributedSetup& d, std::span<const double> block_positions) {
  const BoundingBox mine = bounding_box(block_positions);
  const std::vector<BoundingBox> boxes = concat_over_ranks(d, std::vector<BoundingBox>{mine});
  // The blocks in rank order are the file's rows in order, and std::min and std::max keep the
  // first of equal values: the fold of the blocks' folds is the fold over the file, bit for bit.
  BoundingBox b{{1e300, 1e300, 1e300}, {-1e300, -1e300, -1e300}};
  for (const BoundingBox& r : boxes)
    for (int c = 0; c < 3; ++c) {
      b.lo[c] = std::min(b.lo[c], r.lo[c]);
      b.hi[c] = std::max(b.hi[c], r.hi[c]);
    }
  return b;
}

namespace {

bool item_less(const MortonItem& a, const MortonItem& b) { return a.key < b.key || (a.key == b.key && a.file < b.file); }

// A double's place in the order of doubles as an unsigned integer (negative ones reversed).
uint64_t ordered_bits(double v) {
  uint64_t u;
  std::memcpy(&u, &v, sizeof u);
  return u >> 63 ? ~u : u | (uint64_t{1} << 63);
}
double from_ordered_bits(uint64_t u) {
  u = u >> 63 ? u & ~(uint64_t{1} << 63) : ~u;
  double v;
  std::memcpy(&v, &u, sizeof v);
  return v;
}

int64_t sum_over_ranks(const DistributedSetup& d, int64_t mine) {
  int64_t sum = 0;
  for (const int64_t v : concat_over_ranks(d, std::vector<int64_t>{mine})) sum += v;
  return sum;
}

}  // namespace

MortonBlock distributed_morton_sort(const DistributedSetup& d, std::vector<MortonItem> mine) {
  std::sort(mine.begin(), mine.end(), item_less);  // (key, file) pairs are distinct: a total order
  const size_t ranks = static_cast<size_t>(d.ranks), m = mine.size();
  // Regular samples: ranks - 1 from each rank's sorted items, then ranks - 1 splitters evenly
  // among all samples; rank r receives the items above splitter r - 1 up to splitter r.
  std::vector<MortonItem> samples;
  if (m > 0)
    for (size_t j = 1; j < ranks; ++j) samples.push_back(mine[j * m / ranks]);
  samples = concat_over_ranks(d, samples);
  std::sort(samples.begin(), samples.end(), item_less);
  std::vector<int64_t> counts(ranks, 0);
  size_t at = 0;
  for (size_t r = 0; r < ranks; ++r) {
    size_t end = m;
    if (r + 1 < ranks && !samples.empty()) {
      const MortonItem& split = samples[(r + 1) * samples.size() / ranks];
      end = static_cast<size_t>(std::upper_bound(mine.begin() + static_cast<int64_t>(at), mine.end(), split, item_less) - mine.begin());
    }
    counts[r] = static_cast<int64_t>(end - at);
    at = end;
  }
  std::vector<int64_t> received;
  const std::vector<char> in = d.exchange(mine.data(), counts, sizeof(MortonItem), received);
  std::vector<MortonItem>().swap(mine);
  MortonBlock b;
  b.items.resize(in.size() / sizeof(MortonItem));
  if (!in.empty()) std::memcpy(static_cast<void*>(b.items.data()), in.data(), in.size());
  std::sort(b.items.begin(), b.items.end(), item_less);  // the ranks' sorted runs, merged
  const std::vector<int64_t> held = concat_over_ranks(d, std::vector<int64_t>{static_cast<int64_t>(b.items.size())});
  for (int r = 0; r < d.ranks; ++r) {
    if (r < d.rank) b.first += held[static_cast<size_t>(r)];
    b.n += held[static_cast<size_t>(r)];
  }
  return b;
}

RankRun move_run(const DistributedSetup& d, RankRun run, const std::vector<int64_t>& begin) {
  std::vector<int64_t> counts(static_cast<size_t>(d.ranks), 0);
  for (int r = 0; r < d.ranks; ++r) {
    const int64_t lo = std::max(begin[static_cast<size_t>(r)], run.first),
                  hi = std::min(begin[static_cast<size_t>(r) + 1], run.first + static_cast<int64_t>(run.p.size()));
    counts[static_cast<size_t>(r)] = std::max<int64_t>(0, hi - lo);
  }
  std::vector<int64_t> received;
  const std::vector<char> in = d.exchange(run.p.data(), counts, sizeof(PlanParticle), received);
  RankRun out;
  out.first = begin[static_cast<size_t>(d.rank)];
  out.p.resize(in.size() / sizeof(PlanParticle));
  if (!in.empty()) std::memcpy(static_cast<void*>(out.p.data()), in.data(), in.size());
  if (static_cast<int64_t>(out.p.size()) != begin[static_cast<size_t>(d.rank) + 1] - out.first)
    throw std::logic_error("distributed set-up: the ranks' runs do not cover the body");
  return out;
}

namespace {

struct RunArrays {
  std::vector<double> x0, horizon, half_cell;
};
RunArrays run_arrays(const std::vector<PlanParticle>& p) {
  RunArrays a;
  a.x0.resize(3 * p.size());
  a.horizon.resize(p.size());
  a.half_cell.resize(p.size());
  for (size_t k = 0; k < p.size(); ++k) {
    std::copy_n(p[k].x, 3, &a.x0[3 * k]);
    a.horizon[k] = p[k].horizon;
    a.half_cell[k] = p[k].half_cell;
  }
  return a;
}

// Every rank's value of a trivially copyable T, in rank order.
template <class T>
std::vector<T> each_rank(const DistributedSetup& d, const T& mine) {
  const std::vector<char> bytes = d.concat(&mine, 1, sizeof(T), true);
  std::vector<T> out(bytes.size() / sizeof(T));
  if (!bytes.empty()) std::memcpy(static_cast<void*>(out.data()), bytes.data(), bytes.size());
  return out;
}

}  // namespace

ReachFigures body_reach_figures(const DistributedSetup& d, const RankRun& run, int dimension) {
  const RunArrays a = run_arrays(run.p);
  ReachBounds bounds;  // the runs in rank order are the internal order: the folds are the body's
  for (const ReachBounds& b : each_rank(d, reach_bounds(a.horizon, a.half_cell, dimension))) bounds.fold(b);
  ReachFigures mine(bounds), body(bounds);
  mine.add(a.x0, a.horizon, a.half_cell, dimension);
  for (const ReachFigures& f : each_rank(d, mine)) body.fold(f);
  return body;
}

FormedWindow form_window(const DistributedSetup& d, const RankRun& rows, int dimension, const ReachFigures& body,
                         int64_t body_n) {
  const RunArrays a = run_arrays(rows.p);
  const int64_t m = static_cast<int64_t>(rows.p.size());
  const WindowMarks marks(a.x0, a.horizon, a.half_cell, dimension, body, body_n, 0, m);
  // Every rank's marks, summarised by blocks of cells (MarksSummary: 9 B per 512 cells of
  // its window), to every rank.
  std::vector<MarksSummary> summaries;
  {
    const std::vector<char> mine = marks.summary().bytes();
    const std::vector<int64_t> sizes = concat_over_ranks(d, std::vector<int64_t>{static_cast<int64_t>(mine.size())});
    const std::vector<char> all = d.concat(mine.data(), mine.size(), 1, true);
    size_t at = 0;
    for (const int64_t size : sizes) {
      summaries.push_back(MarksSummary::from_bytes(all.data() + at, static_cast<size_t>(size)));
      at += static_cast<size_t>(size);
    }
  }
  // To each other rank, this run's particles that may be near its rows (in a block its
  // marks reach with their class's bit), with their internal indices.
  struct Candidate {
    int64_t internal;
    PlanParticle p;
  };
  std::vector<Candidate> out;
  std::vector<int64_t> counts(static_cast<size_t>(d.ranks), 0);
  for (int r = 0; r < d.ranks; ++r) {
    if (r == d.rank) continue;
    const size_t at = out.size();
    for (int64_t j = 0; j < m; ++j)
      if (summaries[static_cast<size_t>(r)].may_be_near(rows.p[static_cast<size_t>(j)].x, marks.class_of(j)))
        out.push_back({rows.first + j, rows.p[static_cast<size_t>(j)]});
    counts[static_cast<size_t>(r)] = static_cast<int64_t>(out.size() - at);
  }
  std::vector<int64_t> received;
  const std::vector<char> in = d.exchange(out.data(), counts, sizeof(Candidate), received);
  std::vector<Candidate>().swap(out);
  std::vector<Candidate> got(in.size() / sizeof(Candidate));
  if (!in.empty()) std::memcpy(static_cast<void*>(got.data()), in.data(), in.size());
  // The runs are in rank order: the candidates from lower ranks precede the rows, ascending.
  FormedWindow f;
  auto take = [&](const Candidate& q) {
    const int c = body.class_of(q.p.horizon + partial_volume_reach(q.p.half_cell, dimension));
    if (!marks.near(q.p.x, c)) return;
    f.window.index.push_back(static_cast<int32_t>(q.internal));
    f.p.push_back(q.p);
  };
  size_t q = 0;
  for (; q < got.size() && got[q].internal < rows.first; ++q) take(got[q]);
  f.window.row_begin = static_cast<int64_t>(f.window.index.size());
  for (int64_t j = 0; j < m; ++j) {
    f.window.index.push_back(static_cast<int32_t>(rows.first + j));
    f.p.push_back(rows.p[static_cast<size_t>(j)]);
  }
  f.window.row_end = static_cast<int64_t>(f.window.index.size());
  for (; q < got.size(); ++q) take(got[q]);
  for (size_t k = 1; k < f.window.index.size(); ++k)
    if (f.window.index[k] <= f.window.index[k - 1]) throw std::logic_error("distributed set-up: a formed window is not ascending");
  if (m == 0) return FormedWindow{};  // (geometric_window's for an empty range: empty)
  return f;
}

double distributed_order_statistic(const DistributedSetup& d, const std::vector<double>& mine, int64_t k) {
  // The least t with more than k values at or below it (in ordered_bits) is the k-th value.
  std::vector<uint64_t> bits(mine.size());
  for (size_t i = 0; i < mine.size(); ++i) bits[i] = ordered_bits(mine[i]);
  uint64_t lo = 0, hi = UINT64_MAX;
  while (lo < hi) {
    const uint64_t mid = lo + (hi - lo) / 2;
    int64_t at_or_below = 0;
    for (const uint64_t b : bits) at_or_below += b <= mid;
    if (sum_over_ranks(d, at_or_below) > k) hi = mid;
    else lo = mid + 1;
  }
  return from_ordered_bits(lo);
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

// The partition cut from every rank's slice of the family sizes (its run of the internal
// order, `first` its first row), into `rows`, as MortonRangePartitioner cuts the whole
// offsets: the slices' entries summed over the ranks before each (a prefix over the ranks),
// each rank finds the cuts whose targets fall in its slice (slice_cuts), and every rank
// merges the ranks' cuts; each rank's first entry comes from the slice holding its first
// row. No rank holds an array of the body's size, except rank 0 with a serial HDF5
// (root_keeps_offsets): it gathers the sizes into the whole offsets for its writers (I/O
// staging). Every rank refuses too many ranks alike first.
Partition cut_partition(PdSystem& s, const DistributedSetup& d, const std::vector<int64_t>& slice_sizes, int64_t first,
                        DistributedRows& rows, size_t body_n) {
  try {
    require_ranks_fit(static_cast<int64_t>(body_n), d.ranks);
  } catch (const std::invalid_argument& e) {
    throw InputError(s.config.file, "mpirun -np", e.what(), "at most one rank per particle");
  }
  int64_t mine = 0;
  for (const int64_t v : slice_sizes) mine += v;
  const std::vector<int64_t> slice_entries = concat_over_ranks(d, std::vector<int64_t>{mine});
  const std::vector<int64_t> slice_first = concat_over_ranks(d, std::vector<int64_t>{first});
  int64_t before = 0, entries = 0;
  for (int r = 0; r < d.ranks; ++r) {
    if (r < d.rank) before += slice_entries[static_cast<size_t>(r)];
    entries += slice_entries[static_cast<size_t>(r)];
  }
  const int64_t n = static_cast<int64_t>(body_n);
  if (slice_first[static_cast<size_t>(d.rank)] != first || (d.rank + 1 < d.ranks && slice_first[static_cast<size_t>(d.rank) + 1] != first + static_cast<int64_t>(slice_sizes.size())) ||
      (d.rank + 1 == d.ranks && first + static_cast<int64_t>(slice_sizes.size()) != n))
    throw std::logic_error("distributed set-up: the ranks' family sizes do not cover the particles");
  const MortonRangePartitioner partitioner;
  std::vector<int64_t> cut(static_cast<size_t>(d.ranks), -1);
  {
    const std::vector<int64_t> found = partitioner.slice_cuts(slice_sizes, first, before, n, entries, d.ranks);
    const std::vector<int64_t> all = concat_over_ranks(d, found);
    for (size_t q = 0; q < all.size(); ++q)
      if (all[q] >= 0) cut[q % static_cast<size_t>(d.ranks)] = all[q];
    for (int r = 1; r < d.ranks; ++r)
      if (cut[static_cast<size_t>(r)] < 0) throw std::logic_error("distributed set-up: a cut's target in no slice");
  }
  Partition part = MortonRangePartitioner::from_slice_cuts(cut, n, d.ranks);
  // Each rank's first entry: the slice holding its first row answers (the last rank's end: the total).
  {
    const int64_t m = static_cast<int64_t>(slice_sizes.size()), last = first + m;
    std::vector<int64_t> prefix(slice_sizes.size() + 1, before);
    for (int64_t k = 0; k < m; ++k) prefix[k + 1] = prefix[k] + slice_sizes[static_cast<size_t>(k)];
    std::vector<int64_t> entry(static_cast<size_t>(d.ranks) + 1, -1);
    for (int r = 0; r <= d.ranks; ++r) {
      const int64_t b = part.begin[static_cast<size_t>(r)];
      if ((b >= first && b < last) || (b == n && last == n)) entry[static_cast<size_t>(r)] = prefix[b - first];
    }
    rows.entry_begin.assign(static_cast<size_t>(d.ranks) + 1, -1);
    const std::vector<int64_t> all = concat_over_ranks(d, entry);
    for (size_t q = 0; q < all.size(); ++q)
      if (all[q] >= 0) rows.entry_begin[q % (static_cast<size_t>(d.ranks) + 1)] = all[q];
    for (const int64_t e : rows.entry_begin)
      if (e < 0) throw std::logic_error("distributed set-up: a rank's first row in no slice");
  }
  if (root_keeps_offsets(s.config)) {
    const std::vector<char> bytes = d.concat(slice_sizes.data(), slice_sizes.size(), sizeof(int64_t), false);
    if (d.rank == 0) {
      rows.full_offsets.assign(body_n + 1, 0);
      const int64_t* size = reinterpret_cast<const int64_t*>(bytes.data());
      if (bytes.size() != body_n * sizeof(int64_t))
        throw std::logic_error("distributed set-up: the ranks' family sizes do not cover the particles");
      for (size_t i = 0; i < body_n; ++i) rows.full_offsets[i + 1] = rows.full_offsets[i] + size[i];
    }
  }
  rows.active = true;
  rows.begin = part.begin[d.rank];
  rows.end = part.begin[d.rank + 1];
  s.distributed_rows = part.begin;
  return part;
}

// The partition and the rank's rows' window, planned by every rank from its slice of the
// internal order (family_slice's: the ranks' runs after the Morton sort): the body's reach
// classes, the slice's window (form_window) and its family sizes (family_sizes on the
// window's particles: every partner of the slice), the cut (cut_partition), then the rows'
// window formed from the runs moved to the partition's ranges. Collective.
struct PlannedRows {
  Partition part;
  FormedWindow rows;
};
PlannedRows plan_rows(PdSystem& s, const DistributedSetup& d, RankRun slice, DistributedRows& rows, size_t body_n) {
  const ReachFigures body = body_reach_figures(d, slice, s.dimension);
  std::vector<int64_t> slice_sizes;
  {
    const FormedWindow w = form_window(d, slice, s.dimension, body, static_cast<int64_t>(body_n));
    const RunArrays a = run_arrays(w.p);
    slice_sizes = family_sizes(a.x0, a.horizon, a.half_cell, s.dimension, s.config.partial_volume, w.window.row_begin,
                               w.window.row_end);
  }
  PlannedRows p;
  p.part = cut_partition(s, d, slice_sizes, slice.first, rows, body_n);
  p.rows = form_window(d, move_run(d, std::move(slice), p.part.begin), s.dimension, body, static_cast<int64_t>(body_n));
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

DistributedRows plan_distributed_rows(PdSystem& s, const DistributedSetup& d, RankRun slice) {
  DistributedRows rows;
  rows.end = static_cast<int64_t>(s.n);
  if (!d.active()) return rows;
  if (setup_on_window(d)) throw std::logic_error("plan_distributed_rows: a staged rank 0's (the other ranks: plan_window_system)");
  // The row lengths the set-up will build, counted without a bond stored, and the partition
  // MortonRangePartitioner cuts from them (the one the whole-system set-up's ranks cut):
  // plan_rows, every rank on its slice. The rows' window (every partner of the rows) and how
  // the owners' values reach it (exchange_owned), formed once here for the family build and
  // every pass.
  PlannedRows p = plan_rows(s, d, std::move(slice), rows, s.n);
  rows.window = std::move(p.rows.window);
  rows.exchange = window_exchange(d, p.part.begin, rows.window);
  return rows;
}

DistributedRows plan_window_system(PdSystem& s, const DistributedSetup& d, const ReadFileRows& read,
                                   const ValuesOfRow& values, RankRun slice) {
  if (!setup_on_window(d)) throw std::logic_error("plan_window_system: a distributed set-up's rank on a window");
  DistributedRows rows;
  s.body_n = s.n;
  PlannedRows planned = plan_rows(s, d, std::move(slice), rows, s.body_n);
  const Partition& part = planned.part;
  struct {
    GeometricWindow window;
    std::vector<int64_t> file;
  } p;
  p.window = std::move(planned.rows.window);
  for (const PlanParticle& q : planned.rows.p) p.file.push_back(q.file);
  std::vector<PlanParticle>().swap(planned.rows.p);
  // The window system (as a cut of the whole body would leave it): the rows' window's
  // particles in its order, from their file rows; the particle model holds those rows
  // (ascending) and the facets' mesh cells, its sets their members among them.
  ParticleModel& pm = s.particles;
  read(sorted_unique(p.file), facet_cells(pm), pm);
  s.setup_file_rows = {static_cast<int64_t>(pm.size())};
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
  s.original_index = std::move(p.file);
  s.window_global = p.window.index;
  s.n = w;
  rows.window = std::move(p.window);
  rows.windowed = true;
  rows.exchange = window_exchange(d, part.begin, rows.window);
  return rows;
}

std::vector<int64_t> facet_cells(const ParticleModel& m) {
  std::vector<int64_t> cells;
  if (m.nodes_per_cell > 0)
    for (const SurfaceFacets& sf : m.surfaces) cells.insert(cells.end(), sf.particle.begin(), sf.particle.end());
  return sorted_unique(std::move(cells));
}

bool setup_on_window(const DistributedSetup& d) { return d.active() && !(d.rank == 0 && root_stages_whole_body()); }

void refuse_together(const DistributedSetup& d, std::exception_ptr mine) {
  std::string record;  // file, field, message, each ended by a NUL; empty: no refusal
  std::exception_ptr other;
  if (mine) try {
      std::rethrow_exception(mine);
    } catch (const InputError& e) {
      for (const std::string* part : {&e.file(), &e.field()}) record += *part + '\0';
      record += std::string(e.what()) + '\0';
    } catch (...) {
      other = std::current_exception();
    }
  if (!d.active()) {
    if (mine) std::rethrow_exception(mine);
    return;
  }
  const std::vector<int64_t> sizes = concat_over_ranks(d, std::vector<int64_t>{static_cast<int64_t>(record.size())});
  const std::vector<char> all = concat_over_ranks(d, std::vector<char>(record.begin(), record.end()));
  if (other) std::rethrow_exception(other);
  size_t at = 0;
  for (const int64_t n : sizes) {
    if (n > 0) {
      std::vector<std::string> part;
      for (size_t q = at, begin = at; q < at + static_cast<size_t>(n); ++q)
        if (all[q] == '\0') {
          part.emplace_back(all.begin() + static_cast<int64_t>(begin), all.begin() + static_cast<int64_t>(q));
          begin = q + 1;
        }
      if (part.size() != 3) throw std::logic_error("refuse_together: a refusal's record");
      throw InputError::composed(part[0], part[1], part[2]);
    }
    at += static_cast<size_t>(n);
  }
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
  // The row offsets kept for the run: rank 0 the whole system's with a serial HDF5 (its
  // writers' staging, root_keeps_offsets), the other ranks none (their rows' are their systems'): each rank's entry range and the total
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
