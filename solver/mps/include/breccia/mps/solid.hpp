#pragma once
// Stress-based MPS solid ([Inagaki 2009] thesis, docs/references.md): total Lagrangian
// bonds, a stress state per particle updated incrementally (Hooke, co-rotated with the
// Hughes-Winget/Jaumann rotation, optional von Mises plasticity with linear hardening),
// internal force as the MPS divergence of the stress, symplectic Euler. 2D plane strain
// or 3D. The kernels are in solid_kernels.hpp; this class owns the data and the loops.
//
// step() reads like the algorithm:
//   1. H_i = grad u at the particle (corrected MPS gradient)
//   2. stress update: rotate, Hooke increment, radial return
//   3. force = MPS divergence of stress (+ hourglass control, external and contact forces)
//   4. v += dt a, u += dt v (symplectic Euler), prescribed displacements
#include <array>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "breccia/mps/fracture.hpp"
#include "breccia/mps/contact.hpp"
#include "breccia/mps/neighbours.hpp"
#include "breccia/mps/particles.hpp"
#include "breccia/mps/solid_kernels.hpp"

namespace breccia::mps {

enum class PressureForce { Conservative, Repulsive };

struct SolidOptions {
  int dimension = 2;
  double spacing_m = 0.0;
  double thickness_m = 1.0;        // 2D out-of-plane thickness (volumes already include it)
  double re_over_spacing = 2.1;
  double hourglass = 0.1;          // alpha: hourglass stiffness relative to the shear modulus
  double damping_per_s = 0.0;      // mass-proportional damping a -= damping v (quasi-static runs)
  double damping_until_s = std::numeric_limits<double>::infinity();  // damping while t < this
  PressureForce pressure = PressureForce::Conservative;
  double safety = 0.3;             // dt = safety * spacing / c_L
  // Split step() into substeps where bonds are squeezed (Solid::update_substeps). false: the
  // fixed step of the reference spacing throughout (for comparisons: it inverts the 16-across
  // Taylor bar at safety 0.3).
  bool substeps = true;
  std::optional<double> dt_s;      // used as given when set
  std::array<double, 3> gravity_m_s2{0.0, 0.0, 0.0};
  // Body of each particle (empty: one body). No bond joins two bodies; they interact
  // through contact only (contact.hpp).
  std::vector<int> body_id;
  // Updated Lagrangian stencils: when some particle's gradient relative to its stencil's
  // reference, |H| (Frobenius), exceeds stencil_update_strain, every stencil (neighbours,
  // bond vectors, weights, moment matrices, volumes) is rebuilt on the current
  // configuration. Stress and plastic strain live on the particles and are carried; the
  // hourglass residual restarts from zero (its energy is counted as dissipated).
  // false: total Lagrangian (the reference stencils are kept for the whole run).
  bool updated_lagrangian = false;
  double stencil_update_strain = 0.1;
};

// A rigid half-space {x : (x - point) . normal >= 0} is the allowed side.
// A particle that penetrates by depth g feels the penalty force k g normal, with
// k = stiffness_factor * (lambda + 2 mu) * A / spacing (A: particle face area), i.e. the
// floor is as stiff as one layer of the material times the factor. The force is
// conservative (energy 1/2 k g^2), so a frictionless bounce conserves energy up to the
// time-integration error. With friction, Coulomb's law through a tangential spring
// k_t = tangential_stiffness_factor * mu * A / spacing (contact_kernels.hpp).
struct RigidFloor {
  std::array<double, 3> point_m{0.0, 0.0, 0.0};
  std::array<double, 3> normal{0.0, 1.0, 0.0};
  double stiffness_factor = 1.0;
  double static_friction = 0.0, kinetic_friction = 0.0;
  double tangential_stiffness_factor = 1.0;
  std::optional<PrescribedMotion> motion;  // ground motion
};

// Where Solid::step's substeps run instead of the OpenMP loops: a device with its own copy of
// the state (the CUDA launcher, breccia/mps/cuda_solid.hpp). It runs the phases of
// solid_phases.hpp in Solid's order; Solid keeps the clock, the substep count, the error
// checks and the cutting of bonds by fracture, and its host arrays become a cache, refreshed
// by download() only when read.
// Supported: total Lagrangian stencils, plasticity, both pressure forms, rigid planes with
// or without friction, frictionless contact between particles (either normal), prescribed
// sets, constant external forces, gravity, damping, pre-cut bonds and fracture; the rest is
// refused before a device is built (solid_device_refusal, solid_case.hpp).
struct SolidHostState {  // what download() refreshes (sized by the caller)
  std::array<std::vector<double>, 3>* u = nullptr;
  std::array<std::vector<double>, 3>* v = nullptr;
  std::vector<Mat3>* gradient = nullptr;
  std::vector<Mat3>* f_inverse = nullptr;
  std::vector<SymTensor>* stress = nullptr;
  std::vector<double>* eq_plastic_strain = nullptr;
  std::vector<double>* stress_work_j = nullptr;
  std::vector<ForceMatrices>* matrices = nullptr;
};

// What fracture changed on the host for the particles it names (upload_cut): their bond
// weights (their CSR rows; a cut bond's two ends are both named) and stencil state.
struct SolidCutState {
  const BondList* bonds = nullptr;
  const std::vector<Mat3>* moment_inverse = nullptr;
  const std::vector<char>* full_stencil = nullptr;
  const std::vector<Mat3>* gradient = nullptr;
  const std::vector<Mat3>* f_inverse = nullptr;
  const std::vector<SymTensor>* stress = nullptr;
  const std::vector<ForceMatrices>* matrices = nullptr;
};

class SolidStepDevice {
public:
  virtual ~SolidStepDevice() = default;
  // One substep in two halves, so that fracture can cut bonds between them as on the CPU:
  // phase 1 (gradient, stress, force matrices), then phases 2-4, symplectic Euler over dt and
  // the prescribed values at time_after_s. Queued: return before the device has finished.
  virtual void stress_phase() = 0;
  virtual void motion_phase(double dt, double time_after_s) = 0;
  // Particles found inverted (det F <= 0) by the stress phases since the last call; waits.
  virtual long long inverted_particles() = 0;
  // Which particles the last stress phase found inverted (1 each, sized N), for fracture's
  // debris rule (FractureModel::absorb_inversion).
  virtual void inverted_flags(std::vector<char>& flags) = 0;
  // Fracture: the separation stress of every particle from the last stress phase
  // (FractureModel::evaluate's arithmetic); returns the largest finite value (0 if none).
  virtual double largest_separation_pa() = 0;
  // After Solid has cut bonds on the host: copy the cut state of `particles` to the device.
  virtual void upload_cut(const SolidCutState& host, const std::vector<long long>& particles) = 0;
  // min over intact bonds of squeezed_bond_length (Solid::update_substeps), capped at spacing.
  virtual double shortest_squeezed_bond_m(double window_s) = 0;
  // Bonds below kMinNeighbourDistanceRatio by the clumping measure (stability_checks.hpp).
  virtual long long clumped_bonds() = 0;
  // Rigid planes with friction: the energy in the particles' tangential springs now, and the
  // energy dissipated by slip since the device was built plus what the solid had dissipated
  // before (Contact::friction_dissipation_j; summed per particle, so it differs from the
  // CPU's running sum at rounding level).
  virtual void friction_totals(double* spring_energy_j, double* dissipated_j) = 0;
  // Particle pairs in contact at the last substep (Contact::contact_pairs).
  virtual long long contact_pairs() = 0;
  // u and v only (kinematics), or every field of SolidHostState.
  virtual void download(const SolidHostState& host, bool kinematics_only) = 0;
  virtual std::string description() const = 0;  // backend and device, for logs and summary.json
};

class Solid {
public:
  // position_m: 3N reference positions; volume_m3: N (2D: area x thickness).
  Solid(std::vector<double> position_m, std::vector<double> volume_m3, double density_kg_m3, const SolidLaw& law,
        const SolidOptions& options);

