#include "breccia/mps/crack.hpp"

#include <cmath>
#include <limits>
#include <unordered_map>
#include <utility>

#include "breccia/common/error.hpp"

namespace breccia::mps {
namespace {

double cross(double ax, double ay, double bx, double by) { return ax * by - ay * bx; }

// Does the open segment p->q cross the segment a->b (shifted by `shift` along x)?
bool crosses(double px, double py, double qx, double qy, const CrackSpec& c, double shift) {
  const double ax = c.start_m[0] + shift, ay = c.start_m[1], bx = c.end_m[0] + shift, by = c.end_m[1];
  const double d1 = cross(bx - ax, by - ay, px - ax, py - ay);
  const double d2 = cross(bx - ax, by - ay, qx - ax, qy - ay);
  const double d3 = cross(qx - px, qy - py, ax - px, ay - py);
  const double d4 = cross(qx - px, qy - py, bx - px, by - py);
  // Both products are symmetric in p <-> q, so bond i-j and bond j-i are cut together; a
  // bond through a crack tip counts as crossing.
  return d1 * d2 < 0.0 && d3 * d4 <= 0.0;
}

}  // namespace

CrackPairs build_crack_pairs(const CaseSpec& spec, const std::vector<double>& p, double h, double face_depth_m,
                             const Periodicity& periodic, BondList& bonds) {
  CrackPairs pairs;
  const double lx = periodic.period_m[0];
  const MaterialSpec& m = spec.material;
  for (size_t c = 0; c < spec.cracks.size(); ++c) {
    const CrackSpec& crack = spec.cracks[c];
    const std::string where = "cracks[" + std::to_string(c) + "].segment";
    const double ax = crack.start_m[0], ay = crack.start_m[1];
    const double len = std::hypot(crack.end_m[0] - ax, crack.end_m[1] - ay);
    const double sx = (crack.end_m[0] - ax) / len, sy = (crack.end_m[1] - ay) / len;
    const double nx = -sy, ny = sx;  // + side: left of start -> end

    // Face particles: within one spacing of the line, projecting onto the segment.
    std::vector<int> plus, minus;
    std::vector<double> t_plus, t_minus, d_minus;
    const size_t n = p.size() / 3;
    for (size_t i = 0; i < n; ++i) {
      const double rx = p[3 * i] - ax;
      const double ry = p[3 * i + 1] - ay;
      const double t = rx * sx + ry * sy, d = rx * nx + ry * ny;
      if (t < 0 || t > len || std::abs(d) >= h) continue;
      if (std::abs(d) < 1e-6 * h)
        throw InputError(spec.file, where, "the crack line passes through particle centres",
                         "a line between particle rows (shift it by half a spacing)");
      if (d > 0) {
        plus.push_back(static_cast<int>(i));
        t_plus.push_back(t);
      } else {
        minus.push_back(static_cast<int>(i));
        t_minus.push_back(t);
        d_minus.push_back(-d);
      }
    }
    FrictionLaw law;
    law.static_mu = crack.static_friction;
    law.kinetic_mu = crack.kinetic_friction;
    const double face_area = h * face_depth_m;
    // Default stiffness: factor * modulus * area / spacing. With factor 1 the springs give
    // about the coupling of the continuum bonds they replace (for re = 2.1 spacing the MPS
    // Laplacian couples neighbouring rows with 0.91 mu per spacing), so a sticking crack is
    // nearly invisible to the wave; a much stiffer spring is a stiffness mismatch that
    // reflects (measured: factor 10 reflects ~10% in amplitude at 20 points per wavelength).
    law.shear_stiffness_n_m = crack.shear_stiffness_n_m.value_or(crack.stiffness_factor * m.shear_modulus_pa * face_area / h);
    law.normal_stiffness_n_m = crack.normal_stiffness_n_m.value_or(
        crack.stiffness_factor * (m.lame_lambda_pa + 2 * m.shear_modulus_pa) * face_area / h);
    law.preload_n = crack.normal_stress_pa * face_area;
    law.clapping = crack.clapping;
    law.restick_continuous = crack.restick_continuous;
    pairs.law.push_back(law);
    pairs.name.push_back(crack.name);

    std::vector<char> used(minus.size(), 0);
    size_t made = 0;
    for (size_t a = 0; a < plus.size(); ++a) {
      long long best = -1;
      double best_dt = 0.5 * h, best_d = 0.0;
      for (size_t b = 0; b < minus.size(); ++b) {
        if (used[b]) continue;
        const double dt = std::abs(t_minus[b] - t_plus[a]);
        if (dt < best_dt - 1e-9 * h || (best >= 0 && std::abs(dt - best_dt) <= 1e-9 * h && d_minus[b] < best_d)) {
          best = static_cast<long long>(b);
          best_dt = dt;
          best_d = d_minus[b];
        }
      }
      if (best < 0) continue;
      used[best] = 1;
      pairs.plus.push_back(plus[a]);
      pairs.minus.push_back(minus[best]);
      pairs.crack.push_back(static_cast<int>(c));
      pairs.normal_x.push_back(nx);
      pairs.normal_y.push_back(ny);
      pairs.tangent_x.push_back(sx);
      pairs.tangent_y.push_back(sy);
      pairs.state.push_back({});
      ++made;
    }
    if (made == 0)
      throw InputError(spec.file, where, "no particles face each other across the crack (outside the body?)",
                       "a segment inside the particle model, at least one spacing long");
  }
  if (spec.cracks.empty()) return pairs;

  remove_bonds(bonds, [&](long long i, long long j, long long k) {
    const double px = p[3 * i], py = p[3 * i + 1];
    const double qx = px + bonds.rx[k], qy = py + bonds.ry[k];
    for (const auto& crack : spec.cracks) {
      if (crosses(px, py, qx, qy, crack, 0.0)) return true;
      if (lx > 0 && (crosses(px, py, qx, qy, crack, lx) || crosses(px, py, qx, qy, crack, -lx))) return true;
    }
    return false;
  });
  return pairs;
}

PairIncidence pair_incidence(const CrackPairs& pairs) {
  std::unordered_map<int, std::vector<std::pair<int, unsigned char>>> by_particle;
  std::vector<int> order;
  auto add = [&](int i, int p, unsigned char plus) {
    auto [it, fresh] = by_particle.try_emplace(i);
    if (fresh) order.push_back(i);
    it->second.emplace_back(p, plus);
  };
  for (size_t p = 0; p < pairs.size(); ++p) {
    add(pairs.plus[p], static_cast<int>(p), 1);
    add(pairs.minus[p], static_cast<int>(p), 0);
  }
  PairIncidence inc;
  for (int i : order) {
    inc.particle.push_back(i);
    for (const auto& [p, plus] : by_particle[i]) {
      inc.pair.push_back(p);
      inc.plus_side.push_back(plus);
    }
    inc.offset.push_back(static_cast<long long>(inc.pair.size()));
  }
  return inc;
}

}  // namespace breccia::mps
