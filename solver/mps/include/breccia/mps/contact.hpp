#pragma once
#include <cmath>
#include <limits>
// Contact of the stress-based MPS solid (solid.hpp; [Inagaki 2009], docs/references.md):
//  - between particles that are not bonded (different bodies, or parts of one body far
//    apart in the reference configuration) once they come within the contact distance in
//    the current configuration (a cut bond, weight 0, no longer counts as a bond): a cell
//    list on the current positions, rebuilt every step (O(N)), and a penalty force along
//    the pair direction or the neighbour-distribution normal (contact_kernels.hpp), with
//    optional Coulomb friction per pair;
//  - with rigid obstacles: half-spaces (the floor) and 2D polygons, fixed or free rigid
//    bodies (mass, moment of inertia, translation and rotation), with Coulomb friction;
//    free polygons also rest on the half-spaces through their vertices.
// The solid calls compute_forces() once per step before its force loop, adds force(a)[i],
// and advance_rigid_bodies() after its own update (the same symplectic Euler step).
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "breccia/mps/contact_spec.hpp"

#include "breccia/mps/contact_grid.hpp"
#include "breccia/mps/contact_kernels.hpp"
#include "breccia/mps/kernels.hpp"
#include "breccia/mps/solid_phases.hpp"

namespace breccia::mps {

// Direction of the contact force between two particles (contact_kernels.hpp).
enum class ContactNormal {
  Pair,                  // line of centres, penetration d - r (central force)
  NeighbourDistribution  // from both particles' neighbour distributions (the thesis' normal)
};

// Contact between particles that are not bonded (contact_kernels.hpp).
struct ParticleContact {
  double distance_m = 0.0;     // centres closer than this repel (default: one spacing, particles touching)
  double stiffness_n_m = 0.0;  // penalty k per pair
  ContactNormal normal = ContactNormal::Pair;
  double window_m = 0.0;       // NeighbourDistribution: tangential hat width (the spacing; 0: distance_m)
  // Coulomb friction between the particles (as RigidContactLaw; k_t per pair, times the
  // pair's weight with NeighbourDistribution).
  double tangential_stiffness_n_m = 0.0;
  double static_friction = 0.0, kinetic_friction = 0.0;
  std::vector<int> body_id;    // per particle (may be empty: one body)
  bool frictional() const { return static_friction > 0.0 || kinetic_friction > 0.0; }
};

// Friction and penalty stiffness of one rigid obstacle (per contacting particle).
struct RigidContactLaw {
  double normal_stiffness_n_m = 0.0;
  double tangential_stiffness_n_m = 0.0;
  double static_friction = 0.0;   // mu_s
  double kinetic_friction = 0.0;  // mu_k <= mu_s
  // Normal dashpot (polygons only): c = 2 zeta sqrt(k m_eff) per contacting particle, zeta
  // from the stated restitution (damping_ratio_of_restitution); 0: undamped.
  double damping_ratio = 0.0;
  bool frictional() const { return static_friction > 0.0 || kinetic_friction > 0.0; }
};

// Allowed side {x : (x - point) . normal >= 0}; particle centres below it are pushed out.
struct HalfSpace {
  std::array<double, 3> point_m{0.0, 0.0, 0.0};
  std::array<double, 3> normal{0.0, 1.0, 0.0};  // normalised by add_half_space
  RigidContactLaw law;
  std::optional<PrescribedMotion> motion;
  // Where the motion has taken it (Contact keeps these): offset of point_m and velocity.
  std::array<double, 3> offset_m{0.0, 0.0, 0.0}, velocity_m_s{0.0, 0.0, 0.0};
  // The motion's last step along its direction (m; NaN before the first): the ground work's
  // centred booking (Contact::advance_obstacles).
  double last_step_m = std::numeric_limits<double>::quiet_NaN();
};

// The plane and its law as the per-particle body half_space_contact_at takes them.
inline PlaneContact plane_contact(const HalfSpace& h) {
  PlaneContact p;
  for (int a = 0; a < 3; ++a) {
    p.point[a] = h.point_m[a] + h.offset_m[a];
    p.normal[a] = h.normal[a];
    p.velocity[a] = h.velocity_m_s[a];
  }
  p.normal_stiffness = h.law.normal_stiffness_n_m;
  p.tangential_stiffness = h.law.tangential_stiffness_n_m;
  p.static_friction = h.law.static_friction;
  p.kinetic_friction = h.law.kinetic_friction;
  return p;
}

// A 2D rigid polygon: vertices in order (either orientation), closed implicitly. Particle
// centres inside it are pushed out to the nearest boundary point. A free body moves under
// the contact reactions and gravity (translation and rotation about its centroid).
struct RigidPolygon {
  std::string name;
  std::vector<double> x_m, y_m;  // vertices, world frame at t = 0
  bool fixed = true;
  double mass_kg = 0.0, inertia_kg_m2 = 0.0;  // free bodies: about the centroid
  std::array<double, 2> velocity_m_s{0.0, 0.0};
  double angular_velocity_rad_s = 0.0;
  RigidContactLaw law;
  // Free bodies: damping ratio of the normal dashpot of each vertex on the half-spaces (from
  // the stated floor_restitution, damping_ratio_of_restitution); 0: undamped.
  double floor_damping_ratio = 0.0;
  std::optional<PrescribedMotion> motion;  // fixed bodies only: ground motion (translation)
};

// Area, centroid and polar second moment of area about the centroid of a simple polygon.
struct PolygonGeometry {
  double area_m2 = 0.0;
  double cx_m = 0.0, cy_m = 0.0;
  double polar_moment_m4 = 0.0;  // integral of |x - c|^2 dA
};
PolygonGeometry polygon_geometry(const std::vector<double>& x, const std::vector<double>& y);

// Current state of the particles, as the solid holds it.
struct ParticleStateView {
  int dimension = 2;
  long long count = 0;
  const double* position_m = nullptr;  // 3N reference positions
  VectorField u, v;
  BondsView bonds;                     // pairs bonded now do not contact
};

class Contact {
public:
  bool active() const { return particle_contact_on_ || !half_spaces_.empty() || !polygons_.empty(); }
  bool particle_contact() const { return particle_contact_on_; }
  const ParticleContact& particle_settings() const { return particles_; }
  // The pair law as the per-particle bodies of contact_grid.hpp take it.
  PairContactParams pair_params() const {
    return {particles_.distance_m, window_m(), particles_.stiffness_n_m,
            particles_.normal == ContactNormal::NeighbourDistribution ? 1 : 0};
  }
  void set_particle_contact(ParticleContact pc);
  void add_half_space(HalfSpace h);
  const std::vector<HalfSpace>& half_spaces() const { return half_spaces_; }
  void add_polygon(RigidPolygon p);