  void add_prescribed(PrescribedSet set);
  void set_floor(const RigidFloor& floor);
  // Contact between unbonded particles and with rigid polygons (contact.hpp); stiffnesses in
  // N/m, e.g. factor * face_stiffness_n_m().
  // On a device, with its totals (friction, pairs in contact: sync_contact).
  Contact& contact() {
    sync_contact();
    return contact_;
  }
  const Contact& contact() const {
    sync_contact();
    return contact_;
  }
  // Penalty stiffness of one particle layer: (lambda + 2 mu) A / spacing, and its shear
  // counterpart mu A / spacing (A: particle face area, spacing x thickness in 2D).
  double face_stiffness_n_m() const;
  double shear_face_stiffness_n_m() const;
  // A particle's face area: spacing x thickness in 2D, spacing^2 in 3D.
  double face_area_m2() const;
  // Brittle fracture with the separation tensor (fracture.hpp); nullptr when not enabled.
  void set_fracture(const FractureLaw& law);
  // On a device the separation values are brought up to date here when read (sync_fracture).
  const FractureModel* fracture() const {
    sync_fracture();
    return fracture_ ? &*fracture_ : nullptr;
  }
  // Pre-cut: gives every intact bond (i, j) with cut(i, j) weight 0, as fracture does (no
  // stress or hourglass force, out of the gradient, stencils refreshed; the pair becomes a
  // contact candidate). Returns the number of bonds cut, each pair once (solid_cut.cpp).
  long long cut_bonds(const std::function<bool(long long i, long long j)>& cut);
  // Constant external force per particle (N), e.g. a pressure load; may be changed between steps.
  std::vector<double>& external_force(int axis) { return external_force_n_[axis]; }

