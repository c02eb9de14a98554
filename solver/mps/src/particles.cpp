#include "breccia/mps/particles.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "breccia/common/error.hpp"
#include "breccia/common/particle_file.hpp"
#include "breccia/mps/bodies.hpp"

namespace breccia::mps {

double burst_displacement(const BurstHistory& h, double t) {
  const double tau = t - h.delay_s, length = h.cycles * h.period_s;
  if (tau < 0.0 || tau > length) return 0.0;
  const double carrier = h.amplitude_m * std::sin(2.0 * std::numbers::pi * tau / h.period_s);
  if (!h.hann) return carrier;
  return carrier * 0.5 * (1.0 - std::cos(2.0 * std::numbers::pi * tau / length));
}

double burst_velocity(const BurstHistory& h, double t) {
  const double tau = t - h.delay_s, length = h.cycles * h.period_s;
  if (tau < 0.0 || tau > length) return 0.0;
  const double w = 2.0 * std::numbers::pi / h.period_s, wl = 2.0 * std::numbers::pi / length;
  const double s = std::sin(w * tau), ds = w * std::cos(w * tau);
  if (!h.hann) return h.amplitude_m * ds;
  const double env = 0.5 * (1.0 - std::cos(wl * tau)), denv = 0.5 * wl * std::sin(wl * tau);
  return h.amplitude_m * (ds * env + s * denv);
}

ParticleCloud build_particle_cloud(const CaseSpec& spec) {
  if (spec.bodies) return build_bodies_cloud(spec);
  ParticleCloud c;
  if (spec.lattice) {
    const LatticeSpec& l = *spec.lattice;
    c.dimension = l.dimension;
    c.spacing_m = l.spacing_m;
    c.thickness_m = l.thickness_m;
    std::array<long long, 3> count{1, 1, 1};
    for (int a = 0; a < c.dimension; ++a) {
      count[a] = std::llround((l.high_m[a] - l.low_m[a]) / l.spacing_m);
      if (count[a] < 1) throw InputError(spec.file, "specimen.lattice.spacing", "larger than the box", "spacing < box size");
      if (l.periodic[a]) c.periodic.period_m[a] = count[a] * l.spacing_m;
    }
    const double re = spec.re_over_spacing * c.spacing_m;
    for (int a = 0; a < 3; ++a)
      if (c.periodic.period_m[a] > 0 && c.periodic.period_m[a] < 2.0 * re)
        throw InputError(spec.file, "specimen.lattice.periodic", "periodic box shorter than 2 re",
                         "a periodic length of at least " + std::to_string(2.0 * re) + " m");
    append_lattice(c.dimension, l.low_m, count, l.spacing_m, l.thickness_m, c);
    return c;
  }
  const ParticleModel model = read_particle_file(spec.particle_file);
  c.dimension = model.dimension;
  c.thickness_m = model.thickness_m;
  c.position_m = model.position_m;
  c.volume_m3 = model.volume_m3;
  c.content_id = model.content_id;
  std::vector<double> sp = model.spacing_m;
  std::nth_element(sp.begin(), sp.begin() + sp.size() / 2, sp.end());
  c.spacing_m = sp[sp.size() / 2];
  for (const auto& s : model.sets) {
    c.set_names.push_back(s.name);
    c.set_members.push_back(s.indices);
  }
  return c;
}

size_t append_lattice(int dimension, const std::array<double, 3>& low_m, const std::array<long long, 3>& count,
                      double spacing_m, double thickness_m, ParticleCloud& cloud,
                      const std::function<bool(double, double, double)>& keep) {
  const double volume = dimension == 2 ? spacing_m * spacing_m * thickness_m : std::pow(spacing_m, 3);
  const size_t before = cloud.volume_m3.size();
  for (long long k = 0; k < (dimension == 3 ? count[2] : 1); ++k)
    for (long long j = 0; j < count[1]; ++j)
      for (long long i = 0; i < count[0]; ++i) {
        const double x = low_m[0] + (i + 0.5) * spacing_m, y = low_m[1] + (j + 0.5) * spacing_m;
        const double z = dimension == 3 ? low_m[2] + (k + 0.5) * spacing_m : 0.0;
        if (keep && !keep(x, y, z)) continue;
        cloud.position_m.insert(cloud.position_m.end(), {x, y, z});
        cloud.volume_m3.push_back(volume);
      }
  return cloud.volume_m3.size() - before;
}

std::vector<PrescribedSet> select_boundary(const CaseSpec& spec, const ParticleCloud& cloud) {
  const size_t n = cloud.position_m.size() / 3;
  const std::vector<double>& pos = cloud.position_m;
  std::array<double, 3> lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  for (size_t i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], pos[3 * i + a]);
      hi[a] = std::max(hi[a], pos[3 * i + a]);
    }
  std::vector<PrescribedSet> out;
  for (size_t b = 0; b < spec.boundary.size(); ++b) {
    const BoundarySpec& bs = spec.boundary[b];
    PrescribedSet set;
    set.components = bs.components;
    set.burst = bs.burst;
    if (!bs.set.empty()) {
      const auto it = std::find(cloud.set_names.begin(), cloud.set_names.end(), bs.set);
      if (it == cloud.set_names.end())
        throw InputError(spec.file, "boundary[" + std::to_string(b) + "].set", "unknown set '" + bs.set + "'",
                         "a particle set of the particle file");
      for (auto i : cloud.set_members[it - cloud.set_names.begin()]) set.particles.push_back(static_cast<int>(i));
    } else {
      for (size_t i = 0; i < n; ++i) {
        const double* p = &pos[3 * i];
        bool in = false;
        if (bs.box_m) {
          const auto& bx = *bs.box_m;
          in = true;
          for (int a = 0; a < cloud.dimension; ++a) in = in && p[a] >= bx[a] && p[a] <= bx[3 + a];
        } else {
          const double tol = 0.5 * cloud.spacing_m;
          if (bs.face == "left") in = p[0] < lo[0] + tol;
          if (bs.face == "right") in = p[0] > hi[0] - tol;
          if (bs.face == "bottom") in = p[1] < lo[1] + tol;
          if (bs.face == "top") in = p[1] > hi[1] - tol;
          if (bs.face == "back") in = cloud.dimension == 3 && p[2] < lo[2] + tol;
          if (bs.face == "front") in = cloud.dimension == 3 && p[2] > hi[2] - tol;
        }
        if (in) set.particles.push_back(static_cast<int>(i));
      }
    }
    if (set.particles.empty())
      throw InputError(spec.file, "boundary[" + std::to_string(b) + "]", "selects no particles",
                       "a face, box or set containing particles");
    out.push_back(std::move(set));
  }
  return out;
}