  // Contact forces on every particle at the current state (force(a)[i], N); updates the
  // friction springs with the step dt and collects the reactions on free rigid bodies.
  void compute_forces(const ParticleStateView& s, double dt);
  const std::vector<double>& force(int axis) const { return force_n_[axis]; }
  // Symplectic Euler step of the free rigid bodies under the reactions of the last
  // compute_forces() and gravity: v += dt a, then x += dt v.
  void advance_rigid_bodies(double dt, const std::array<double, 3>& gravity_m_s2);
  // Moves the obstacles with a prescribed motion from time t to t + dt (after
  // advance_rigid_bodies, the same step) and books the work their reactions of the last
  // compute_forces() do: ground_work_j(), the energy the moving ground puts in.
  void advance_obstacles(double t, double dt);
  bool moving_obstacles() const;
  double ground_work_j() const { return ground_work_j_; }
  // Force the bodies pushed half-space h with at the last compute_forces() (N; host runs
  // only: a device computes the plane contact itself and leaves this at zero).
  const std::array<double, 3>& plane_reaction_n(size_t h) const { return plane_reaction_n_[h]; }

  // Penalty energy of all contacts in the state s, plus the energy stored in the friction
  // springs (as left by the last compute_forces()).
  double potential_energy_j(const ParticleStateView& s) const;
  double friction_dissipation_j() const { return dissipated_j_; }
  // Particle masses (kg), needed by a damped polygon contact (its dashpot's m_eff).
  void set_particle_masses(std::vector<double> mass_kg) { particle_mass_kg_ = std::move(mass_kg); }
  // Some polygon has a normal dashpot: on the particles (RigidContactLaw::damping_ratio > 0)
  // or on its vertices' floor contacts (floor_damping_ratio > 0).
  bool damped() const;
  // Energy the normal dashpots have removed (J): the work of each step's dashpot force over
  // the leapfrog's two half steps around it (obstacle_forces, free_bodies_on_half_spaces).
  double contact_damping_j() const { return damping_dissipated_j_; }
  // With the contact run on a device (Solid::attach_device): the totals it reports replace
  // those compute_forces() would have left.
  void set_device_totals(double spring_energy_j, double dissipated_j, long long contact_pairs) {
    spring_energy_j_ = spring_energy_j;
    dissipated_j_ = dissipated_j;
    contact_pairs_ = contact_pairs;
  }
  // The friction springs of the rigid obstacles as the last compute_forces() left them, one
  // per particle and obstacle (half-spaces first, then polygons; empty before the first).
  const std::vector<FrictionState>& obstacle_springs() const { return friction_; }
  double rigid_kinetic_energy_j() const;
  double rigid_gravity_energy_j(const std::array<double, 3>& gravity_m_s2) const;  // -m g . (c - c0)
  long long contact_pairs() const { return contact_pairs_; }