  void step();
  // Hand the substeps to a device built from this solid's current state; from then on the
  // host arrays are refreshed from the device when read. Set initial values, external forces
  // and prescribed sets first: writes through the non-const accessors after attaching do not
  // reach the device.
  void attach_device(std::unique_ptr<SolidStepDevice> device);
  bool on_device() const { return device_ != nullptr; }
  std::string backend_description() const;  // "cpu (OpenMP, N threads)" or the device's

  // Internal force (N, 3N array) that a uniform stress state would produce in the reference
  // configuration. It vanishes on particles whose stencil is full and equals the discrete
  // surface traction of that stress elsewhere, so minus it, restricted to the particles
  // near one surface, is the load consistent with the operators for a uniform pressure or
  // traction on that surface (a plain point force on the outer particle layer is not: the
  // second layer's stencil is truncated too and would be left unbalanced).
  std::vector<double> internal_force_of_uniform_stress(const SymTensor& stress) const;

  double time_s() const { return time_s_; }
  long long steps() const { return steps_; }
  double dt_s() const { return dt_s_; }
  double cfl_dt_s() const { return cfl_dt_s_; }
  double spacing_m() const { return options_.spacing_m; }
  double thickness_m() const { return options_.thickness_m; }
  int dimension() const { return options_.dimension; }
  size_t size() const { return volume_m3_.size(); }
  const BondList& bonds() const { return bonds_; }
  const Normalisation& normalisation() const { return norm_; }
  const SolidOptions& options() const { return options_; }
  const SolidLaw& law() const { return law_; }
  double density_kg_m3() const { return density_kg_m3_; }
  double p_wave_speed() const;

