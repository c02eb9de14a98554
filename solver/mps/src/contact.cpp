#include "breccia/mps/contact.hpp"
#include "breccia/mps/solid_phases.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <omp.h>

#include "breccia/common/cell_list.hpp"

namespace breccia::mps {

// Below this many particles thread start-up costs more than the pair loop (as in solid.cpp).
constexpr long long kContactParallelMin = 8192;

PolygonGeometry polygon_geometry(const std::vector<double>& x, const std::vector<double>& y) {
  // Green's theorem over the edges; the signs cancel for clockwise polygons.
  const size_t n = x.size();
  double a2 = 0.0, sx = 0.0, sy = 0.0, jx = 0.0, jy = 0.0;
  for (size_t k = 0, m = n - 1; k < n; m = k++) {
    const double cr = x[m] * y[k] - x[k] * y[m];
    a2 += cr;
    sx += (x[m] + x[k]) * cr;
    sy += (y[m] + y[k]) * cr;
    jx += (y[m] * y[m] + y[m] * y[k] + y[k] * y[k]) * cr;  // 12 * integral of y^2
    jy += (x[m] * x[m] + x[m] * x[k] + x[k] * x[k]) * cr;  // 12 * integral of x^2
  }
  PolygonGeometry g;
  const double area = 0.5 * a2;
  g.area_m2 = std::fabs(area);
  if (g.area_m2 == 0.0) return g;
  g.cx_m = sx / (6.0 * area);
  g.cy_m = sy / (6.0 * area);
  const double polar_origin = (jx + jy) / 12.0 * (area < 0 ? -1.0 : 1.0);
  g.polar_moment_m4 = polar_origin - g.area_m2 * (g.cx_m * g.cx_m + g.cy_m * g.cy_m);
  return g;
}

void Contact::set_particle_contact(ParticleContact pc) {
  particles_ = std::move(pc);
  particle_contact_on_ = particles_.distance_m > 0.0 && particles_.stiffness_n_m > 0.0;
  pair_friction_key_.clear();
  pair_friction_.clear();
}

void Contact::add_half_space(HalfSpace h) {
  const double len = std::sqrt(h.normal[0] * h.normal[0] + h.normal[1] * h.normal[1] + h.normal[2] * h.normal[2]);
  for (double& c : h.normal) c /= len;
  h.offset_m = h.velocity_m_s = {0.0, 0.0, 0.0};
  h.last_step_m = std::numeric_limits<double>::quiet_NaN();
  if (h.motion && h.motion->quantity == PrescribedMotion::Quantity::Velocity)
    for (int a = 0; a < 3; ++a) h.velocity_m_s[a] = h.motion->direction[a] * h.motion->history.at(0.0);
  half_spaces_.push_back(h);
  plane_reaction_n_.assign(half_spaces_.size(), {0.0, 0.0, 0.0});
  friction_.clear();
}

void Contact::add_polygon(RigidPolygon p) {
  const PolygonGeometry g = polygon_geometry(p.x_m, p.y_m);
  BodyState b;
  b.cx = b.cx0 = g.cx_m;
  b.cy = b.cy0 = g.cy_m;
  for (size_t k = 0; k < p.x_m.size(); ++k) {
    b.local_x.push_back(p.x_m[k] - g.cx_m);
    b.local_y.push_back(p.y_m[k] - g.cy_m);
  }
  if (!p.fixed) {
    b.vx = p.velocity_m_s[0];
    b.vy = p.velocity_m_s[1];
    b.omega = p.angular_velocity_rad_s;
  } else if (p.motion && p.motion->quantity == PrescribedMotion::Quantity::Velocity) {
    b.vx = p.motion->direction[0] * p.motion->history.at(0.0);
    b.vy = p.motion->direction[1] * p.motion->history.at(0.0);
  }
  polygons_.push_back(std::move(p));
  body_.push_back(std::move(b));
  friction_.clear();
}

void Contact::polygon_vertices(size_t k, std::vector<double>& x, std::vector<double>& y) const {
  const BodyState& b = body_[k];
  const double c = std::cos(b.angle), s = std::sin(b.angle);
  x.resize(b.local_x.size());
  y.resize(b.local_y.size());
  for (size_t m = 0; m < x.size(); ++m) {
    x[m] = b.cx + c * b.local_x[m] - s * b.local_y[m];
    y[m] = b.cy + s * b.local_x[m] + c * b.local_y[m];
  }
}

void Contact::compute_forces(const ParticleStateView& s, double dt) {
  const long long n = s.count;
  for (auto& f : force_n_) f.assign(n, 0.0);
  spring_energy_j_ = 0.0;
  contact_pairs_ = 0;
  if (particle_contact_on_) pair_forces(s, dt);
  if (!half_spaces_.empty() || !polygons_.empty()) obstacle_forces(s, dt);
}

double Contact::potential_energy_j(const ParticleStateView& s) const {
  double e = spring_energy_j_ + obstacle_penalty_energy_j(s);
  if (particle_contact_on_) e += pair_energy_j(s);
  return e;
}

// Cell list of edge >= the search radius d on the current positions, then for each
// particle the unbonded partners j > i closer than d (two passes, count then fill, parallel
// over i).
Contact::PairCandidates Contact::pair_candidates(const ParticleStateView& s) const {
  const long long n = s.count;
  const int dim = s.dimension;
  PairCandidates c;
  c.x.resize(3 * n);
  for (long long i = 0; i < n; ++i) {
    c.x[3 * i] = s.position_m[3 * i] + s.u.x[i];
    c.x[3 * i + 1] = s.position_m[3 * i + 1] + s.u.y[i];
    c.x[3 * i + 2] = s.position_m[3 * i + 2] + (dim == 3 ? s.u.z[i] : 0.0);
  }
  const std::vector<double>& x = c.x;
  const BondsView b = s.bonds;
  const bool distribution = particles_.normal == ContactNormal::NeighbourDistribution;
  // Planar face-face pairs reach one window sideways (contact_kernels.hpp).
  const double d = pair_search_radius(pair_params());
  CellGrid grid;  // common's cell list; axes beyond the dimension stay one cell
  // At most ~4N cells, so a particle flung far away cannot make the grid huge (cells then
  // grow beyond the contact distance, which stays correct).
  const double cap = std::pow(4.0 * static_cast<double>(std::max<long long>(n, 1)), 1.0 / dim);
  for (int a = 0; a < dim; ++a) {
    double mn = 1e300, mx = -1e300;
    for (long long i = 0; i < n; ++i) {
      mn = std::min(mn, x[3 * i + a]);
      mx = std::max(mx, x[3 * i + a]);
    }
    grid.origin[a] = mn;
    const double extent = std::max(mx - mn, 0.0);
    grid.count[a] =
        std::clamp<long long>(static_cast<long long>(std::floor(extent / d)), 1, static_cast<long long>(cap) + 1);
    grid.cell[a] = std::max(extent / grid.count[a], d);
  }
  const CellList cells = sort_into_cells(grid, x);
  const long long* count = grid.count;
  // visit(i, emit): every unbonded j > i within d of i.
  auto visit = [&](long long i, auto&& emit) {
    const long long ci[3] = {grid.coordinate(0, x[3 * i]), grid.coordinate(1, x[3 * i + 1]),
                             grid.coordinate(2, x[3 * i + 2])};
    for (long long cz = std::max(0LL, ci[2] - 1); cz <= std::min(count[2] - 1, ci[2] + 1); ++cz)
      for (long long cy = std::max(0LL, ci[1] - 1); cy <= std::min(count[1] - 1, ci[1] + 1); ++cy)
        for (long long cx = std::max(0LL, ci[0] - 1); cx <= std::min(count[0] - 1, ci[0] + 1); ++cx) {
          const long long cell_index = grid.index(cx, cy, cz);
          for (int64_t q = cells.start[cell_index]; q < cells.start[cell_index + 1]; ++q) {
            const int j = cells.members[q];
            if (j <= i) continue;
            const double dx[3] = {x[3 * i] - x[3 * j], x[3 * i + 1] - x[3 * j + 1], x[3 * i + 2] - x[3 * j + 2]};
            if (dx[0] * dx[0] + dx[1] * dx[1] + dx[2] * dx[2] >= d * d) continue;
            // Bonded now: a bond with nonzero weight (fracture.cpp cuts a bond by zeroing it,
            // so crack faces meet through contact).
            bool bonded = false;
            for (long long m = b.offset[i]; m < b.offset[i + 1] && !bonded; ++m)
              bonded = b.neighbour[m] == j && b.weight[m] != 0.0;
            if (!bonded) emit(j);
          }
        }
  };
  // One pass: each thread appends the pairs of its contiguous block of particles (static
  // schedule) to its own list; the lists joined in thread order are sorted by i, and each
  // particle's partners are sorted by j.
  std::vector<std::vector<std::array<int, 2>>> found(1);
#pragma omp parallel if (n > kContactParallelMin)
  {
#pragma omp single
    found.resize(omp_get_num_threads());
    std::vector<std::array<int, 2>>& mine = found[omp_get_thread_num()];
#pragma omp for schedule(static)
    for (long long i = 0; i < n; ++i) {
      const size_t from = mine.size();
      visit(i, [&](int j) { mine.push_back({static_cast<int>(i), j}); });
      std::sort(mine.begin() + from, mine.end());
    }
  }
  for (const auto& part : found) c.pairs.insert(c.pairs.end(), part.begin(), part.end());
  if (distribution) {  // surface directions of the particles in candidate pairs only
    c.surface.assign(3 * n, 0.0);
    std::vector<char> needed(n, 0);
    for (const auto& [i, j] : c.pairs) needed[i] = needed[j] = 1;
    for (long long i = 0; i < n; ++i)
      if (needed[i]) neighbour_distribution_direction(i, b, x.data(), &c.surface[3 * i]);
  }
  return c;
}

PairContactGeometry Contact::pair_geometry(const PairCandidates& c, int i, int j) const {
  const double dx[3] = {c.x[3 * i] - c.x[3 * j], c.x[3 * i + 1] - c.x[3 * j + 1], c.x[3 * i + 2] - c.x[3 * j + 2]};
  const bool distribution = particles_.normal == ContactNormal::NeighbourDistribution;
  return pair_contact_geometry(dx, distribution ? &c.surface[3 * i] : nullptr, distribution ? &c.surface[3 * j] : nullptr,
                               pair_params());
}

double Contact::pair_energy_j(const ParticleStateView& s) const {
  const PairCandidates c = pair_candidates(s);
  double energy = 0.0;
  for (const auto& [i, j] : c.pairs) {
    double f[3] = {0.0, 0.0, 0.0}, normal_force = 0.0;
    energy += pair_normal_force(pair_geometry(c, i, j), particles_.stiffness_n_m, f, &normal_force);
  }
  return energy;
}

// Each pair once (i < j): the force on i and minus it on j, so the pair forces are equal
// and opposite by construction (linear momentum exact). Serial over the pairs: they are
// surface pairs only, few against the solid's bond loop.
void Contact::pair_forces(const ParticleStateView& s, double dt) {
  const PairCandidates c = pair_candidates(s);
  const long long n = s.count;
  const bool friction = particles_.frictional();
  std::vector<long long> keys;
  std::vector<FrictionState> springs;
  size_t previous = 0;  // merge cursor into the springs of the last step (both sorted by key)
  for (const auto& [i, j] : c.pairs) {
    const PairContactGeometry g = pair_geometry(c, i, j);
    double f[3] = {0.0, 0.0, 0.0}, normal_force = 0.0;
    pair_normal_force(g, particles_.stiffness_n_m, f, &normal_force);
    if (normal_force <= 0.0) continue;
    ++contact_pairs_;
    if (friction) {
      const long long key = static_cast<long long>(i) * n + j;
      while (previous < pair_friction_key_.size() && pair_friction_key_[previous] < key) ++previous;
      FrictionState st = (previous < pair_friction_key_.size() && pair_friction_key_[previous] == key)
                             ? pair_friction_[previous]
                             : FrictionState{};
      const double v_rel[3] = {s.v.x[i] - s.v.x[j], s.v.y[i] - s.v.y[j],
                               s.dimension == 3 ? s.v.z[i] - s.v.z[j] : 0.0};
      const double k_t = particles_.tangential_stiffness_n_m * g.weight;
      dissipated_j_ += coulomb_tangential_force(st, g.n, v_rel, dt, normal_force, k_t, particles_.static_friction,
                                                particles_.kinetic_friction, f);
      spring_energy_j_ += 0.5 * k_t * (st.s[0] * st.s[0] + st.s[1] * st.s[1] + st.s[2] * st.s[2]);
      keys.push_back(key);
      springs.push_back(st);
    }
    for (int a = 0; a < 3; ++a) {
      force_n_[a][i] += f[a];
      force_n_[a][j] -= f[a];
    }
  }
  pair_friction_key_ = std::move(keys);
  pair_friction_ = std::move(springs);
}

void Contact::rigid_contact(long long i, long long slot, double depth, const double n[3], const double v_surface[3],
                            const RigidContactLaw& law, const ParticleStateView& s, double dt, double f[3]) {
  const double normal_force = law.normal_stiffness_n_m * depth;
  for (int a = 0; a < 3; ++a) f[a] += normal_force * n[a];
  rigid_friction(i, slot, normal_force, n, v_surface, law, s, dt, f);
}

bool Contact::particle_dashpots() const {
  return std::any_of(polygons_.begin(), polygons_.end(), [](const RigidPolygon& p) { return p.law.damping_ratio > 0.0; });
}

bool Contact::damped() const {
  return particle_dashpots() ||
         std::any_of(polygons_.begin(), polygons_.end(), [](const RigidPolygon& p) { return p.floor_damping_ratio > 0.0; });
}

// The dashpot's m_eff is the reduced mass of the particle and the polygon at the contact
// point along n: 1/m_eff = 1/m_i + 1/M + ((r x n)_z)^2 / I for a free polygon (r from its
// centroid: a rigid body's effective mass at a point), m_i for a fixed one. Then the particle,
// were it a rigid point on the polygon, would leave with the stated restitution.
// Work booking (as friction's, coulomb_tangential_force): in the leapfrog the force of step
// n does the work F_n . (v^n + v^n+1) dt / 2 on the relative motion; the first half,
// -c (v_n^n)^2 dt / 2, is booked now, the second at the next step (settle_dashpot).
void Contact::polygon_dashpot(long long i, long long slot, size_t p, double px, double py, const double n[3],
                              const double v_rel[3], double dt, double f[3]) {
  const RigidPolygon& poly = polygons_[p];
  double inverse_mass = 1.0 / particle_mass_kg_[i];
  if (!poly.fixed) {
    const double arm = (px - body_[p].cx) * n[1] - (py - body_[p].cy) * n[0];
    inverse_mass += 1.0 / poly.mass_kg + arm * arm / poly.inertia_kg_m2;
  }
  const double c = 2.0 * poly.law.damping_ratio * std::sqrt(poly.law.normal_stiffness_n_m / inverse_mass);
  const double vn = v_rel[0] * n[0] + v_rel[1] * n[1];
  const double force = -c * vn;  // along n: resists approach and separation alike
  f[0] += force * n[0];
  f[1] += force * n[1];
  dashpot_force_n_[slot * static_cast<long long>(particle_mass_kg_.size()) + i] = {force * n[0], force * n[1]};
  damping_dissipated_j_ -= 0.5 * force * vn * dt;
}

void Contact::settle_dashpot(long long index, const double v_rel[3], double dt) {
  std::array<double, 2>& last = dashpot_force_n_[index];
  if (last[0] == 0.0 && last[1] == 0.0) return;
  damping_dissipated_j_ -= 0.5 * (last[0] * v_rel[0] + last[1] * v_rel[1]) * dt;
  last = {0.0, 0.0};
}

void Contact::rigid_friction(long long i, long long slot, double normal_force, const double n[3],
                             const double v_surface[3], const RigidContactLaw& law, const ParticleStateView& s,
                             double dt, double f[3]) {
  if (!law.frictional()) return;
  const double v_rel[3] = {s.v.x[i] - v_surface[0], s.v.y[i] - v_surface[1],
                           (s.dimension == 3 ? s.v.z[i] : 0.0) - v_surface[2]};
  FrictionState& st = friction_[slot * s.count + i];
  dissipated_j_ += coulomb_tangential_force(st, n, v_rel, dt, normal_force, law.tangential_stiffness_n_m,
                                            law.static_friction, law.kinetic_friction, f);
  spring_energy_j_ += 0.5 * law.tangential_stiffness_n_m * (st.s[0] * st.s[0] + st.s[1] * st.s[1] + st.s[2] * st.s[2]);
}

// Rigid obstacles: a loop over particles per obstacle (few obstacles; the bounding-box test
// rejects most particles of a polygon at once). Serial, because the reactions on a free
// body are a sum over its particles.
void Contact::obstacle_forces(const ParticleStateView& s, double dt) {
  const long long n = s.count;
  const long long slots = static_cast<long long>(half_spaces_.size() + polygons_.size());
  if (friction_.size() != static_cast<size_t>(slots * n)) friction_.assign(slots * n, FrictionState{});
  auto current = [&](long long i, int a) {
    const double* u = a == 0 ? s.u.x : (a == 1 ? s.u.y : s.u.z);
    return s.position_m[3 * i + a] + ((a < s.dimension) ? u[i] : 0.0);
  };
  if (particle_dashpots()) {
    if (particle_mass_kg_.size() != static_cast<size_t>(n))
      throw std::logic_error("Contact: a damped polygon contact needs the particle masses (set_particle_masses)");
    if (dashpot_force_n_.size() != static_cast<size_t>(slots * n)) dashpot_force_n_.assign(slots * n, {0.0, 0.0});
  }
  plane_reaction_n_.assign(half_spaces_.size(), {0.0, 0.0, 0.0});
  for (size_t h = 0; h < half_spaces_.size(); ++h) {
    const PlaneContact plane = plane_contact(half_spaces_[h]);
    std::array<double, 3>& reaction = plane_reaction_n_[h];
    for (long long i = 0; i < n; ++i) {
      const double x[3] = {current(i, 0), current(i, 1), current(i, 2)};
      const double v[3] = {s.v.x[i], s.v.y[i], s.dimension == 3 ? s.v.z[i] : 0.0};
      double f[3] = {0.0, 0.0, 0.0};
      // The body the CUDA launcher runs too (solid_phases.hpp).
      if (half_space_contact_at(x, v, plane, dt, friction_[h * n + i], f, &dissipated_j_, &spring_energy_j_) <= 0.0)
        continue;
      for (int a = 0; a < 3; ++a) {
        force_n_[a][i] += f[a];
        reaction[a] -= f[a];
      }
    }
  }
  std::vector<double> vx, vy;
  for (size_t p = 0; p < polygons_.size(); ++p) {
    const RigidPolygon& poly = polygons_[p];
    BodyState& b = body_[p];
    b.fx = b.fy = b.torque = 0.0;
    polygon_vertices(p, vx, vy);
    const double x0 = *std::min_element(vx.begin(), vx.end()), x1 = *std::max_element(vx.begin(), vx.end());
    const double y0 = *std::min_element(vy.begin(), vy.end()), y1 = *std::max_element(vy.begin(), vy.end());
    const long long slot = static_cast<long long>(half_spaces_.size() + p);
    const bool dashpot = poly.law.damping_ratio > 0.0;
    for (long long i = 0; i < n; ++i) {
      const double px = current(i, 0), py = current(i, 1);
      double normal2[2] = {0.0, 0.0};
      const double depth = (px < x0 || px > x1 || py < y0 || py > y1)
                               ? 0.0
                               : polygon_penetration(vx.data(), vy.data(), static_cast<int>(vx.size()), px, py, normal2);
      const double v_surface[3] = {b.vx - b.omega * (py - b.cy), b.vy + b.omega * (px - b.cx), 0.0};
      const double v_rel[3] = {s.v.x[i] - v_surface[0], s.v.y[i] - v_surface[1], 0.0};
      if (dashpot) settle_dashpot(slot * n + i, v_rel, dt);
      if (depth <= 0.0) {
        dissipated_j_ += release_friction_spring(friction_[slot * n + i], v_rel, dt, poly.law.tangential_stiffness_n_m);
        continue;
      }
      // The penalty pushes the particle out towards the nearest boundary point.
      const double nrm[3] = {normal2[0], normal2[1], 0.0};
      double f[3] = {0.0, 0.0, 0.0};
      rigid_contact(i, slot, depth, nrm, v_surface, poly.law, s, dt, f);
      if (dashpot) polygon_dashpot(i, slot, p, px, py, nrm, v_rel, dt, f);
      for (int a = 0; a < 3; ++a) force_n_[a][i] += f[a];
      // Equal and opposite reaction at the particle's position.
      b.fx -= f[0];
      b.fy -= f[1];
      b.torque -= (px - b.cx) * f[1] - (py - b.cy) * f[0];
    }
  }
  free_bodies_on_half_spaces(dt);
  if (polygons_.size() > 1) {
    std::vector<std::array<double, 3>> reactions(polygons_.size(), {0.0, 0.0, 0.0});
    polygon_pairs(&reactions);
    for (size_t p = 0; p < polygons_.size(); ++p) {
      body_[p].fx += reactions[p][0];
      body_[p].fy += reactions[p][1];
      body_[p].torque += reactions[p][2];
    }
  }
}

// Vertices only, as for the floor: two edges crossing with no vertex inside the other body
// are not seen (fine for bodies that meet face to face or corner first and do not pass
// through each other within a step).
double Contact::polygon_pairs(std::vector<std::array<double, 3>>* reactions) const {
  double energy = 0.0;
  std::vector<double> ax, ay, bx, by;
  for (size_t p = 0; p < polygons_.size(); ++p)
    for (size_t q = p + 1; q < polygons_.size(); ++q) {
      if (polygons_[p].fixed && polygons_[q].fixed) continue;
      const double kp = polygons_[p].law.normal_stiffness_n_m, kq = polygons_[q].law.normal_stiffness_n_m;
      if (!(kp > 0.0) || !(kq > 0.0)) continue;
      const double k = kp * kq / (kp + kq);
      polygon_vertices(p, ax, ay);
      polygon_vertices(q, bx, by);
      // Vertices of `from` (body f) inside `into` (body t): the force on f pushes the vertex out.
      auto push = [&](size_t f, const std::vector<double>& fx, const std::vector<double>& fy, size_t t,
                      const std::vector<double>& tx, const std::vector<double>& ty) {
        for (size_t m = 0; m < fx.size(); ++m) {
          double normal[2];
          const double depth =
              polygon_penetration(tx.data(), ty.data(), static_cast<int>(tx.size()), fx[m], fy[m], normal);
          if (depth <= 0.0) continue;
          energy += 0.5 * k * depth * depth;
          if (!reactions) continue;
          const double force[2] = {k * depth * normal[0], k * depth * normal[1]};
          std::array<double, 3>& a = (*reactions)[f];
          std::array<double, 3>& b = (*reactions)[t];
          a[0] += force[0];
          a[1] += force[1];
          a[2] += (fx[m] - body_[f].cx) * force[1] - (fy[m] - body_[f].cy) * force[0];
          b[0] -= force[0];
          b[1] -= force[1];
          b[2] -= (fx[m] - body_[t].cx) * force[1] - (fy[m] - body_[t].cy) * force[0];
        }
      };
      push(p, ax, ay, q, bx, by);
      push(q, bx, by, p, ax, ay);
    }
  return energy;
}

// Free rigid polygons on the half-spaces (the floor): each vertex below a plane is pushed
// out with the plane's penalty and friction law, as a particle would be, the force acting
// at the vertex. Vertices only: an edge crossing the plane between two vertices above it
// is not seen (fine for a body resting on or bouncing off the plane).
void Contact::free_bodies_on_half_spaces(double dt) {
  size_t vertices = 0;
  for (const auto& poly : polygons_) vertices += poly.x_m.size();
  if (vertex_friction_.size() != half_spaces_.size() * vertices)
    vertex_friction_.assign(half_spaces_.size() * vertices, FrictionState{});
  if (vertex_dashpot_force_n_.size() != half_spaces_.size() * vertices)
    vertex_dashpot_force_n_.assign(half_spaces_.size() * vertices, {0.0, 0.0});
  std::vector<double> vx, vy;
  size_t first = 0;
  for (size_t p = 0; p < polygons_.size(); first += polygons_[p].x_m.size(), ++p) {
    if (polygons_[p].fixed) continue;
    BodyState& b = body_[p];
    polygon_vertices(p, vx, vy);
    for (size_t h = 0; h < half_spaces_.size(); ++h) {
      const HalfSpace& hs = half_spaces_[h];
      const PlaneContact plane = plane_contact(hs);
      for (size_t m = 0; m < vx.size(); ++m) {
        FrictionState& st = vertex_friction_[h * vertices + first + m];
        const double height = (vx[m] - plane.point[0]) * hs.normal[0] + (vy[m] - plane.point[1]) * hs.normal[1] -
                              plane.point[2] * hs.normal[2];
        // Relative to the plane (which may be moving: ground motion).
        const double v_vertex[3] = {b.vx - b.omega * (vy[m] - b.cy) - plane.velocity[0],
                                    b.vy + b.omega * (vx[m] - b.cx) - plane.velocity[1], -plane.velocity[2]};
        // The second half step of the last dashpot force's work (as settle_dashpot).
        std::array<double, 2>& last = vertex_dashpot_force_n_[h * vertices + first + m];
        if (last[0] != 0.0 || last[1] != 0.0) {
          damping_dissipated_j_ -= 0.5 * (last[0] * v_vertex[0] + last[1] * v_vertex[1]) * dt;
          last = {0.0, 0.0};
        }
        if (height >= 0.0) {
          dissipated_j_ += release_friction_spring(st, v_vertex, dt, hs.law.tangential_stiffness_n_m);
          continue;
        }
        const double normal_force = -hs.law.normal_stiffness_n_m * height;
        double f[3] = {normal_force * hs.normal[0], normal_force * hs.normal[1], normal_force * hs.normal[2]};
        if (polygons_[p].floor_damping_ratio > 0.0) {
          // The vertex's normal dashpot, c = 2 zeta sqrt(k m_eff) with the body's effective
          // mass at the vertex along n, 1/m_eff = 1/M + ((r x n)_z)^2 / I: the vertex striking
          // the floor alone leaves it with the stated restitution. Friction's N stays k g.
          const double arm = (vx[m] - b.cx) * hs.normal[1] - (vy[m] - b.cy) * hs.normal[0];
          const double inverse_mass = 1.0 / polygons_[p].mass_kg + arm * arm / polygons_[p].inertia_kg_m2;
          const double c = 2.0 * polygons_[p].floor_damping_ratio * std::sqrt(hs.law.normal_stiffness_n_m / inverse_mass);
          const double vn = v_vertex[0] * hs.normal[0] + v_vertex[1] * hs.normal[1] + v_vertex[2] * hs.normal[2];
          const double force = -c * vn;
          for (int a = 0; a < 3; ++a) f[a] += force * hs.normal[a];
          last = {force * hs.normal[0], force * hs.normal[1]};
          damping_dissipated_j_ -= 0.5 * force * vn * dt;
        }
        if (hs.law.frictional()) {
          dissipated_j_ += coulomb_tangential_force(st, hs.normal.data(), v_vertex, dt, normal_force,
                                                    hs.law.tangential_stiffness_n_m, hs.law.static_friction,
                                                    hs.law.kinetic_friction, f);
          spring_energy_j_ +=
              0.5 * hs.law.tangential_stiffness_n_m * (st.s[0] * st.s[0] + st.s[1] * st.s[1] + st.s[2] * st.s[2]);
        }
        b.fx += f[0];
        b.fy += f[1];
        b.torque += (vx[m] - b.cx) * f[1] - (vy[m] - b.cy) * f[0];
        for (int a = 0; a < 3; ++a) plane_reaction_n_[h][a] -= f[a];
      }
    }
  }
}

double Contact::obstacle_penalty_energy_j(const ParticleStateView& s) const {
  double e = 0.0;
  auto current = [&](long long i, int a) {
    const double* u = a == 0 ? s.u.x : (a == 1 ? s.u.y : s.u.z);
    return s.position_m[3 * i + a] + ((a < s.dimension) ? u[i] : 0.0);
  };
  for (const HalfSpace& hs : half_spaces_)
    for (long long i = 0; i < s.count; ++i) {
      double height = 0.0;
      for (int a = 0; a < 3; ++a) height += (current(i, a) - hs.point_m[a] - hs.offset_m[a]) * hs.normal[a];
      if (height < 0.0) e += 0.5 * hs.law.normal_stiffness_n_m * height * height;
    }
  std::vector<double> vx, vy;
  for (size_t p = 0; p < polygons_.size(); ++p) {
    polygon_vertices(p, vx, vy);
    for (long long i = 0; i < s.count; ++i) {
      double normal2[2];
      const double depth =
          polygon_penetration(vx.data(), vy.data(), static_cast<int>(vx.size()), current(i, 0), current(i, 1), normal2);
      e += 0.5 * polygons_[p].law.normal_stiffness_n_m * depth * depth;
    }
    if (polygons_[p].fixed) continue;
    for (const HalfSpace& hs : half_spaces_) {  // free bodies' vertices on the planes
      const PlaneContact plane = plane_contact(hs);
      for (size_t m = 0; m < vx.size(); ++m) {
        const double height = (vx[m] - plane.point[0]) * hs.normal[0] + (vy[m] - plane.point[1]) * hs.normal[1] -
                              plane.point[2] * hs.normal[2];
        if (height < 0.0) e += 0.5 * hs.law.normal_stiffness_n_m * height * height;
      }
    }
  }
  if (polygons_.size() > 1) e += polygon_pairs(nullptr);
  return e;
}

void Contact::advance_rigid_bodies(double dt, const std::array<double, 3>& g) {
  for (size_t p = 0; p < polygons_.size(); ++p) {
    if (polygons_[p].fixed) continue;
    BodyState& b = body_[p];
    const RigidPolygon& poly = polygons_[p];
    b.vx += dt * (b.fx / poly.mass_kg + g[0]);
    b.vy += dt * (b.fy / poly.mass_kg + g[1]);
    b.omega += dt * b.torque / poly.inertia_kg_m2;
    b.cx += dt * b.vx;
    b.cy += dt * b.vy;
    b.angle += dt * b.omega;
  }
}

namespace {
// Velocity and displacement increment of a prescribed motion over [t, t + dt], the same
// symplectic Euler step the solid takes (v += dt a, then x += dt v); a displacement history
// is followed exactly, its velocity the step's mean.
void advance_motion(const PrescribedMotion& m, double t, double dt, double offset_along, double& velocity_along,
                    double& step_along) {
  switch (m.quantity) {
    case PrescribedMotion::Quantity::Acceleration:
      velocity_along += dt * m.history.at(t);
      step_along = dt * velocity_along;
      break;
    case PrescribedMotion::Quantity::Velocity:
      velocity_along = m.history.at(t + dt);
      step_along = dt * velocity_along;
      break;
    case PrescribedMotion::Quantity::Displacement:
      step_along = m.history.at(t + dt) - offset_along;
      velocity_along = step_along / dt;
      break;
  }
}
double along(const std::array<double, 3>& v, const std::array<double, 3>& d) { return v[0] * d[0] + v[1] * d[1] + v[2] * d[2]; }

// The ground's work of a step, centred as the friction's and the dashpots' are: the reaction
// R_n of the positions at t_n acts over the half steps on either side of them, so it is booked
// on the mean of the motion's last step and this one (R_n (D_{n+1} - D_{n-1}) / 2). Booked on
// this step alone (R_n (D_{n+1} - D_n)), a block carried at a steady acceleration a gained
// m a^2 t dt / 2 more work than kinetic energy. Before the first step the last one is the
// motion's velocity at the start times dt (0 from rest). Updates last_step.
double centred_step(double& last_step, double step, double start_velocity, double dt) {
  const double previous = std::isnan(last_step) ? start_velocity * dt : last_step;
  last_step = step;
  return 0.5 * (previous + step);
}
}  // namespace

bool Contact::moving_obstacles() const {
  for (const auto& h : half_spaces_)
    if (h.motion) return true;
  for (const auto& p : polygons_)
    if (p.motion) return true;
  return false;
}

void Contact::advance_obstacles(double t, double dt) {
  for (size_t h = 0; h < half_spaces_.size(); ++h) {
    HalfSpace& hs = half_spaces_[h];
    if (!hs.motion) continue;
    const auto& d = hs.motion->direction;
    double v = along(hs.velocity_m_s, d), step = 0.0;
    const double v_start = v;
    advance_motion(*hs.motion, t, dt, along(hs.offset_m, d), v, step);
    const double booked = centred_step(hs.last_step_m, step, v_start, dt);
    for (int a = 0; a < 3; ++a) {
      // The ground pushes the bodies with minus the reaction.
      ground_work_j_ -= plane_reaction_n_[h][a] * booked * d[a];
      hs.offset_m[a] += step * d[a];
      hs.velocity_m_s[a] = v * d[a];
    }
  }
  for (size_t p = 0; p < polygons_.size(); ++p) {
    const RigidPolygon& poly = polygons_[p];
    if (!poly.fixed || !poly.motion) continue;
    BodyState& b = body_[p];
    const auto& d = poly.motion->direction;
    double v = b.vx * d[0] + b.vy * d[1], step = 0.0;
    const double v_start = v;
    advance_motion(*poly.motion, t, dt, (b.cx - b.cx0) * d[0] + (b.cy - b.cy0) * d[1], v, step);
    ground_work_j_ -= (b.fx * d[0] + b.fy * d[1]) * centred_step(b.last_step_m, step, v_start, dt);
    b.cx += step * d[0];
    b.cy += step * d[1];
    b.vx = v * d[0];
    b.vy = v * d[1];
  }
}

double Contact::rigid_kinetic_energy_j() const {
  double e = 0.0;
  for (size_t p = 0; p < polygons_.size(); ++p) {
    if (polygons_[p].fixed) continue;
    const BodyState& b = body_[p];
    e += 0.5 * polygons_[p].mass_kg * (b.vx * b.vx + b.vy * b.vy) + 0.5 * polygons_[p].inertia_kg_m2 * b.omega * b.omega;
  }
  return e;
}

double Contact::rigid_gravity_energy_j(const std::array<double, 3>& g) const {
  double e = 0.0;
  for (size_t p = 0; p < polygons_.size(); ++p) {
    if (polygons_[p].fixed) continue;
    const BodyState& b = body_[p];
    e -= polygons_[p].mass_kg * (g[0] * (b.cx - b.cx0) + g[1] * (b.cy - b.cy0));
  }
  return e;
}

std::array<double, 2> Contact::rigid_momentum() const {
  std::array<double, 2> m{0.0, 0.0};
  for (size_t p = 0; p < polygons_.size(); ++p) {
    if (polygons_[p].fixed) continue;
    m[0] += polygons_[p].mass_kg * body_[p].vx;
    m[1] += polygons_[p].mass_kg * body_[p].vy;
  }
  return m;
}

}  // namespace breccia::mps