  size_t polygon_count() const { return polygons_.size(); }
  const RigidPolygon& polygon(size_t k) const { return polygons_[k]; }
  // Vertices of polygon k in the current position (world frame).
  void polygon_vertices(size_t k, std::vector<double>& x, std::vector<double>& y) const;
  std::array<double, 2> polygon_centroid_m(size_t k) const { return {body_[k].cx, body_[k].cy}; }
  double polygon_angle_rad(size_t k) const { return body_[k].angle; }
  // Linear momentum of the free rigid bodies (kg m/s).
  std::array<double, 2> rigid_momentum() const;

private:
  struct BodyState {
    double cx = 0.0, cy = 0.0, cx0 = 0.0, cy0 = 0.0, angle = 0.0;
    double vx = 0.0, vy = 0.0, omega = 0.0;
    double fx = 0.0, fy = 0.0, torque = 0.0;  // reactions of the last compute_forces()
    double last_step_m = std::numeric_limits<double>::quiet_NaN();  // a moving fixed polygon's (HalfSpace's)
    std::vector<double> local_x, local_y;     // vertices relative to the centroid at angle 0
  };
  // Particle pairs in contact candidates: current positions, surface directions (for the
  // distribution normal) and the unbonded pairs i < j within reach, sorted by (i, j).
  struct PairCandidates {
    std::vector<double> x, surface;       // 3N each
    std::vector<std::array<int, 2>> pairs;
  };
  PairCandidates pair_candidates(const ParticleStateView& s) const;
  PairContactGeometry pair_geometry(const PairCandidates& c, int i, int j) const;
  double window_m() const { return particles_.window_m > 0.0 ? particles_.window_m : particles_.distance_m; }
  // Penalty energy of the particle pairs in state s (friction springs not included).
  double pair_energy_j(const ParticleStateView& s) const;
  // Pair forces (normal penalty and friction) into force_n_; updates the pair friction springs.
  void pair_forces(const ParticleStateView& s, double dt);
  void obstacle_forces(const ParticleStateView& s, double dt);
  double obstacle_penalty_energy_j(const ParticleStateView& s) const;
  void free_bodies_on_half_spaces(double dt);
  // Contact between two rigid polygons (at least one free): each vertex of one inside the
  // other is pushed out to the nearest boundary point, k g, equal and opposite at the vertex
  // on both bodies; k the two laws' normal stiffnesses in series. Frictionless. Adds the
  // reactions (fx, fy, torque per polygon) to *reactions when given; returns the penalty energy.
  double polygon_pairs(std::vector<std::array<double, 3>>* reactions) const;
  void rigid_contact(long long i, long long slot, double depth, const double n[3], const double v_surface[3],
                     const RigidContactLaw& law, const ParticleStateView& s, double dt, double f[3]);
  // The normal dashpot of particle i on polygon p (law.damping_ratio > 0) at the particle's
  // position (px, py): adds -c (v_rel . n) n to f, books the first half step of its work and
  // keeps the force for the second (settle_dashpot at the next step).
  void polygon_dashpot(long long i, long long slot, size_t p, double px, double py, const double n[3],
                       const double v_rel[3], double dt, double f[3]);
  // Books the work of particle slot's last dashpot force over the half step after it
  // (velocity v_rel relative to the surface now) and clears it.
  void settle_dashpot(long long index, const double v_rel[3], double dt);
  // Some polygon has a dashpot on its particle contacts (needs the particle masses).
  bool particle_dashpots() const;
  // The Coulomb part of rigid_contact (normal_force = the normal penalty's size).
  void rigid_friction(long long i, long long slot, double normal_force, const double n[3], const double v_surface[3],
                      const RigidContactLaw& law, const ParticleStateView& s, double dt, double f[3]);

  bool particle_contact_on_ = false;
  ParticleContact particles_;
  std::vector<HalfSpace> half_spaces_;
  std::vector<RigidPolygon> polygons_;
  std::vector<BodyState> body_;
  std::array<std::vector<double>, 3> force_n_;
  // Friction springs, one per particle and obstacle (half-spaces first, then polygons).
  std::vector<FrictionState> friction_;
  // Friction springs of free polygons' vertices on the half-spaces (half-space major).
  std::vector<FrictionState> vertex_friction_;
  // Friction springs of the particle pairs in contact at the last step, sorted by key
  // i * N + j (i < j); a pair that leaves contact loses its spring.
  std::vector<long long> pair_friction_key_;
  std::vector<FrictionState> pair_friction_;
  double spring_energy_j_ = 0.0, dissipated_j_ = 0.0;
  // Normal dashpots: particle masses, the last step's dashpot force per particle and
  // obstacle (x, y; as friction_), and the energy they removed.
  std::vector<double> particle_mass_kg_;
  std::vector<std::array<double, 2>> dashpot_force_n_;
  // The last step's dashpot force per free polygon vertex and half-space (as vertex_friction_).
  std::vector<std::array<double, 2>> vertex_dashpot_force_n_;
  double damping_dissipated_j_ = 0.0;
  long long contact_pairs_ = 0;
  // Reaction on each half-space (the force the particles and free bodies' vertices push it
  // with) from the last compute_forces(), and the work the moving obstacles have done.
  std::vector<std::array<double, 3>> plane_reaction_n_;
  double ground_work_j_ = 0.0;
};

}  // namespace breccia::mps