  const std::vector<double>& position_m() const { return position_m_; }
  const std::vector<double>& volume_m3() const { return volume_m3_; }
  const std::vector<double>& displacement(int axis) const {
    sync_host(true);
    return u_[axis];
  }
  const std::vector<double>& velocity(int axis) const {
    sync_host(true);
    return v_[axis];
  }
  std::vector<double>& displacement(int axis) {
    sync_host(true);
    return u_[axis];
  }
  std::vector<double>& velocity(int axis) {
    sync_host(true);
    return v_[axis];
  }
  const std::vector<SymTensor>& stress_pa() const {
    sync_host(false);
    return stress_;
  }
  const std::vector<double>& eq_plastic_strain() const {
    sync_host(false);
    return eq_plastic_strain_;
  }
  // Current displacement gradient H = F - I per particle (up to date after a step), relative
  // to the stencil's reference configuration (the initial one unless updated Lagrangian).
  const std::vector<Mat3>& displacement_gradient() const {
    sync_host(false);
    return gradient_;
  }
  // Displacement since the stencils' reference configuration (= displacement() in total
  // Lagrangian form); with bonds().rx etc. it gives the current bond vectors.
  const std::vector<double>& stencil_displacement(int axis) const {
    sync_host(true);
    return options_.updated_lagrangian ? u_stencil_[axis] : u_[axis];
  }
  // Volume ratio J = det F of each particle relative to the initial configuration.
  std::vector<double> volume_ratio() const;
  long long stencil_rebuilds() const { return stencil_rebuilds_; }
  int substeps() const { return substeps_; }  // substeps per step() (squeezed bonds; update_substeps())
  long long substep_hold_steps() const { return substep_hold_steps_; }  // update_substeps()

  double kinetic_energy_j() const;  // particles and free rigid bodies
  // Stress work accumulated since the start (elastic energy + plastic dissipation).
  double stress_work_j() const;
  double hourglass_energy_j() const;
  // Penalty energy of all contacts (floor, polygons, particle pairs) + friction springs.
  double contact_energy_j() const;
  double floor_energy_j() const { return contact_energy_j(); }  // the floor was the only contact once
  double friction_dissipation_j() const {
    sync_contact();
    return contact_.friction_dissipation_j();
  }
  // Energy dissipated by material damping (SolidLaw::viscous_time_s) since the start.
  double material_damping_j() const;
  double gravity_energy_j() const;  // - m g . u (particles and free rigid bodies), zero at the start
  double plastic_fraction() const;  // share of particles with eq. plastic strain > 0

  // What a device launcher needs beyond the public state.
  const std::vector<double>& stencil_volume_m3() const { return stencil_volume_m3_; }
  const std::vector<Mat3>& moment_inverse() const { return moment_inverse_; }
  const std::vector<char>& full_stencil() const { return full_stencil_; }
  const std::vector<double>& external_force_n(int axis) const { return external_force_n_[axis]; }
  const std::vector<PrescribedSet>& prescribed() const { return prescribed_; }
  double hourglass_stiffness() const;  // K_hg of an elastic particle (Pa/m^3)
  // State that the host arrays above do not show (sync_host(false) included).
  const std::vector<Mat3>& f_inverse() const {
    sync_host(false);
    return f_inverse_;
  }
  const std::vector<ForceMatrices>& force_matrices_of_particles() const {
    sync_host(false);
    return matrices_;
  }
  const std::vector<double>& stress_work_of_particles_j() const {
    sync_host(false);
    return stress_work_j_;
  }

