#include "breccia/common/families.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

#include "breccia/common/cell_list.hpp"
#include "breccia/common/family_build.hpp"
#include "breccia/common/huge_pages.hpp"

#if defined(_OPENMP)
#include <omp.h>
#endif

namespace breccia {

namespace {

// The grids' binning on the host: one thread. Its passes are O(N) and short (about 10 ms of
// the 0.5 s build on the 41^3 lattice); the 6 passes per grid each as a parallel region cost
// more than they save where the machine is shared (threads waiting at every region's end:
// the concrete demo's families took 0.53 -> 0.84 CPU s on 2 threads with load 10).
struct SerialFamilyExec {
  template <class F>
  void for_each(int64_t n, const F& f, const char* /*name*/) const {
    for (int64_t i = 0; i < n; ++i) f(i);
  }
};

// A uniform lattice (every horizon and every pad the same, every point within 1e-6 spacings of
// lo + k * spacing, at most one point per lattice site): its rows come from the integer
// offsets within reach and the lattice-to-index map instead of a cell search (the 41^3 bench's
// families: 0.68 CPU s, most of it candidates of 125 cells per row, 3.7 per partner). The
// partners are decided by the same test on the same bits (family::within_reach), and the
// offsets cover every j that can pass it: a point lies within 1e-6 spacings per axis of its
// site, so |x_j - x_i| >= |o| spacing - 4e-6 spacing, and the table keeps every o with |o|
// spacing <= reach + 0.01 spacing. Each row is sorted as the cell search's is, so the rows
// are the same entry for entry (tests/solver/test_family_build.cpp).
struct LatticeRows {
  double spacing = 0.0;
  long long count[3] = {1, 1, 1};
  std::vector<int32_t> site_of;       // 3N: each point's lattice site
  std::vector<int32_t> point_at;      // count[0] count[1] count[2]: the point at a site, -1 none
  std::vector<int32_t> offsets;       // 3 per offset within reach (0 excluded)
};

std::optional<LatticeRows> lattice_rows(std::span<const double> x, std::span<const double> horizon,
                                        std::span<const double> pad) {
  const size_t n = horizon.size();
  if (n < 2 || n > static_cast<size_t>(INT32_MAX)) return std::nullopt;
  for (size_t i = 1; i < n; ++i)
    if (horizon[i] != horizon[0] || (!pad.empty() && pad[i] != pad[0])) return std::nullopt;
  const BoundingBox box = bounding_box(x);
  double spacing = std::numeric_limits<double>::infinity();  // the smallest step from the box's low corner
  for (size_t i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d) {
      const double step = x[3 * i + d] - box.lo[d];
      if (step > 0.0) spacing = std::min(spacing, step);
    }
  if (!std::isfinite(spacing)) return std::nullopt;
  LatticeRows l;
  l.spacing = spacing;
  double sites = 1.0;
  for (int d = 0; d < 3; ++d) {
    const double extent = std::nearbyint((box.hi[d] - box.lo[d]) / spacing);
    if (!(extent < 1e6)) return std::nullopt;
    l.count[d] = static_cast<long long>(extent) + 1;
    sites *= static_cast<double>(l.count[d]);
  }
  if (sites > std::max(8.0 * static_cast<double>(n), 65536.0)) return std::nullopt;
  l.site_of.resize(3 * n);
  l.point_at.assign(static_cast<size_t>(sites), -1);
  const double tolerance = 1e-6 * spacing;
  for (size_t i = 0; i < n; ++i) {
    long long k[3];
    for (int d = 0; d < 3; ++d) {
      const double v = x[3 * i + d] - box.lo[d];
      const double r = std::nearbyint(v / spacing);
      if (!(std::fabs(v - r * spacing) <= tolerance)) return std::nullopt;
      k[d] = static_cast<long long>(r);
      l.site_of[3 * i + d] = static_cast<int32_t>(k[d]);
    }
    int32_t& at = l.point_at[static_cast<size_t>((k[2] * l.count[1] + k[1]) * l.count[0] + k[0])];
    if (at >= 0) return std::nullopt;  // two points at one site
    at = static_cast<int32_t>(i);
  }
  const double reach = horizon[0] + (pad.empty() ? 0.0 : pad[0]) + 0.01 * spacing;
  const long long ring = static_cast<long long>(std::ceil(reach / spacing));
  long long lim[3];
  for (int d = 0; d < 3; ++d) lim[d] = std::min(ring, l.count[d] - 1);
  for (long long c = -lim[2]; c <= lim[2]; ++c)
    for (long long b = -lim[1]; b <= lim[1]; ++b)
      for (long long a = -lim[0]; a <= lim[0]; ++a) {
        const double r = spacing * std::sqrt(static_cast<double>(a * a + b * b + c * c));
        if ((a || b || c) && r <= reach)
          l.offsets.insert(l.offsets.end(), {static_cast<int32_t>(a), static_cast<int32_t>(b), static_cast<int32_t>(c)});
      }
  return l;
}

// A row's partners ascending: an LSD radix sort on v - min in 8-bit digits (as many as the
// row's span needs), the short rows by sort_ascending. The cell search emits a row as
// sorted runs in cell order, on which sort_ascending's quicksort mispredicts its comparisons:
// it was a quarter of the families' CPU on the full concrete case (perf). The partners are
// distinct, so any correct sort gives the same array. `scratch` is the calling thread's.
void sort_row_ascending(int32_t* a, int64_t m, std::vector<uint32_t>& scratch) {
  if (m < 64) {
    family::sort_ascending(a, m);
    return;
  }
  int32_t lo = a[0], hi = a[0];
  for (int64_t k = 1; k < m; ++k) {
    lo = std::min(lo, a[k]);
    hi = std::max(hi, a[k]);
  }
  const uint32_t span = static_cast<uint32_t>(hi) - static_cast<uint32_t>(lo);
  int digits = 1;
  while (digits < 4 && (span >> (8 * digits)) != 0) ++digits;
  if (scratch.size() < static_cast<size_t>(2 * m)) scratch.resize(static_cast<size_t>(2 * m));
  uint32_t* from = scratch.data();
  uint32_t* to = from + m;
  uint32_t start[4][256] = {};
  for (int64_t k = 0; k < m; ++k) {
    const uint32_t v = static_cast<uint32_t>(a[k]) - static_cast<uint32_t>(lo);
    from[k] = v;
    for (int d = 0; d < digits; ++d) ++start[d][(v >> (8 * d)) & 255u];
  }
  for (int d = 0; d < digits; ++d) {
    uint32_t sum = 0;
    for (uint32_t& s : start[d]) {
      const uint32_t c = s;
      s = sum;
      sum += c;
    }
    for (int64_t k = 0; k < m; ++k) to[start[d][(from[k] >> (8 * d)) & 255u]++] = from[k];
    std::swap(from, to);
  }
  for (int64_t k = 0; k < m; ++k) a[k] = static_cast<int32_t>(from[k] + static_cast<uint32_t>(lo));
}

}  // namespace

FamilyPlan plan_families(std::span<const double> x, std::span<const double> horizon, std::span<const double> pad,
                         int64_t row_begin, int64_t row_end) {
  const size_t n = horizon.size();
  if (x.size() != 3 * n) throw std::invalid_argument("build_families: position must be 3N");
  if (!pad.empty() && pad.size() != n) throw std::invalid_argument("build_families: pad must be empty or N");
  if (row_end < 0) row_end = static_cast<int64_t>(n);
  if (row_begin < 0 || row_begin > row_end || row_end > static_cast<int64_t>(n))
    throw std::invalid_argument("build_families: rows outside [0, N]");
  FamilyPlan plan;
  plan.n = n;
  plan.row_begin = row_begin;
  plan.row_end = row_end;
  if (n == 0) return plan;
  auto pad_of = [&](size_t i) { return pad.empty() ? 0.0 : pad[i]; };
  // Reach classes: the particles grouped by horizon in octaves from the smallest (class K:
  // h in [2^K, 2^(K+1)) h_min; at most kClasses, the last open-ended). Class K's grids have
  // cells of half the class's largest reach, so a row's search spans 5 cells per axis (125)
  // whatever its horizon: with one grid sized for the finest particles a coarse particle of a
  // graded mesh scanned up to 3,375 (the full concrete case's horizons span 2.9-22 mm).
  constexpr int kClasses = family::kClasses;
  double h_min = horizon[0];
  for (size_t i = 0; i < n; ++i) h_min = std::min(h_min, horizon[i]);
  plan.klass.assign(n, 0);
  int classes = 1;
  if (h_min > 0.0)
    for (size_t i = 0; i < n; ++i) {
      int k = 0;
      double top = 2.0 * h_min;
      while (k + 1 < kClasses && horizon[i] >= top) {
        ++k;
        top *= 2.0;
      }
      plan.klass[i] = static_cast<uint8_t>(k);
      classes = std::max(classes, k + 1);
    }
  plan.classes = classes;
  const BoundingBox box = bounding_box(x);
  // per class: members, largest horizon, largest pad; which classes have rows to build
  std::vector<int64_t> members(static_cast<size_t>(classes), 0);
  std::vector<double> hk(static_cast<size_t>(classes), 0.0), pk(static_cast<size_t>(classes), 0.0);
  std::vector<bool> has_rows(static_cast<size_t>(classes), false);
  for (size_t i = 0; i < n; ++i) {
    const size_t k = plan.klass[i];
    ++members[k];
    hk[k] = std::max(hk[k], horizon[i]);
    pk[k] = std::max(pk[k], pad_of(i));
  }
  for (int64_t i = row_begin; i < row_end; ++i) has_rows[plan.klass[static_cast<size_t>(i)]] = true;
  // A grid's cell: half the class's reach (largest h + largest pad), or larger where the
  // bounding box would otherwise hold more than 8 cells per particle (and 2^16): sparse
  // points in a large box.
  auto cell_of_class = [&](int k) {
    double cell = std::max(0.5 * (hk[static_cast<size_t>(k)] + pk[static_cast<size_t>(k)]), 1e-300);
    for (;;) {
      double cells = 1.0;
      for (int d = 0; d < 3; ++d) cells *= std::floor((box.hi[d] - box.lo[d]) / cell) + 1.0;
      if (cells <= std::max(8.0 * static_cast<double>(n), 65536.0)) return cell;
      cell *= 1.25;
    }
  };
  // Row i of class K finds the particles of classes <= K in the grid "up to K" (all of them
  // binned in K's cells) and those of each coarser class L in the grid "only L" (L's cells),
  // so it visits every particle at most once. Only the grids some row searches: "up to K"
  // where a row is of class K, "only L" for L above the smallest class present.
  auto grid = [&](int lo, int hi, double cell) {
    FamilyPlan::Grid g;
    g.built = true;
    g.cells = CellGrid::covering(box, cell);
    g.class_lo = lo;
    g.class_hi = hi;
    for (int k = lo; k <= hi; ++k) {
      g.size += members[static_cast<size_t>(k)];
      g.max_horizon = std::max(g.max_horizon, hk[static_cast<size_t>(k)]);
      g.max_pad = std::max(g.max_pad, pk[static_cast<size_t>(k)]);
    }
    return g;
  };
  for (int k = 0; k < classes; ++k) {
    const double cell = cell_of_class(k);
    if (has_rows[static_cast<size_t>(k)]) plan.up_to[k] = grid(0, k, cell);
    if (k > 0) plan.only[k] = grid(k, k, cell);
  }
  return plan;
}

Families build_families(std::span<const double> x, std::span<const double> horizon, std::span<const double> pad,
                        int64_t row_begin, int64_t row_end) {
  const FamilyPlan plan = plan_families(x, horizon, pad, row_begin, row_end);
  const size_t n = plan.n;
  Families fam;
  fam.offsets.assign(n + 1, 0);
  if (n == 0) return fam;
  FamilyHostMemory mem;
  const family::Points p = family_detail::points(mem, plan, x, horizon, pad);
  const std::optional<LatticeRows> lattice = lattice_rows(x, horizon, pad);
  const family::Grids grids =
      lattice ? family::Grids{} : family_detail::bin_grids(SerialFamilyExec{}, mem, plan, p);
  // Row i's partners: by the lattice's offsets where the points are one, else the cell search.
  auto search = [&](int64_t i, auto& emit) {
    if (!lattice) {
      family::search_row(p, grids, i, emit);
      return;
    }
    const LatticeRows& l = *lattice;
    const int32_t* site = l.site_of.data() + 3 * i;
    const double* xi = p.x + 3 * i;
    const double horizon_i = p.horizon[i], pad_i = p.pad_of(i);
    const size_t offsets = l.offsets.size() / 3;
    for (size_t q = 0; q < offsets; ++q) {
      const int32_t* o = l.offsets.data() + 3 * q;
      const long long a = site[0] + o[0], b = site[1] + o[1], c = site[2] + o[2];
      if (a < 0 || a >= l.count[0] || b < 0 || b >= l.count[1] || c < 0 || c >= l.count[2]) continue;
      const int32_t j = l.point_at[static_cast<size_t>((c * l.count[1] + b) * l.count[0] + a)];
      if (j >= 0 && family::within_reach(xi, horizon_i, pad_i, p.x + 3 * j, p.horizon[j], p.pad_of(j))) emit(j);
    }
  };
  // One thread on a lattice, every row: the rows by transposition, with no sort. Row i's
  // search counts its partners; then for i ascending each partner j gets i appended to its
  // row, so every row is written in ascending order. Partnership is symmetric (within_reach
  // gives the same bits from either end: x_i - x_j = -(x_j - x_i) exactly, and every horizon
  // and pad is the same here), so row j receives exactly the partners its own search finds,
  // and count[j] of them. The sorts took 0.26 CPU s of the 41^3 set-up.
#if defined(_OPENMP)
  const bool one_thread = omp_get_max_threads() == 1;
#else
  const bool one_thread = true;
#endif
  if (lattice && one_thread && plan.row_begin == 0 && plan.row_end == static_cast<int64_t>(n)) {
    struct Count {
      int64_t found = 0;
      void operator()(int32_t) { ++found; }
    };
    for (size_t i = 0; i < n; ++i) {
      Count c;
      search(static_cast<int64_t>(i), c);
      fam.offsets[i + 1] = fam.offsets[i] + c.found;
    }
    assign_on_huge_pages(fam.neighbors, static_cast<size_t>(fam.offsets[n]));
    std::vector<int64_t> cursor(fam.offsets.begin(), fam.offsets.end() - 1);
    struct Append {
      int32_t* neighbors;
      int64_t* cursor;
      int32_t row;
      void operator()(int32_t j) { neighbors[cursor[j]++] = row; }
    };
    for (size_t i = 0; i < n; ++i) {
      Append a{fam.neighbors.data(), cursor.data(), static_cast<int32_t>(i)};
      search(static_cast<int64_t>(i), a);
    }
    for (size_t j = 0; j < n; ++j)
      if (cursor[j] != fam.offsets[j + 1]) throw std::logic_error("build_families: a lattice row is not symmetric");
    return fam;
  }
  // The rows: build_families_with's kernels would search each row twice (count, then write);
  // here each is searched once (search_row, the same kernel) and kept. Each block of 512 rows
  // is searched into a scratch buffer of its thread (sorted per row), then appended to the
  // thread's store: chunks of 16M entries (64 MB) on huge pages, written once and never
  // moved; the lists are copied into place once the counts are known. Buffers of their own
  // per block, grown by doubling, copied themselves several times and faulted in every 4 KiB
  // page of them one by one.
  constexpr size_t block = 512;
  const size_t blocks = (n + block - 1) / block;
#if defined(_OPENMP)
  const size_t threads = static_cast<size_t>(omp_get_max_threads());
#else
  const size_t threads = 1;
#endif
  constexpr size_t chunk_entries = size_t{1} << 24;
  std::vector<std::vector<std::vector<int32_t>>> store(threads);
  std::vector<const int32_t*> found(blocks, nullptr);  // block b's lists, count[] of its rows long
  std::vector<int64_t> count(n, 0);
  struct Keep {  // search_row's emit: the partners onto the block's list
    std::vector<int32_t>& list;
    void operator()(int32_t j) { list.push_back(j); }
  };
#pragma omp parallel
  {
#if defined(_OPENMP)
    std::vector<std::vector<int32_t>>& chunks = store[static_cast<size_t>(omp_get_thread_num())];
#else
    std::vector<std::vector<int32_t>>& chunks = store[0];
#endif
    std::vector<int32_t> list;
    std::vector<uint32_t> sort_scratch;
    Keep keep{list};
#pragma omp for schedule(dynamic, 4)
    for (size_t b = 0; b < blocks; ++b) {
      list.clear();
      const int64_t first_row = std::max<int64_t>(plan.row_begin, static_cast<int64_t>(b * block));
      const int64_t last_row = std::min<int64_t>(plan.row_end, static_cast<int64_t>(std::min(n, (b + 1) * block)));
      for (int64_t i = first_row; i < last_row; ++i) {  // the rows outside [row_begin, row_end) are left empty
        const size_t first = list.size();
        search(i, keep);
        sort_row_ascending(list.data() + first, static_cast<int64_t>(list.size() - first), sort_scratch);
        count[static_cast<size_t>(i)] = static_cast<int64_t>(list.size() - first);
      }
      if (chunks.empty() || chunks.back().capacity() - chunks.back().size() < list.size()) {
        chunks.emplace_back();
        const size_t capacity = std::max(chunk_entries, list.size());
        chunks.back().reserve(capacity);
        advise_huge_pages(chunks.back().data(), capacity * sizeof(int32_t));
      }
      std::vector<int32_t>& chunk = chunks.back();
      found[b] = chunk.data() + chunk.size();
      chunk.insert(chunk.end(), list.begin(), list.end());
    }
  }
  for (size_t i = 0; i < n; ++i) fam.offsets[i + 1] = fam.offsets[i] + count[i];
  assign_on_huge_pages(fam.neighbors, static_cast<size_t>(fam.offsets[n]));
#pragma omp parallel for schedule(dynamic, 4)
  for (size_t b = 0; b < blocks; ++b) {
    const int64_t first = fam.offsets[b * block], last = fam.offsets[std::min(n, (b + 1) * block)];
    if (last > first) std::copy(found[b], found[b] + (last - first), fam.neighbors.begin() + first);
  }
  return fam;
}

bool families_on_lattice(std::span<const double> x, std::span<const double> horizon, std::span<const double> pad) {
  return lattice_rows(x, horizon, pad).has_value();
}

}  // namespace breccia
