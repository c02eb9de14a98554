#pragma once
// Case-file keys for several bodies and contact in the stress formulation (docs/mps.md,
// "Contact"): specimen.bodies (shapes with their own initial velocity), contact.particles
// (contact between unbonded particles) and contact.rigid_bodies (2D polygons, fixed or
// free, with Coulomb friction). Plain structs, SI after parsing (contact_spec.cpp).
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "breccia/solver/history.hpp"

namespace breccia {
class Section;
}

namespace breccia::mps {

// One body of specimen.bodies: a lattice box, an annulus of particles on concentric
// circles (inner_radius 0: a disc), which follows both round surfaces, or (3D) a cylinder
// along z: the cubic lattice cut to it (a staircase surface, as a Taylor bar is set up).
struct BodyShapeSpec {
  std::string name;
  std::string type;                  // box | annulus | cylinder
  std::array<double, 6> box_m{};     // box: x0 y0 z0 x1 y1 z1
  std::array<double, 3> center_m{};  // annulus: centre; cylinder: centre of the lower end face
  double inner_radius_m = 0.0, outer_radius_m = 0.0;  // annulus; cylinder: outer_radius_m = radius
  double length_m = 0.0;             // cylinder: along +z from center_m
  std::array<double, 3> velocity_m_s{};  // initial velocity of the body (added to initial.velocity)
};

struct BodiesSpec {
  int dimension = 2;
  double spacing_m = 0.0;
  double thickness_m = 1.0;  // 2D out-of-plane thickness
  std::vector<BodyShapeSpec> shapes;
};

// Coulomb friction of a surface (floor, polygon, or between particle bodies).
struct FrictionSpec {
  double static_friction = 0.0;   // mu_s >= 0
  double kinetic_friction = 0.0;  // 0 <= mu_k <= mu_s (default mu_s)
  double tangential_stiffness_factor = 1.0;  // k_t = factor mu A / spacing
};

// Contact between particles that are not bonded (contact.hpp).
struct ParticleContactSpec {
  double distance_factor = 1.0;   // contact distance / spacing
  double stiffness_factor = 1.0;  // k = factor (lambda + 2 mu) A / spacing per pair
  std::string normal = "pair";  // pair | neighbour_distribution (contact.hpp, ContactNormal)
  FrictionSpec friction;          // between the particles (default none)
};

// Prescribed motion of a rigid obstacle (ground motion: the floor or a fixed polygon): it
// translates along `direction` with the history as its displacement, velocity or
// acceleration (SI), starting at rest at its given position (a velocity history: at h(0)).
// Contact::advance_obstacles integrates it with the solid's own step.
struct PrescribedMotion {
  enum class Quantity { Displacement, Velocity, Acceleration };
  Quantity quantity = Quantity::Acceleration;
  std::array<double, 3> direction{1.0, 0.0, 0.0};  // unit
  solver::HistorySpec history;
};

// Plane-strain Lame constants of Young's modulus and Poisson's ratio (-1 < nu < 0.5):
// lambda = E nu / ((1 + nu)(1 - 2 nu)), mu = E / (2 (1 + nu)).
struct LameConstants {
  double lambda_pa = 0.0, mu_pa = 0.0;
};
LameConstants lame_of_youngs(double youngs_modulus_pa, double poisson_ratio);

// A rigid polygon's contact layer (contact.rigid_bodies[k].contact_layer): the polygon is
// rigid, so its own local compliance at a contact is absent; it is stood in for by an elastic
// layer of the polygon's material and a stated thickness, a Winkler (bed of springs) law per
// unit area of contact: normal (lambda + 2 mu) / thickness (the constrained modulus of the
// layer over its thickness), tangential mu / thickness. Per particle the penalty is that
// times the particle's face area, so the stiffness per unit area of a face is a property of
// the materials and does not change when the spacing is refined (docs/mps.md).
struct ContactLayerSpec {
  double youngs_modulus_pa = 0.0, poisson_ratio = 0.0, thickness_m = 0.0;
  double normal_stiffness_pa_m() const;      // (lambda + 2 mu) / thickness
  double tangential_stiffness_pa_m() const;  // mu / thickness
};

// A 2D rigid polygon (contact.hpp, RigidPolygon).
struct RigidBodySpec {
  std::string name;
  std::vector<double> x_m, y_m;  // vertices in order, closed implicitly
  bool fixed = true;
  double density_kg_m3 = 0.0;    // free bodies: mass = density * area * thickness
  std::array<double, 3> velocity_m_s{};
  double angular_velocity_rad_s = 0.0;
  double stiffness_factor = 1.0;  // penalty k = factor (lambda + 2 mu) A / spacing
  // > 0: the penalty per unit contact area is set by this length instead of the spacing,
  // k = factor (lambda + 2 mu) A / stiffness_length (and k_t likewise), so the polygon's
  // contact stiffness per unit area of a face does not change when the spacing is refined.
  double stiffness_length_m = 0.0;
  // Given: the penalty per unit area is the layer's (stiffness_factor and
  // tangential_stiffness_factor still scale it); exclusive with stiffness_length.
  std::optional<ContactLayerSpec> contact_layer;
  // Coefficient of restitution of a particle's normal impact on the polygon, 0 < e <= 1: a
  // normal dashpot in the penalty contact (contact_kernels.hpp,
  // damping_ratio_of_restitution); 1 (the default): no dashpot.
  double restitution = 1.0;
  // Free bodies: coefficient of restitution of the polygon's vertices on the floor (the
  // half-spaces), 0 < e <= 1: a normal dashpot in the vertex contact, c = 2 zeta sqrt(k m_eff)
  // with m_eff the body's effective mass at the vertex; 1 (the default): no dashpot.
  double floor_restitution = 1.0;
  FrictionSpec friction;
  std::optional<PrescribedMotion> motion;  // fixed bodies only
};

// Parsers (throw InputError naming the file and field).
BodiesSpec parse_bodies(const Section& s);
ParticleContactSpec parse_particle_contact(const Section& s);
RigidBodySpec parse_rigid_body(const Section& s, size_t index, int dimension);
// motion: {quantity: acceleration | velocity | displacement, direction: [x, y, z],
// history: {type: constant | ramp | double_exponential | table, ...}, unit: g (a table of
// accelerations in g)}; a table file is resolved against the case file's folder.
PrescribedMotion parse_motion(const Section& s, int dimension);
// Reads static_friction, kinetic_friction, tangential_stiffness_factor from s.
FrictionSpec parse_friction(const Section& s);
// Keys parse_friction reads (for allow_only lists).
std::vector<std::string> friction_keys();

}  // namespace breccia::mps
