#pragma once
// breccia-plan: before any run, what a PD case will cost (particles, bonds, steps, memory,
// seconds), what error the atlas of measured convergence sweeps expects of it, and the
// cheapest setup that meets a tolerance. Every number comes from the solver's own code
// (case loader, lattice, families, stable step) or from a measurement with its source;
// docs/plan.md says what is estimated how, and where the estimates stop being good.
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "breccia/solver/case_config.hpp"

namespace breccia::plan {

// ---- measured throughputs (throughputs.yaml, or --calibrate) ----------------------------

struct LoopRate {
  std::string model;  // pmb | lps | correspondence
  int threads = 1;
  double bond_updates_per_core_s = 0.0;  // bond entries x steps / (time loop seconds x threads)
  std::string source;
  std::string precision = "float64";     // model.precision the rate was measured with
};

struct Throughputs {
  std::vector<LoopRate> loop;
  // Set-up work other than the stable-step estimate (families, partial volumes, calibration),
  // in bond entries per core-second.
  double setup_bonds_per_core_s = 0.0;
  std::string setup_source;
  // Force passes of the set-up's stable-step estimate (Lanczos, estimate_max_frequency_lanczos:
  // it stops when converged) where the plan cannot set the case up itself.
  int stable_step_passes = 25;
  // ADR iterations ~ adr_iterations_per_cell x (cells along the longest side) x log10(1/tol).
  double adr_iterations_per_cell_decade = 0.0;
  std::string adr_source;
  // Time per bond entry of softening bonds (materials[].tensile_strength) over the
  // critical-stretch law's, per model key (pmb | lps), float64; a model without one is costed
  // at the critical-stretch rate.
  struct SofteningCost {
    std::string model;
    double time_factor = 1.0;
    std::string source;
  };
  std::vector<SofteningCost> softening;
  std::optional<double> gpu_bond_updates_per_s;  // none measured yet
  std::string gpu_source;
  std::string file;

