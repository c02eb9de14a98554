// The Lanczos stable-step estimate's start on a PMB lattice: the plane wave its largest
// eigenvalue is made of (docs/performance-log.md, "The stable step from the lattice's plane wave").
#include <cmath>

#include "breccia/solver/pd_system.hpp"

namespace breccia::solver {

namespace {
// The largest eigenvalue of the symmetric 3x3 matrix m (xx, yy, zz, xy, xz, yz) and a unit
// vector along it, by power steps from the largest diagonal's axis (the estimate needs a
// good direction, not an exact one).
double largest_eigenpair(const double m[6], double v[3]) {
  v[0] = v[1] = v[2] = 0.0;
  v[m[1] > m[0] ? (m[2] > m[1] ? 2 : 1) : (m[2] > m[0] ? 2 : 0)] = 1.0;
  double lambda = 0.0;
  for (int it = 0; it < 30; ++it) {
    const double y[3] = {m[0] * v[0] + m[3] * v[1] + m[4] * v[2], m[3] * v[0] + m[1] * v[1] + m[5] * v[2],
                         m[4] * v[0] + m[5] * v[1] + m[2] * v[2]};
    const double norm = std::sqrt(y[0] * y[0] + y[1] * y[1] + y[2] * y[2]);
    if (!(norm > 0.0)) break;
    lambda = v[0] * y[0] + v[1] * y[1] + v[2] * y[2];
    for (int d = 0; d < 3; ++d) v[d] = y[d] / norm;
  }
  return lambda;
}
}  // namespace

StableStepStartWave stable_step_start_wave(const PdSystem& sys, const std::vector<double>* row_sums,
                                           std::optional<bool> lattice) {
  StableStepStartWave wave;
  if (sys.config.model != PdModel::PMB || sys.n == 0 || sys.offsets.size() != sys.n + 1 || sys.k_own.empty())
    return wave;
  const std::vector<double>& k_dual = sys.k_dual_halves();  // the own halves where shared (pd_system.hpp)
  // A lattice only: one spacing and one horizon. A graded body's top mode is no plane wave
  // (its fine region's wave fits nowhere else), and the wave there slowed the estimate.
  if (!lattice) {
    lattice = true;
    for (size_t i = 1; i < sys.n && *lattice; ++i)
      lattice = sys.half_cell[i] == sys.half_cell[0] && sys.horizon[i] == sys.horizon[0];
  }
  if (!*lattice) return wave;
  // The candidate row: the largest sum of bond stiffness over length per density (a bulk
  // row: the Silling-Askari sum), the first on ties. A distributed set-up's global system
  // holds its own rows only, the others empty: each rank takes its best and the set-up
  // keeps the best of all by the same rule (setup.cpp), the row one process takes.
  for (size_t i = 0; i < sys.n; ++i) {
    if (sys.offsets[i + 1] == sys.offsets[i]) continue;
    double sum = 0.0;
    if (row_sums) {
      sum = (*row_sums)[i];
    } else {
      for (int64_t k = sys.offsets[i]; k < sys.offsets[i + 1]; ++k) sum += (sys.k_own[k] + k_dual[k]) / sys.xi_len[k];
    }
    sum /= sys.density[i];
    if (sum > wave.score) {
      wave.score = sum;
      wave.row = static_cast<int64_t>(i);
    }
  }
  if (wave.row < 0) return wave;
  // The row's dispersion: a plane wave u = p cos(k . x) over the bulk loads the particle
  // with D(k) p cos(k . x_i), D(k) = sum_j (k_own + k_dual) / |xi| (1 - cos k . xi) e e^T
  // (PMB linearised: each bond's stiffness along its direction). Its largest eigenvalue is
  // searched over k on a grid of the zone (an eighth of pi / spacing, k_x >= 0: D is even
  // in k) and refined four times around the best by a quarter of the step (5,500 k in all:
  // 0.03 s at 41^3, the row's 122 entries each).
  const size_t i = static_cast<size_t>(wave.row);
  const bool planar = sys.dimension == 2;
  struct Entry {
    double xi[3], weight;
  };
  std::vector<Entry> entries;
  for (int64_t k = sys.offsets[i]; k < sys.offsets[i + 1]; ++k) {
    const size_t j = static_cast<size_t>(sys.neighbor[k]);
    const double len = sys.xi_len[k];
    entries.push_back(
        {{sys.x0[3 * j] - sys.x0[3 * i], sys.x0[3 * j + 1] - sys.x0[3 * i + 1], sys.x0[3 * j + 2] - sys.x0[3 * i + 2]},
         (sys.k_own[k] + k_dual[k]) / (len * len * len)});  // xi xi^T / |xi|^2 = e e^T
  }
  double best = -1.0;
  auto evaluate = [&](const double k[3]) {
    double m[6] = {0, 0, 0, 0, 0, 0};
    for (const Entry& e : entries) {
      const double c = e.weight * (1.0 - std::cos(k[0] * e.xi[0] + k[1] * e.xi[1] + k[2] * e.xi[2]));
      m[0] += c * e.xi[0] * e.xi[0];
      m[1] += c * e.xi[1] * e.xi[1];
      m[2] += c * e.xi[2] * e.xi[2];
      m[3] += c * e.xi[0] * e.xi[1];
      m[4] += c * e.xi[0] * e.xi[2];
      m[5] += c * e.xi[1] * e.xi[2];
    }
    if (planar) m[2] = m[4] = m[5] = 0.0;  // z is no degree of freedom
    double v[3];
    const double lambda = largest_eigenpair(m, v);
    if (lambda > best) {
      best = lambda;
      for (int d = 0; d < 3; ++d) {
        wave.k[d] = k[d];
        wave.p[d] = v[d];
      }
    }
  };
  const int steps = 8;
  const double dk = 3.14159265358979323846 / (2.0 * sys.half_cell[i]) / steps;
  const int z_steps = planar ? 0 : steps;
  for (int a = 0; a <= steps; ++a)
    for (int b = -steps; b <= steps; ++b)
      for (int c = -z_steps; c <= z_steps; ++c) {
        const double k[3] = {a * dk, b * dk, c * dk};
        evaluate(k);
      }
  double step = dk;
  for (int level = 0; level < 4; ++level) {
    step /= 4.0;
    const double centre[3] = {wave.k[0], wave.k[1], wave.k[2]};
    for (int a = -4; a <= 4; ++a)
      for (int b = -4; b <= 4; ++b)
        for (int c = planar ? 0 : -4; c <= (planar ? 0 : 4); ++c) {
          const double k[3] = {centre[0] + a * step, centre[1] + b * step, centre[2] + c * step};
          evaluate(k);
        }
  }
  wave.found = best > 0.0;
  return wave;
}

}  // namespace breccia::solver
