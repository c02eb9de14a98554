#include "breccia/mps/neighbours.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "breccia/common/cell_list.hpp"

namespace breccia::mps {
namespace {

// Uniform grid of cells of edge >= radius_re (common's cell list); a periodic axis is cut
// into whole cells of its period, an axis beyond the dimension is one cell.
CellList make_grid(int dimension, const std::vector<double>& p, double re, const Periodicity& periodic) {
  const size_t n = p.size() / 3;
  CellGrid g;
  for (int a = 0; a < 3; ++a) {
    double lo = 0.0, hi = 0.0;
    if (n > 0) {
      lo = hi = p[a];
      for (size_t i = 0; i < n; ++i) {
        lo = std::min(lo, p[3 * i + a]);
        hi = std::max(hi, p[3 * i + a]);
      }
    }
    g.origin[a] = lo;
    const double extent = (periodic.period_m[a] > 0) ? periodic.period_m[a] : (hi - lo);
    if (a >= dimension || extent <= 0) {
      g.count[a] = 1;
      g.cell[a] = std::max(extent, re) + 1.0;
      continue;
    }
    g.count[a] = std::max<long long>(1, static_cast<long long>(std::floor(extent / re)));
    g.cell[a] = std::max(extent / g.count[a], 1e-300);
    if (periodic.period_m[a] <= 0) g.cell[a] = std::max(g.cell[a], re);
  }
  return sort_into_cells(g, p);
}

double minimum_image(double d, double period) {
  if (period <= 0) return d;
  return d - period * std::round(d / period);
}

// Visit every j within re of particle i (j != i): fn(j, rx, ry, rz, r).
template <class Fn>
void for_each_neighbour(const CellList& cells, int dimension, const std::vector<double>& p, double re,
                        const Periodicity& per, long long i, Fn&& fn) {
  const CellGrid& g = cells.grid;
  long long c[3];
  for (int a = 0; a < 3; ++a) c[a] = g.coordinate(a, p[3 * i + a]);
  long long lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    const bool active = a < dimension && g.count[a] > 1;
    lo[a] = active ? -1 : 0;
    hi[a] = active ? 1 : 0;
    // A periodic axis with fewer than 3 cells would visit a cell twice.
    if (active && per.period_m[a] > 0 && g.count[a] < 3) { lo[a] = 0; hi[a] = g.count[a] - 1; }
  }
  for (long long dz = lo[2]; dz <= hi[2]; ++dz)
    for (long long dy = lo[1]; dy <= hi[1]; ++dy)
      for (long long dx = lo[0]; dx <= hi[0]; ++dx) {
        long long q[3] = {c[0] + dx, c[1] + dy, c[2] + dz};
        const bool small_periodic[3] = {per.period_m[0] > 0 && g.count[0] < 3,
                                        per.period_m[1] > 0 && g.count[1] < 3,
                                        per.period_m[2] > 0 && g.count[2] < 3};
        bool outside = false;
        for (int a = 0; a < 3; ++a) {
          if (small_periodic[a]) { q[a] = (a == 0 ? dx : a == 1 ? dy : dz); continue; }
          if (q[a] < 0 || q[a] >= g.count[a]) {
            if (per.period_m[a] > 0) q[a] = (q[a] + g.count[a]) % g.count[a];
            else outside = true;
          }
        }
        if (outside) continue;
        const long long cell = g.index(q[0], q[1], q[2]);
        for (int64_t s = cells.start[cell]; s < cells.start[cell + 1]; ++s) {
          const long long j = cells.members[s];
          if (j == i) continue;
          const double rx = minimum_image(p[3 * j] - p[3 * i], per.period_m[0]);
          const double ry = minimum_image(p[3 * j + 1] - p[3 * i + 1], per.period_m[1]);
          const double rz = minimum_image(p[3 * j + 2] - p[3 * i + 2], per.period_m[2]);
          const double r = std::sqrt(rx * rx + ry * ry + rz * rz);
          if (r < re && r > 0.0) fn(j, rx, ry, rz, r);
        }
      }
}

}  // namespace

BondList build_bonds(int dimension, const std::vector<double>& p, double re, const Periodicity& per) {
  for (int a = 0; a < 3; ++a)
    if (per.period_m[a] > 0 && per.period_m[a] < 2.0 * re)
      throw std::invalid_argument("periodic length shorter than twice the MPS radius re");
  const long long n = static_cast<long long>(p.size() / 3);
  const CellList g = make_grid(dimension, p, re, per);
  BondList b;
  b.dimension = dimension;
  b.radius_re_m = re;
  b.offset.assign(n + 1, 0);
#pragma omp parallel for schedule(static) if (n > 8192)
  for (long long i = 0; i < n; ++i) {
    long long count = 0;
    for_each_neighbour(g, dimension, p, re, per, i, [&](long long, double, double, double, double) { ++count; });
    b.offset[i + 1] = count;
  }
  for (long long i = 0; i < n; ++i) b.offset[i + 1] += b.offset[i];
  const size_t m = static_cast<size_t>(b.offset[n]);
  b.neighbour.resize(m);
  b.rx.resize(m);
  b.ry.resize(m);
  b.rz.resize(m);
  b.weight.resize(m);
#pragma omp parallel for schedule(static) if (n > 8192)
  for (long long i = 0; i < n; ++i) {
    long long k = b.offset[i];
    for_each_neighbour(g, dimension, p, re, per, i, [&](long long j, double rx, double ry, double rz, double r) {
      b.neighbour[k] = static_cast<int>(j);
      b.rx[k] = rx;
      b.ry[k] = ry;
      b.rz[k] = rz;
      b.weight[k] = koshizuka_weight(r, re);
      ++k;
    });
  }
  return b;
}

void remove_bonds(BondList& b, const std::function<bool(long long, long long, long long)>& cut) {
  const long long n = static_cast<long long>(b.particles());
  long long write = 0;
  std::vector<long long> offset(n + 1, 0);
  for (long long i = 0; i < n; ++i) {
    for (long long k = b.offset[i]; k < b.offset[i + 1]; ++k) {
      if (cut(i, b.neighbour[k], k)) continue;
      b.neighbour[write] = b.neighbour[k];
      b.rx[write] = b.rx[k];
      b.ry[write] = b.ry[k];
      b.rz[write] = b.rz[k];
      b.weight[write] = b.weight[k];
      ++write;
    }
    offset[i + 1] = write;
  }
  b.offset = std::move(offset);
  for (auto* v : {&b.rx, &b.ry, &b.rz, &b.weight}) v->resize(write);
  b.neighbour.resize(write);
}

Normalisation reference_normalisation(const BondList& b) {
  Normalisation best;
  const long long n = static_cast<long long>(b.particles());
  for (long long i = 0; i < n; ++i) {
    double sw = 0.0, swr2 = 0.0;
    for (long long k = b.offset[i]; k < b.offset[i + 1]; ++k) {
      sw += b.weight[k];
      swr2 += b.weight[k] * (b.rx[k] * b.rx[k] + b.ry[k] * b.ry[k] + b.rz[k] * b.rz[k]);
    }
    // 1e-12 relative: interior particles of a lattice tie up to round-off; keep the first.
    if (sw > best.number_density_n0 * (1.0 + 1e-12)) {
      best.number_density_n0 = sw;
      best.laplacian_lambda_m2 = swr2 / sw;
    }
  }
  return best;
}

}  // namespace breccia::mps