int nearest_particle(const std::vector<double>& position_m, const std::array<double, 3>& p) {
  int best = -1;
  double best_d2 = 1e300;
  for (size_t i = 0; 3 * i < position_m.size(); ++i) {
    double d2 = 0.0;
    for (int a = 0; a < 3; ++a) d2 += (position_m[3 * i + a] - p[a]) * (position_m[3 * i + a] - p[a]);
    if (d2 < best_d2) {
      best_d2 = d2;
      best = static_cast<int>(i);
    }
  }
  return best;
}

void symplectic_euler_update(std::array<std::vector<double>, 3>& u, std::array<std::vector<double>, 3>& v,
                             const std::array<std::vector<double>, 3>& a, int dimension, double dt) {
  for (int c = 0; c < dimension; ++c) {
    double* uc = u[c].data();
    double* vc = v[c].data();
    const double* ac = a[c].data();
    const long long n = static_cast<long long>(u[c].size());
#pragma omp parallel for schedule(static) if (n > 8192)
    for (long long i = 0; i < n; ++i) symplectic_euler_at(uc[i], vc[i], ac[i], dt);
  }
}

void apply_prescribed_sets(const std::vector<PrescribedSet>& sets, double t, std::array<std::vector<double>, 3>& u,
                           std::array<std::vector<double>, 3>& v) {
  for (const auto& set : sets) {
    const double u_value = set.burst ? burst_displacement(*set.burst, t) : 0.0;
    const double v_value = set.burst ? burst_velocity(*set.burst, t) : 0.0;
    for (int a = 0; a < 3; ++a) {
      if (!set.components[a]) continue;
      for (int i : set.particles) {
        u[a][i] = u_value;
        v[a][i] = v_value;
      }
    }
  }
}

}  // namespace breccia::mps
