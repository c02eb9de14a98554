#pragma once
// The bond families (families.hpp) built through an execution space: the plan (reach
// classes, grid sizes: a few O(N) host loops, plan_families) on the host, then every O(N)
// and per-row pass as a launch of family_kernels.hpp's kernels, `exec.for_each(n, kernel,
// name)`, the step's launch abstraction (solver/include/breccia/solver/step.hpp):
//   per grid: each particle's cell key, the count per cell, their exclusive scan, the fill,
//             each cell's members sorted and copied with its largest horizon and pad;
//   per row:  its partners counted; the counts' exclusive scan into the row offsets; the
//             partners written into the row's slice and sorted.
// `Memory` says where the arrays live (HostMemory below; the device's in
// solver/cuda/src/cuda_families.cu):
//   template <class T> T* make(size_t count)      an array (freed with the Memory)
//   template <class T> const T* input(std::span<const T>)   the data where the kernels read it
//   int64_t read(const int64_t* at)               one value back on the host
//   int64_t* offsets(Families&, size_t count)     the output arrays: on the host, the
//   int32_t* neighbors(Families&, size_t count)   Families' own; elsewhere copied into it by
//   void finish(Families&)                        finish.
// build_families (families.cpp) bins with these launches on one host thread and searches
// each row once on OpenMP threads, keeping its partners (the same row kernel, search_row).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <span>
#include <stdexcept>
#include <vector>

#include "breccia/common/cell_list.hpp"
#include "breccia/common/families.hpp"
#include "breccia/common/family_kernels.hpp"
#include "breccia/common/huge_pages.hpp"