  // Per-core float64 rate for this model at this thread count: the entry measured at that
  // count, else the one at the nearest measured count (per-core rates fall with more threads).
  const LoopRate& rate(solver::PdModel model, int threads) const;
  // The entry of this model and precision nearest in thread count; nullptr if none.
  const LoopRate* find(solver::PdModel model, int threads, const std::string& precision) const;
  // float32 rate / float64 rate for this model at the nearest measured thread count, when
  // both were measured (loop entries with precision: float32); empty otherwise.
  std::optional<double> float32_speedup(solver::PdModel model, int threads) const;
  // Time per bond entry of `model` over that of `reference` (float64, nearest thread count):
  // e.g. correspondence against LPS. Empty when either is not measured.
  std::optional<double> relative_cost(solver::PdModel model, solver::PdModel reference, int threads) const;
};

// The model's name in throughputs.yaml and the atlas: pmb | lps | correspondence.
std::string model_key(solver::PdModel model);

Throughputs load_throughputs(const std::string& path);
std::string default_throughputs_path();

// Measure this machine: a lattice block shaped like the case (dimension, model, horizon
// factor, influence) of about `target_bonds` bond entries, set up and stepped for at least
// `min_loop_s` of CPU time. Rates are per CPU-second (process CPU time / threads), which
// stays meaningful on a shared machine.
Throughputs calibrate(const solver::CaseConfig& like, int threads, const Throughputs& base,
                      double target_bonds = 2.0e6, double min_loop_s = 0.5);

// ---- cost estimate --------------------------------------------------------------------

struct CostOptions {
  int threads = 1;
  // Particle files above this many particles: bonds from the bulk family size at m (an
  // upper bound: surface particles have fewer) instead of building the families. Lattices
  // are always counted exactly (family offsets over the box).
  long long exact_bond_limit = 2'000'000;
  // Up to this many particles the stable step comes from the solver's set-up of the whole
  // case; above, from a lattice block of the case's smallest spacing (see docs/plan.md).
  long long exact_step_limit = 150'000;
};

struct CostEstimate {
  int dimension = 3;
  std::string model;
  std::string particles_kind;  // lattice | tet (particles.h5 from a mesh) | file
  long long particles = 0;
  long long bonds = 0;  // bond entries (each bond once from each end), as breccia-solve counts
  bool bonds_exact = true;
  std::string bonds_method;
  double spacing_m = 0.0;      // median particle spacing
  double min_spacing_m = 0.0;
  double max_spacing_m = 0.0;
  double horizon_m = 0.0;      // at the median spacing
  double horizon_factor = 0.0; // m = horizon / spacing
  double stable_dt_s = 0.0;
  double dt_s = 0.0;
  std::string dt_method;
  long long steps = 0;
  bool quasi_static = false;
  std::string steps_method;
  double run_bytes = 0.0;    // resident during the time loop (PdSystem arrays)
  double bond_entry_bytes = 0.0;  // of which per bond entry (bytes_per_bond)
  double setup_bytes = 0.0;  // peak during set-up (families under construction as well)
  int threads = 1;
  double loop_s = 0.0;   // time loop, CPU, wall-clock on a quiet machine
  double setup_s = 0.0;  // set-up
  std::string rate_source;
  std::string setup_source;
  std::optional<double> gpu_loop_s;
  std::string gpu_note;
  double total_s() const { return loop_s + setup_s; }
};

CostEstimate estimate_cost(const solver::CaseConfig& config, const Throughputs& rates, const CostOptions& options = {});

// Bond entries per particle of a particle deep inside a square/cubic lattice at horizon
// factor m (the same partial-volume rule as set-up): the bulk family size.
double bulk_family_size(int dimension, double horizon_factor);
// Bond entries of a whole lattice box with one horizon (exact, without building it).
long long lattice_bond_count(const std::array<long long, 3>& particles_per_axis, int dimension, double horizon_factor);

// Bytes the PdSystem holds per particle and per bond entry (pd_system.hpp, as allocated).
double bytes_per_particle(int dimension, solver::PdModel model);
// softening: + s_onset, bond_damage; shared_dual_halves: without k_dual, s0_dual (set-up shares
// them with the own halves where they are equal: PdSystem::dual_halves_shared);
// own_volumes_counted: the own halves' volumes as a sample count (a byte) instead of a double
// (model.partial_volume: sampled, the default; PdSystem::own_count).
double bytes_per_bond(bool softening = false, bool shared_dual_halves = false, bool own_volumes_counted = true);

// ---- atlas ------------------------------------------------------------------------------

struct AtlasRow {
  std::string problem, model, particles_kind, precision, backend, error_measure;
  int dimension = 3, threads = 1;
  double m = 0, spacing_m = 0, wall_s = 0, error = 0;
  long long particles = 0, bonds = 0, steps = 0;
  // Particles along a geometric-mean side: particles^(1/dimension). The CSV has no
  // geometry, so this is how a row and a case are put on one resolution axis.
  double resolution() const;
};

// Reads the fixed CSV contract (docs/plan.md); throws InputError on a wrong header or row.
std::vector<AtlasRow> read_atlas(const std::string& path);
std::string default_atlas_path();

struct ProblemClass {
  std::string problem;  // an atlas problem name
  std::string why;
};
ProblemClass classify_problem(const solver::CaseConfig& config);

struct ErrorEstimate {
  bool known = false;
  double error = 0.0;
  std::string how;  // which rows, interpolated or nearest
};
// Rows of the case's dimension; failing that, the other dimension's (said so in `how`).
ErrorEstimate expected_error(const std::vector<AtlasRow>& atlas, const std::string& problem, const std::string& model,
                             int dimension, const std::string& kind, double m, double resolution);

// The atlas records a nominal m (2, 3, 4, 5) and runs the solver at m + 0.015 so a lattice
// point at exactly m spacings is inside (tools/atlas, horizon_factor). A row's m that is a
// multiple of 0.5 is read as nominal; any other value is the horizon factor itself.
double horizon_factor_of_row_m(double m);

// The coarsest resolution at which the measured error of one (problem, model, dimension,
// kind, m, float64) group meets the tolerance, interpolated log-log between the last
// measured setting that fails and the first that passes (and every finer one passes).
struct ResolutionNeed {
  bool met = false;
  double resolution = 0.0;
  double error_at_need = 0.0;
  std::string how;
};
ResolutionNeed resolution_for(const std::vector<AtlasRow>& atlas, const std::string& problem, const std::string& model,
                              int dimension, const std::string& kind, double m, double tolerance);

// ---- proposal ---------------------------------------------------------------------------

struct PlaneCheck {
  bool plane = false;
  solver::Planar planar = solver::Planar::None;
  std::string why;
};
// Can this 3D lattice case be modelled in 2D? Conservative: see docs/plan.md.
PlaneCheck plane_check(const solver::CaseConfig& config);

struct Proposal {
  bool tolerance_met = false;
  bool from_atlas = false;
  int dimension = 3;
  solver::Planar planar = solver::Planar::None;
  std::string model;
  double horizon_factor = 3.015;
  double spacing_m = 0.0;  // lattice spacing (or the mesh size to ask the mesher for)
  double expected_error = 0.0;
  std::string precision = "float64";  // float32 only where the atlas and the throughputs show it pays
  CostEstimate cost;
  std::vector<std::string> reasoning;  // plain sentences, in order
};

Proposal propose(const solver::CaseConfig& config, const std::vector<AtlasRow>& atlas, double tolerance,
                 const Throughputs& rates, const CostOptions& options);

// Write the proposal as a case file breccia-solve accepts (parsed back to check).
void write_proposed_case(const solver::CaseConfig& config, const Proposal& proposal, const std::string& path);

// The case as the proposal would have it (no file written): used by write_proposed_case
// and by cost estimates of candidates.
solver::CaseConfig proposed_config(const solver::CaseConfig& config, const Proposal& proposal);

// The largest spacing at which a lattice box (d = 2: [x0, y0, x1, y1]; 3: [x0, y0, z0, x1, y1,
// z1]) has at least resolution^d particles, rounded down so the longest side holds a whole
// number of cells (a measured row's resolution gives its own lattice back).
double spacing_for_resolution(const std::vector<double>& box, int d, double resolution);

}  // namespace breccia::plan