  int nearest_particle(const std::array<double, 3>& p) const;
  double sample(int particle, const std::string& field) const;

private:
  void compute_acceleration(double dt);
  void apply_prescribed(double t);
  ParticleStateView state_view() const;
  // Refresh the host arrays from the device after it has stepped (no-op without one): u and v
  // only, or everything.
  void sync_host(bool kinematics_only) const;
  double shortest_squeezed_bond_m() const;  // update_substeps' measure on the host arrays
  [[noreturn]] void throw_inverted(long long inverted, double time_s) const;
  // solid_fracture.cpp: fail, cut bonds, refresh the cut stencils; returns the particles
  // whose stencil changed (sorted).
  std::vector<long long> apply_fracture();
  void refresh_cut_stencils(const std::vector<long long>& changed);
  FractureModel::State fracture_state() const;
  // Device path: debris rule for the inverted particles, then the host's cutting on the
  // substeps where the device finds a particle at the strength.
  void absorb_inverted_on_device(long long inverted);
  void fracture_on_device();
  void sync_fracture() const;  // separation values of the device's last stress phase
  void sync_contact() const;  // the device's contact totals (friction, pairs) into contact_
  void build_stencils(const std::vector<double>& position_m);  // bonds, L^-1, surface flags
  // bond_coefficient_ of particle i's bonds (build_stencils; fracture's cuts name both ends).
  void refresh_bond_coefficients(long long i);
  void rebuild_stencils_on_current_configuration();            // updated Lagrangian
  void update_substeps();  // substeps per step() from the shortest current bond
  // The stress particle i's force matrices carry: elastic + viscous (material damping).
  SymTensor stress_in_force(size_t i) const {
    return viscous_stress_.empty() ? stress_[i] : add_stresses(stress_[i], viscous_stress_[i]);
  }

  std::vector<double> position_m_, volume_m3_;
  double density_kg_m3_ = 0.0;
  SolidLaw law_;
  SolidOptions options_;
  // mutable: with a device, its totals (friction, pairs in contact) are a cache of the
  // device's (sync_contact).
  mutable Contact contact_;
  mutable bool contact_current_ = true;
  // mutable: with a device, its separation values are a cache too (sync_fracture).
  mutable std::optional<FractureModel> fracture_;
  mutable bool separation_current_ = true;
  BondList bonds_;
  Normalisation norm_;
  // c_k = V_j w_k / |r_k|^2 per bond on the stencil volumes (bond_coefficient, solid_kernels.hpp):
  // the gradient, force and hourglass loops read it instead of dividing per bond per step.
  std::vector<double> bond_coefficient_;
  // mutable: with a device attached, the state below is a cache of its state (sync_host).
  std::vector<Mat3> moment_inverse_;                   // L^-1
  mutable std::vector<Mat3> gradient_, f_inverse_;     // H = F - I, F^-1
  mutable std::vector<ForceMatrices> matrices_;
  mutable std::vector<SymTensor> stress_;
  std::vector<char> full_stencil_;  // number density >= 0.97 n0 (not a surface particle)
  mutable std::vector<double> eq_plastic_strain_, stress_work_j_;
  // Material damping (law_.viscous_time_s > 0, else empty): solid_phases.hpp, stress_phase_at.
  std::vector<SymTensor> viscous_stress_;
  std::vector<double> viscous_work_j_;
  std::vector<double> pressure_pa_, pressure_floor_pa_;
  mutable std::array<std::vector<double>, 3> u_, v_;
  std::array<std::vector<double>, 3> a_, external_force_n_;
  std::unique_ptr<SolidStepDevice> device_;
  mutable bool kinematics_current_ = true;  // host u, v hold the device's latest state
  mutable bool state_current_ = true;       // the other cached arrays do
  // Updated Lagrangian: stencil volumes V0 J (mass stays density x volume_m3_), the
  // displacement at the last rebuild, the displacement since then, and J at the last rebuild.
  std::vector<double> stencil_volume_m3_, stencil_volume_ratio_;
  std::array<std::vector<double>, 3> u_at_rebuild_, u_stencil_;
  long long stencil_rebuilds_ = 0;
  int substeps_ = 1;  // per step(): keeps the step stable where bonds are squeezed
  // The count is lowered only after substep_hold_steps_ steps in which no check needed it
  // (update_substeps): last_needed_step_ is the last check that did.
  long long substep_hold_steps_ = 0, last_needed_step_ = 0;
  double hourglass_released_j_ = 0.0;  // hourglass energy at rebuilds (dissipated)
  std::vector<PrescribedSet> prescribed_;
  double mean_volume_m3_ = 0.0;
  double dt_s_ = 0.0, cfl_dt_s_ = 0.0, time_s_ = 0.0;
  long long steps_ = 0;
};

}  // namespace breccia::mps
