#pragma once
// The MPS case file, validated in one place (docs/mps.md lists every key and default).
// All values SI after parsing.
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "breccia/mps/contact_spec.hpp"

namespace breccia::mps {

enum class Equation { Navier, RotationFree };
enum class Integrator { SymplecticEuler, VelocityVerlet };
// displacement: the linear Navier operators of simulation.hpp (small displacements, no
// stress state). stress: the stress-based solid of solid.hpp (stress per particle,
// co-rotated, optional von Mises plasticity, contact with a rigid floor).
enum class Formulation { Displacement, Stress };

// von Mises with linear isotropic hardening: sigma_y = yield_stress + hardening_modulus eps_p.
struct PlasticitySpec {
  double yield_stress_pa = 0.0;       // > 0
  double hardening_modulus_pa = 0.0;  // >= 0 (0: perfectly plastic)
};

// Brittle fracture with the separation tensor (fracture.hpp): a particle fails when its
// separation stress reaches tensile_strength.
struct FractureSpec {
  double tensile_strength_pa = 0.0;  // > 0
};

// Rigid floor (solid.hpp, RigidFloor): the allowed side is (x - point).normal >= 0.
struct FloorSpec {
  std::array<double, 3> point_m{0.0, 0.0, 0.0};
  std::array<double, 3> normal{0.0, 1.0, 0.0};
  double stiffness_factor = 1.0;
  FrictionSpec friction;  // none by default
  std::optional<PrescribedMotion> motion;  // ground motion (contact_spec.hpp)
};

struct LatticeSpec {
  int dimension = 2;
  std::array<double, 3> low_m{0, 0, 0}, high_m{0, 0, 0};
  double spacing_m = 0.0;
  double thickness_m = 1.0;  // 2D out-of-plane thickness
  std::array<bool, 3> periodic{false, false, false};
};

struct MaterialSpec {
  std::string name;
  double density_kg_m3 = 0.0;
  double lame_lambda_pa = 0.0;  // = C13 for isotropic media
  double shear_modulus_pa = 0.0;  // mu = C55
  std::optional<PlasticitySpec> plasticity;  // stress formulation only
  std::optional<FractureSpec> fracture;      // stress formulation only
  // Material damping (stress formulation only): damping_ratio at damping_frequency, as the
  // stiffness-proportional coefficient beta = zeta / (pi f) in s (0: none).
  double damping_ratio = 0.0, damping_frequency_hz = 0.0, viscous_time_s = 0.0;
  double p_wave_speed() const;  // sqrt((lambda + 2 mu) / rho)
  double s_wave_speed() const;  // sqrt(mu / rho)
};

// A frictional crack (2D): a straight segment; continuum bonds crossing it are removed and
// the particles facing each other across it interact through the Coulomb law (crack.hpp).
struct CrackSpec {
  std::string name;
  std::array<double, 3> start_m{}, end_m{};
  double static_friction = 0.0;   // mu_s
  double kinetic_friction = 0.0;  // mu_k <= mu_s
  double normal_stress_pa = 0.0;  // static compressive pre-stress sigma0 clamping the faces
  double stiffness_factor = 1.0;  // ks, kn = factor * modulus * face area / spacing
  std::optional<double> shear_stiffness_n_m, normal_stiffness_n_m;  // explicit overrides
  bool clapping = false;          // faces may open (normal force >= 0); default contact only
  bool restick_continuous = false;  // false: paper rule, spring reference reset at re-stick
};

struct BurstHistory {
  double amplitude_m = 0.0;  // signed: the paper's u1 = -u0 sin(2 pi t/T) has amplitude -u0
  double period_s = 0.0;
  double cycles = 0.0;
  double delay_s = 0.0;
  bool hann = false;  // Hann envelope over the burst (smooth pulse for speed tests)
};

struct BoundarySpec {
  std::string name;
  std::string face;  // left|right|bottom|top|back|front (lattice), or empty
  std::optional<std::array<double, 6>> box_m;  // x0 y0 z0 x1 y1 z1
  std::string set;   // particle set of particles.h5
  std::array<bool, 3> components{false, false, false};
  std::optional<BurstHistory> burst;  // none: held at zero displacement
};

struct InitialGaussian {
  std::array<double, 3> center_m{}, amplitude_m{};
  double width_m = 0.0;  // u = A exp(-|r - c|^2 / width^2)
};

struct ProbeSpec {
  std::string name;
  std::array<double, 3> position_m{};
  std::string field;  // displacement_x ... velocity_z
};

struct CaseSpec {
  std::string file;
  // specimen
  std::optional<LatticeSpec> lattice;
  std::string particle_file;
  std::optional<BodiesSpec> bodies;  // several bodies (stress formulation)
  // model
  double re_over_spacing = 2.1;
  Equation equation = Equation::Navier;
  Integrator integrator = Integrator::SymplecticEuler;
  Formulation formulation = Formulation::Displacement;
  // stress formulation (docs/mps.md, "Stress-based solid")
  double hourglass = 0.1;          // hourglass stiffness / shear modulus
  bool repulsive_pressure = false; // pressure_force: repulsive (Inagaki) | conservative
  bool updated_lagrangian = false; // lagrangian: updated (stencils rebuilt on the current configuration) | total
  // elastic_law: neo_hookean (default where it applies: no plasticity, total-Lagrangian
  // stencils) | rate (Hooke increments on the rotated stress; what plasticity and updated
  // stencils use)
  bool rate_elastic_law = false;
  double stencil_update_strain = 0.1;  // rebuild when some |H| (since the last rebuild) exceeds this
  double damping_per_s = 0.0;      // mass-proportional damping (quasi-static runs)
  std::optional<double> damping_until_s;  // damping only while t < this (a settling phase)
  std::array<double, 3> gravity_m_s2{0.0, 0.0, 0.0};
  std::optional<FloorSpec> floor;
  std::optional<ParticleContactSpec> particle_contact;  // contact.particles (implied by >= 2 bodies)
  std::vector<RigidBodySpec> rigid_bodies;             // contact.rigid_bodies (2D)
  MaterialSpec material;
  std::vector<CrackSpec> cracks;
  std::vector<BoundarySpec> boundary;
  std::optional<InitialGaussian> initial;
  std::array<double, 3> initial_velocity_m_s{0.0, 0.0, 0.0};  // uniform, every particle
  // time
  double end_time_s = 0.0;
  std::optional<double> dt_s;
  double safety = 0.5;  // dt = safety * spacing / c_L (default 0.5; 0.3 for the stress formulation)
  // output
  long long snapshot_every = 0;  // 0: first and last state only
  long long history_every = 1;
  bool energy = false;
  bool progress = true;
  std::vector<ProbeSpec> probes;
};

// Parse and validate; throws breccia::InputError naming the file and field.
CaseSpec load_case(const std::string& case_file);
CaseSpec parse_case_text(const std::string& yaml_text, const std::string& name = "<text>");

}  // namespace breccia::mps
