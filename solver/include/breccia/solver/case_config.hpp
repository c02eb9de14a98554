#pragma once
// The PD case file, parsed and validated in one place (docs/case-format.md). Everything
// here is SI; names of sets and surfaces are checked against the particle model later,
// in setup, where the model is known.
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "breccia/solver/gas_law.hpp"
#include "breccia/solver/history.hpp"
#include "breccia/solver/pd_physics.hpp"

namespace breccia::solver {

using Vec3 = std::array<double, 3>;

struct LatticeSpec {
  int dimension = 3;
  std::vector<double> box;  // x0 y0 [z0] x1 y1 [z1]
  double spacing = 0.0;
  double thickness = 1.0;
};

struct MaterialSpec {
  std::string name;
  double density = 0.0;
  double youngs_modulus = 0.0;
  double poisson_ratio = 0.25;
  double fracture_energy = 0.0;  // 0: unbreakable
  double tensile_strength = 0.0; // > 0: bilinear softening bonds with this strength (0: brittle)
  double weibull_modulus = 0.0;  // 0: no scatter
  long long weibull_seed = 1;
  // > 0: the draws are correlated in space over this length (a Gaussian random field through a
  // Gaussian copula, random_field.hpp; docs/theory.md "Weibull heterogeneity"); 0: per bond.
  double weibull_correlation_length = 0.0;
  // What the Weibull draw scales (softening materials): both G0 and the strength by the same
  // ratio to the mean (default), or only one of them.
  enum class WeibullScales { Both, FractureEnergy, TensileStrength } weibull_scales = WeibullScales::Both;
  // With `Both`, how the strength follows the bond's G0 draw w (weibull.strength_scaling,
  // docs/theory.md "Weibull heterogeneity"): w itself (default), sqrt(w) (a flaw-size
  // argument, sigma_t ~ sqrt(E G0 / a)), or not at all.
  enum class WeibullStrength { Same, Sqrt, None } weibull_strength = WeibullStrength::Same;
  // Rate-dependent strength of the softening bonds (pd_physics.hpp strength_dif); None: static.
  StrengthRateLaw strength_rate = StrengthRateLaw::None;
  // > 0: the softening bonds also crush in compression (docs/theory.md "Crushing"); 0: elastic.
  double compressive_strength = 0.0;
};

// The tensile strength of a bond of material `m` whose draw of G0 is `drawn_g0` (mean
// m.fracture_energy), as m.weibull_strength says: m.tensile_strength x (drawn_g0 / mean)^p,
// p = 1, 1/2 or 0. Set-up only (each bond's onset is stored; every backend reads it).
double weibull_bond_strength(const MaterialSpec& m, double drawn_g0);

// Explosive gas in a cavity (loads[].type: gas; gas.hpp, docs/case-format.md).
struct GasSpec {
  GasLaw law;                          // the isentrope: two-gamma (default) or JWL (gas_law.hpp)
  double jwl_explosive_density = 0.0;  // kg/m3, the unreacted explosive's (JWL's v = 1)
  bool stemming_open = false;          // mouth open: the gas vents from the start
  std::vector<std::string> vent_surfaces;  // the front reaching one of these vents the gas
  double front_speed = 0.0;            // m/s along open bonds; 0: the escape speed (gas_escape_speed)
  bool crack_entry = true;             // the gas enters cracks (false: stays in the hole)
  double density = 0.0;                // gas density in the reference cavity [kg/m3]
  double vent_area = 0.0;              // m2; 0: the mouth's area
  bool vent_crack_opening = false;     // vent_area: crack_opening, the cracks' mouths on the vent surfaces
  double ambient_pressure = 101325.0;  // Pa
  double cavity_volume = 0.0;          // m3; 0: from the surface's facets
  // The exact crack pass (openings, front, joins, vents) every this many steps; in between the
  // crack volume follows the particles' motion along the last pass's push vectors (gas.hpp).
  int crack_pass_every = 1;
  // The interval adapts: the crack volume a pass finds the drift missed, over the cavity's
  // volume, above this halves it, below a quarter of it doubles it (gas_crack_pass_interval).
  double crack_pass_tolerance = 1e-3;
  // at_once (true, the default): a step where the exact pass would change which entries are in
  // the volume is a pass (GasCrackChange). tolerance (false): no such check; the new crack a
  // pass finds counts as missed volume against crack_pass_tolerance, with the drift's error.
  bool crack_pass_new_crack_at_once = true;
};

struct LoadSpec {
  enum class Kind { Pressure, Traction, BodyForce, Gas } kind = Kind::Pressure;
  std::string surface;  // Pressure, Traction, Gas
  std::string set;      // BodyForce: empty = all
  Vec3 vector{0, 0, 0}; // Traction [Pa] or body acceleration [m/s2]
  HistorySpec history;  // Pressure: the pressure itself; Gas: the closed-cavity gauge pressure
                        // at the reference volume; others: a multiplier (default 1)
  GasSpec gas;
  // Traction: spread the surface's total force over the particles within this distance of it,
  // in proportion to their volume (a boundary layer, docs/theory.md "Loads over a boundary
  // layer"); 0: on the particles that carry the surface's facets. depth_horizon: the largest
  // horizon of those particles.
  double depth = 0.0;
  bool depth_horizon = false;
};

struct BoundarySpec {
  enum class Kind { Fixed, Velocity, Displacement } kind = Kind::Fixed;
  std::string set;
  Vec3 value{0, 0, 0};
  std::array<bool, 3> components{true, true, true};
  double ramp_time = 0.0;  // linear ramp of the velocity/displacement to its value
  // Velocity, Displacement: per component an expression in x, y, z (reference position, m)
  // and t (s), SI result, instead of `value` when not empty (checked at parse; the ramp
  // multiplies it too). Evaluated per particle once, or every step when it names t.
  std::vector<std::string> expression;
};

struct InitialSpec {
  enum class Kind { Velocity, RadialVelocity, Displacement } kind = Kind::Velocity;
  std::string set;  // empty = all particles
  Vec3 value{0, 0, 0};
  // Velocity, Displacement: per component an expression in x, y, z (reference position, m;
  // SI result), instead of `value` when not empty (checked at parse, common/expression.hpp).
  std::vector<std::string> expression;
  // Velocity, Displacement: or read from a file, one row per particle in the particle file's
  // order (HDF5 dataset N x 2|3, or CSV rows of 2|3 numbers), when `field_file` is not empty.
  std::string field_file, field_dataset;
  Vec3 center{0, 0, 0};
  double strain_rate = 0.0;  // RadialVelocity: v = rate * (x - center) (in-plane in 2D)
  bool cylindrical = false;  // RadialVelocity about the z axis through center
};

struct PrecrackSpec {
  enum class Kind { Segment, Polygon, Surface } kind = Kind::Segment;
  std::vector<Vec3> points;  // Segment: 2 points (2D); Polygon: >= 3 coplanar points (3D)
  std::string surface;       // Surface: a named facet group of the particle file
};

// A particle set defined in the case (sets:), by a region of the reference configuration or
// by set algebra over sets defined before it (in the particle file or earlier in the list).
struct RegionSetSpec {
  enum class Kind { Box, Sphere, Cylinder, HalfSpace, NearSurface, Material, Union, Intersection, Difference } kind = Kind::Box;
  std::string name;
  std::string field;               // "sets[k]", for messages
  std::vector<double> box;         // x0 y0 [z0] x1 y1 [z1]
  Vec3 center{0, 0, 0};            // sphere, cylinder
  Vec3 axis{0, 0, 1};              // cylinder
  double radius = 0.0;             // sphere, cylinder
  double length = 0.0;             // cylinder: 0 = unbounded along the axis
  Vec3 point{0, 0, 0}, normal{0, 0, 1};  // half-space: (x - point) . normal >= 0
  std::vector<std::string> operands;     // union, intersection, difference (first minus the rest)
  std::string surface;                   // near_surface: a surface of the particle file ...
  double distance = 0.0;                 //   ... and the largest distance to its facets (m)
  std::vector<std::string> materials;    // material: names of the particle file's materials
};

struct IndenterSpec {
  bool enabled = false;
  double radius = 0.0;
  Vec3 center{0, 0, 0};
  Vec3 velocity{0, 0, 0};
  double stiffness = 0.0;  // LAMMPS fix indent K [N/m^3 per unit volume]: F = -K (R - r)^2
};

struct ProbeSpec {
  std::string name;
  Vec3 position{0, 0, 0};
  std::string field = "displacement";  // displacement | velocity
};

// The largest horizon in particle spacings a case may ask for: a 3D family then holds about
// 4/3 pi 50^3 = 5e5 partners per particle, beyond any machine at a useful particle count;
// more is a unit slip ("1 km" for "1 mm"), refused at input rather than as an allocation
// failure. Convergence studies go to m of about 12.
inline constexpr double kLargestHorizonFactor = 50.0;

struct CaseConfig {
  std::string file;      // the case file path
  std::string directory; // its folder: relative paths resolve against it
  std::string name;
  // specimen
  std::string particles_path;
  std::optional<LatticeSpec> lattice;
  // model
  PdModel model = PdModel::PMB;
  std::string model_name = "pmb";
  Planar planar = Planar::None;
  Influence influence = Influence::Constant;
  double horizon_factor = 3.015;    // horizon = factor * local spacing
  std::optional<double> horizon_m;  // or one fixed horizon
  bool variable_horizon = false;    // per-particle horizon from local spacing
  bool surface_correction = false;  // energy method (Le & Bobaru 2018)
  bool fracture = true;
  // Bond-family edge: Breccia's sampled partial volumes (default), or LAMMPS PERI's linear
  // ramp over the last half spacing inside the horizon, nothing beyond it (docs/theory.md).
  PartialVolume partial_volume = PartialVolume::Sampled;
  // PMB micromodulus: discrete (scaled so that a complete family's bulk energy is the
  // classical one, the default) or continuum (the textbook value as LAMMPS PERI takes it).
  enum class PmbCalibration { Discrete, Continuum } pmb_calibration = PmbCalibration::Discrete;
  // Silling & Askari (2005) compressive enhancement: a bond breaks at s0 - alpha s_min, s_min
  // the smallest bond stretch of either end at the previous step (0: fixed s0).
  double compressive_enhancement = 0.0;
  // LAMMPS PERI's short-range repulsion between family members closer than
  // min(0.9 |xi|, 1.35 spacing) (docs/theory.md, Short-range forces).
  bool short_range_forces = false;
  // When a bond found past its critical stretch stops pushing: at once (before_force, the
  // default) or after this pass (after_force, LAMMPS PERI's order; docs/lammps-peri.md).
  bool break_after_force = false;
  // model.cuda_layout: sell: the CUDA backend's fast bond passes walk a SELL-C-sigma copy of
  // the bonds (coalesced loads; sell_layout.hpp). Default csr: one thread per CSR row.
  bool cuda_sell_layout = false;
  bool softening = false;  // some material has a tensile_strength (bilinear softening bonds)
  // The materials' strength_rate (one law per case); not None: s_onset is per-entry state.
  StrengthRateLaw strength_rate = StrengthRateLaw::None;
  // The materials' compressive_strength / tensile_strength (one ratio per case); 0: no crushing.
  double crush_ratio = 0.0;
  // Working precision of the bond loop and the state it streams (docs/theory.md, Precision).
  enum class Precision { Float64, Float32 } precision = Precision::Float64;
  std::vector<std::string> no_fail_sets;
  // Correspondence only: none | penalty (non-affine penalty, docs/theory.md), coefficient G
  std::string stabilisation = "penalty";
  double stabilisation_coefficient = 1.0;
  // model.stress_damage_limit (correspondence only; 0: off): a particle whose family has lost
  // more than this share of its own volume carries no stress (docs/theory.md, Correspondence).
  double stress_damage_limit = 0.0;
  std::vector<MaterialSpec> materials;
  std::vector<PrecrackSpec> precracks;
  std::vector<RegionSetSpec> sets;  // case-defined particle sets (evaluated first in set-up)
  std::vector<LoadSpec> loads;
  std::vector<BoundarySpec> boundaries;
  std::vector<InitialSpec> initial;
  IndenterSpec indenter;
  // time
  std::optional<double> end_time;
  std::optional<long long> steps;
  std::optional<double> dt;
  double safety = 0.8;
  bool check_stability = true;
  bool quasi_static = false;  // adaptive dynamic relaxation
  double adr_tolerance = 1e-8;
  long long adr_max_steps = 100000;
  // output
  long long output_every = 100;
  long long history_every = 10;
  long long checkpoint_every = 0;  // 0: only at the end and on Ctrl-C
  std::vector<std::string> fields{"displacement", "velocity", "damage"};
  std::vector<ProbeSpec> probes;
  bool write_results = true;
};

CaseConfig parse_case_file(const std::string& path);

}  // namespace breccia::solver