namespace breccia {

// What the host decides before any kernel runs: each particle's reach class and the grids.
struct FamilyPlan {
  size_t n = 0;
  int64_t row_begin = 0, row_end = 0;
  std::vector<uint8_t> klass;  // N
  int classes = 1;
  struct Grid {
    bool built = false;  // a grid some row searches
    CellGrid cells;
    int class_lo = 0, class_hi = 0;
    int64_t size = 0;
    double max_horizon = 0.0, max_pad = 0.0;
  };
  Grid up_to[family::kClasses], only[family::kClasses];
};

// Checks the sizes and the row range (std::invalid_argument) and plans the grids.
FamilyPlan plan_families(std::span<const double> position, std::span<const double> horizon_m,
                         std::span<const double> pad_m, int64_t row_begin, int64_t row_end);

// The host's arrays: std::vectors, the output the Families' own vectors.
class FamilyHostMemory {
public:
  template <class T>
  T* make(size_t count) {
    auto* a = new std::vector<T>(count);
    arrays_.push_back(std::shared_ptr<void>(a, [](void* v) { delete static_cast<std::vector<T>*>(v); }));
    return a->data();
  }
  template <class T>
  const T* input(std::span<const T> data) { return data.data(); }
  int64_t read(const int64_t* at) const { return *at; }
  int64_t* offsets(Families& fam, size_t count) {
    fam.offsets.assign(count, 0);
    return fam.offsets.data();
  }
  int32_t* neighbors(Families& fam, size_t count) {
    assign_on_huge_pages(fam.neighbors, count);
    return fam.neighbors.data();
  }
  void finish(Families&) {}

private:
  std::vector<std::shared_ptr<void>> arrays_;
};

namespace family_detail {

// out[0 .. n] = exclusive scan of value[0 .. n) (family_kernels.hpp's three passes).
template <class Exec, class Memory>
void exclusive_scan(const Exec& exec, Memory& mem, const int64_t* value, int64_t n, int64_t* out, const char* name) {
  const int64_t block = std::max<int64_t>(1024, static_cast<int64_t>(std::sqrt(static_cast<double>(n))));
  const int64_t blocks = std::max<int64_t>(1, (n + block - 1) / block);
  int64_t* block_sum = mem.template make<int64_t>(static_cast<size_t>(blocks + 1));
  exec.for_each(blocks, family::ScanBlockSums{value, n, block, block_sum}, name);
  exec.for_each(1, family::ScanBlockStarts{block_sum, blocks}, name);
  exec.for_each(blocks, family::ScanBlockWrite{value, n, block, block_sum, out, blocks}, name);
}

// Grid `plan`'s cell list of the particles of its classes, its view for the row kernels.
template <class Exec, class Memory>
family::GridView bin(const Exec& exec, Memory& mem, const family::Points& p, const FamilyPlan::Grid& plan,
                     int64_t n, int64_t* key) {
  family::GridView g{};
  for (int d = 0; d < 3; ++d) {
    g.origin[d] = plan.cells.origin[d];
    g.count[d] = plan.cells.count[d];
  }
  g.cell = plan.cells.cell[0];
  g.class_lo = plan.class_lo;
  g.class_hi = plan.class_hi;
  g.size = plan.size;
  g.max_horizon = plan.max_horizon;
  g.max_pad = plan.max_pad;
  const int64_t cells = g.cells();
  // cells + 1 buckets (the last: particles of other classes), and their scan's total
  int64_t* count = mem.template make<int64_t>(static_cast<size_t>(cells + 1));
  int64_t* start = mem.template make<int64_t>(static_cast<size_t>(cells + 2));
  int64_t* cursor = mem.template make<int64_t>(static_cast<size_t>(cells + 1));
  int32_t* members = mem.template make<int32_t>(static_cast<size_t>(n));
  auto* sorted = mem.template make<family::Candidate>(static_cast<size_t>(std::max<int64_t>(1, g.size)));
  double* cell_horizon = mem.template make<double>(static_cast<size_t>(cells));
  double* cell_pad = mem.template make<double>(static_cast<size_t>(cells));
  exec.for_each(n, family::BinKey{p, g, key}, "families: cell keys");
  exec.for_each(cells + 1, family::Fill64{count, 0}, "families: cell counts");
  exec.for_each(n, family::BinCount{key, count}, "families: cell counts");
  exclusive_scan(exec, mem, count, cells + 1, start, "families: cell starts");
  exec.for_each(cells + 1, family::Copy64{start, cursor}, "families: cell fill");
  exec.for_each(n, family::BinFill{key, cursor, members}, "families: cell fill");
  exec.for_each(cells, family::SortCell{p, start, members, sorted, cell_horizon, cell_pad}, "families: cell sort");
  g.start = start;
  g.sorted = sorted;
  g.cell_horizon = cell_horizon;
  g.cell_pad = cell_pad;
  return g;
}

}  // namespace family_detail

namespace family_detail {

// The particles where the kernels read them.
template <class Memory>
family::Points points(Memory& mem, const FamilyPlan& plan, std::span<const double> position,
                      std::span<const double> horizon_m, std::span<const double> pad_m) {
  return {mem.input(position), mem.input(horizon_m), pad_m.empty() ? nullptr : mem.input(pad_m),
          mem.input(std::span<const uint8_t>(plan.klass))};
}

// Every grid the plan's rows search, binned.
template <class Exec, class Memory>
family::Grids bin_grids(const Exec& exec, Memory& mem, const FamilyPlan& plan, const family::Points& p) {
  family::Grids grids{};
  grids.classes = plan.classes;
  const int64_t n = static_cast<int64_t>(plan.n);
  int64_t* key = mem.template make<int64_t>(plan.n);
  for (int k = 0; k < plan.classes; ++k) {
    // (an empty grid stays a view of size 0, which no row searches)
    if (plan.up_to[k].built && plan.up_to[k].size > 0) grids.up_to[k] = bin(exec, mem, p, plan.up_to[k], n, key);
    if (plan.only[k].built && plan.only[k].size > 0) grids.only[k] = bin(exec, mem, p, plan.only[k], n, key);
  }
  return grids;
}

}  // namespace family_detail

// build_families(position, horizon_m, pad_m, row_begin, row_end) through `exec` with the
// arrays of `mem`: the same offsets and partners, in the same order, in any execution space.
// The rows are searched twice, once to count and once to write (a GPU has no room to keep a
// row's partners before its offset is known); the host's build_families searches each once.
template <class Exec, class Memory>
Families build_families_with(const Exec& exec, Memory& mem, std::span<const double> position,
                             std::span<const double> horizon_m, std::span<const double> pad_m = {},
                             int64_t row_begin = 0, int64_t row_end = -1) {
  const FamilyPlan plan = plan_families(position, horizon_m, pad_m, row_begin, row_end);
  const int64_t n = static_cast<int64_t>(plan.n);
  Families fam;
  int64_t* offsets = mem.offsets(fam, plan.n + 1);
  if (n == 0) {
    mem.neighbors(fam, 0);
    mem.finish(fam);
    return fam;
  }
  const family::Points p = family_detail::points(mem, plan, position, horizon_m, pad_m);
  const family::Grids grids = family_detail::bin_grids(exec, mem, plan, p);
  const int64_t rows = plan.row_end - plan.row_begin;
  int64_t* count = mem.template make<int64_t>(plan.n);  // zero outside the rows
  exec.for_each(n, family::Fill64{count, 0}, "families: row counts");
  exec.for_each(rows, family::RowCount{p, grids, plan.row_begin, count}, "families: row counts");
  family_detail::exclusive_scan(exec, mem, count, n, offsets, "families: row offsets");
  const int64_t entries = mem.read(offsets + n);
  int32_t* neighbors = mem.neighbors(fam, static_cast<size_t>(entries));
  exec.for_each(rows, family::RowFill{p, grids, plan.row_begin, offsets, neighbors}, "families: rows");
  mem.finish(fam);
  return fam;
}

}  // namespace breccia
