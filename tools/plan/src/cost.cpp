// The cost of a case before it runs: particles (lattice spec or particles.h5), bonds (the
// solver's families with set-up's partial-volume rule), steps (the solver's stable step),
// memory (the PdSystem arrays as allocated) and seconds (measured throughputs).
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <numeric>

#include "breccia/common/error.hpp"
#include "breccia/common/particle_file.hpp"
#include "breccia/plan/plan.hpp"
#include "breccia/solver/family.hpp"
#include "breccia/solver/pd_physics.hpp"
#include "breccia/solver/pd_system.hpp"

namespace breccia::plan {

using solver::CaseConfig;
using solver::PdModel;
using solver::bond_entry_bytes;
using solver::model_separates_dual_halves;

namespace {

std::string fmt_rate(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3g", v);
  return b;
}

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// Particle counts per axis of a lattice spec, exactly as set-up's lattice_model makes them.
std::array<long long, 3> lattice_counts(const solver::LatticeSpec& l) {
  std::array<long long, 3> count{1, 1, 1};
  for (int k = 0; k < l.dimension; ++k)
    count[k] = std::max(1LL, std::llround((l.box[k + l.dimension] - l.box[k]) / l.spacing));
  return count;
}

struct Geometry {
  int dimension = 3;
  std::vector<double> position;  // 3N (files only)
  std::vector<double> spacing;   // N (one entry for a lattice)
  std::string kind;
  double longest_side_m = 0.0;
  long long count = 0;  // particles
};

// A lattice is counted, never built: its bonds come from lattice_bond_count.
Geometry lattice_geometry(const solver::LatticeSpec& l) {
  Geometry g;
  g.dimension = l.dimension;
  g.kind = "lattice";
  const auto count = lattice_counts(l);
  g.count = count[0] * count[1] * count[2];
  g.spacing.assign(1, l.spacing);
  for (int k = 0; k < l.dimension; ++k) g.longest_side_m = std::max(g.longest_side_m, count[k] * l.spacing);
  return g;
}

Geometry file_geometry(const std::string& path) {
  ParticleModel pm = read_particle_file(path);
  Geometry g;
  g.dimension = pm.dimension;
  g.kind = pm.nodes_per_cell > 0 ? "tet" : (pm.source.rfind("lattice", 0) == 0 ? "lattice" : "file");
  g.position = std::move(pm.position_m);
  g.spacing = std::move(pm.spacing_m);
  g.count = static_cast<long long>(g.spacing.size());
  double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
  for (size_t i = 0; i < g.spacing.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], g.position[3 * i + k]);
      hi[k] = std::max(hi[k], g.position[3 * i + k]);
    }
  for (int k = 0; k < g.dimension; ++k) g.longest_side_m = std::max(g.longest_side_m, hi[k] - lo[k]);
  return g;
}

// Per-particle horizon, as set-up chooses it (fixed, per-particle, or factor x median).
std::vector<double> horizons(const CaseConfig& c, const std::vector<double>& spacing) {
  std::vector<double> h(spacing.size());
  if (c.horizon_m) {
    std::fill(h.begin(), h.end(), *c.horizon_m);
  } else if (c.variable_horizon) {
    for (size_t i = 0; i < h.size(); ++i) h[i] = c.horizon_factor * spacing[i];
  } else {
    std::fill(h.begin(), h.end(), c.horizon_factor * median(spacing));
  }
  return h;
}

// Bond entries set-up keeps: family members (with the cell-corner pad) whose cell reaches
// into either end's horizon (setup.cpp, "Families and per-bond coefficients").
struct BondCount {
  long long kept = 0, padded = 0;
};
BondCount count_bonds(const Geometry& g, const std::vector<double>& horizon) {
  const size_t n = g.spacing.size();
  std::vector<double> pad(n), half_cell(n);
  for (size_t i = 0; i < n; ++i) {
    half_cell[i] = 0.5 * g.spacing[i];
    pad[i] = half_cell[i] * std::sqrt(static_cast<double>(g.dimension));
  }
  const solver::Families fam = solver::build_families(g.position, horizon, pad);
  long long kept = 0;
  const double* x = g.position.data();
#pragma omp parallel for schedule(dynamic, 256) reduction(+ : kept)
  for (size_t i = 0; i < n; ++i)
    for (int64_t k = fam.offsets[i]; k < fam.offsets[i + 1]; ++k) {
      const int32_t j = fam.neighbors[k];
      const double xv[3] = {x[3 * j] - x[3 * i], x[3 * j + 1] - x[3 * i + 1], x[3 * j + 2] - x[3 * i + 2]};
      const double xm[3] = {-xv[0], -xv[1], -xv[2]};
      if (solver::partial_volume_sampled(xv, horizon[i], half_cell[j], g.dimension) > 0 ||
          solver::partial_volume_sampled(xm, horizon[j], half_cell[i], g.dimension) > 0)
        ++kept;
    }
  return {kept, static_cast<long long>(fam.bond_count())};
}

// A block of the case's stiffest material at spacing h: what the stable step sees when the
// whole case is too big to set up here. Same model, influence, horizon rule and calibration
// (surface correction included); no loads, constraints or cracks (they do not change the
// highest frequency of a free block).
double sample_stable_dt(const CaseConfig& c, int dimension, double h, double horizon_m) {
  CaseConfig s = c;
  s.file = c.file + " (stable-step sample)";
  s.particles_path.clear();
  s.loads.clear();
  s.boundaries.clear();
  s.initial.clear();
  s.precracks.clear();
  s.no_fail_sets.clear();
  s.probes.clear();
  s.indenter = {};
  s.variable_horizon = false;
  s.horizon_m = horizon_m;
  s.quasi_static = false;
  s.dt.reset();
  s.steps = 1;
  const auto stiffest = std::max_element(c.materials.begin(), c.materials.end(), [](const auto& a, const auto& b) {
    return a.youngs_modulus / a.density < b.youngs_modulus / b.density;
  });
  s.materials = {*stiffest};
  const long long cells = static_cast<long long>(std::ceil(2.0 * horizon_m / h)) + 8;
  solver::LatticeSpec l;
  l.dimension = dimension;
  l.spacing = h;
  l.thickness = c.lattice ? c.lattice->thickness : h;
  for (int k = 0; k < 2 * dimension; ++k) l.box.push_back(k < dimension ? 0.0 : cells * h);
  s.lattice = l;
  return solver::setup_system(s).stable_dt;
}

}  // namespace

// Offsets (in spacings) of the family of a particle deep inside a square/cubic lattice at
// horizon factor m, by set-up's rule: the neighbour's cell reaches into the horizon.
std::vector<std::array<int, 3>> lattice_family_offsets(int dimension, double m) {
  const int reach = static_cast<int>(std::ceil(m + 1.0)) + 1;
  std::vector<std::array<int, 3>> out;
  for (int a = -reach; a <= reach; ++a)
    for (int b = -reach; b <= reach; ++b)
      for (int e = (dimension == 3 ? -reach : 0); e <= (dimension == 3 ? reach : 0); ++e) {
        if (!a && !b && !e) continue;
        const double xv[3] = {double(a), double(b), double(e)};
        if (solver::partial_volume_sampled(xv, m, 0.5, dimension) > 0) out.push_back({a, b, e});
      }
  return out;
}

double bulk_family_size(int dimension, double m) {
  return static_cast<double>(lattice_family_offsets(dimension, m).size());
}

// Bond entries of a whole lattice with one horizon, exactly and without building it: an
// offset o pairs (n_x - |o_x|)(n_y - |o_y|)(n_z - |o_z|) particles of the box.
long long lattice_bond_count(const std::array<long long, 3>& count, int dimension, double m) {
  long long total = 0;
  for (const auto& o : lattice_family_offsets(dimension, m)) {
    long long pairs = 1;
    for (int k = 0; k < 3; ++k) pairs *= std::max(0LL, count[k] - std::abs(o[k]));
    total += pairs;
  }
  return total;
}

// pd_system.hpp, PdSystem fields, in bytes per particle: 3-vectors x0 u v a force body x
// (7 x 3 doubles); volume density horizon half_cell energy_density dissipated damage
// max_stretch dilatation weighted_volume (10 doubles); PMB calibration_factor (1 double) or
// LPS coefficients (3 doubles) plus lps_a, lps_b (2); original_index (1 int64: a file index),
// internal_index material (2 int32); fixed_dof (1 byte); offsets (1 int64); and the
// ParticleModel copy it keeps (position 3, volume, spacing: 5 doubles; material_id: 1 int32).
// Correspondence keeps LPS's arrays plus its moduli (5), F and the force tensor (9 + 9) and
// the non-affine energy (1) per particle (correspondence.cpp, setup_correspondence).
double bytes_per_particle(int dimension, PdModel model) {
  const double doubles = 21 + 10 + (model == PdModel::PMB ? 1 : 5) + 5 + (model == PdModel::Correspondence ? 24 : 0);
  return doubles * sizeof(double) + 3 * sizeof(int32_t) + sizeof(uint8_t) + 2 * sizeof(int64_t);
}

// Per bond entry: the bond arrays set-up holds (pd_system.hpp bond_entry_bytes); softening bonds
// add s_onset and bond_damage (2 floats).
double bytes_per_bond(bool softening, bool shared_dual_halves, bool own_volumes_counted) {
  return static_cast<double>(bond_entry_bytes(shared_dual_halves, own_volumes_counted) + (softening ? 2 : 0) * sizeof(float));
}

// Does set-up share the dual halves with the own ones (setup.cpp: one horizon, every entry's two
// partial volumes equal, and a model that does not separate them)? A lattice has one spacing and
// so one horizon and equal partial volumes both ways; on tets the cells differ, so the estimate
// takes the halves as stored there.
static bool shares_dual_halves(const CaseConfig& c, const std::string& particles_kind, int dimension) {
  return particles_kind == "lattice" && !model_separates_dual_halves(c, dimension);
}

CostEstimate estimate_cost(const CaseConfig& c, const Throughputs& rates, const CostOptions& o) {
  if (c.model_name == "mps")
    throw InputError(c.file, "model.type", "'mps'",
                     "pmb, lps or correspondence (breccia-plan plans PD cases; MPS costs: docs/mps.md)");
  if (c.materials.empty()) throw InputError(c.file, "materials", "none given", "at least one material");
  CostEstimate e;
  e.model = c.model_name;
  e.threads = std::max(1, o.threads);
  e.quasi_static = c.quasi_static;

  // Particles: the same lattice set-up builds, or the particle file.
  Geometry g = c.lattice ? lattice_geometry(*c.lattice) : file_geometry(c.particles_path);
  e.dimension = g.dimension;
  e.particles_kind = g.kind;
  e.particles = g.count;
  e.spacing_m = median(g.spacing);
  e.min_spacing_m = *std::min_element(g.spacing.begin(), g.spacing.end());
  e.max_spacing_m = *std::max_element(g.spacing.begin(), g.spacing.end());
  const std::vector<double> horizon = horizons(c, g.spacing);
  e.horizon_m = median(horizon);
  e.horizon_factor = e.horizon_m / e.spacing_m;

  // Bonds and the stable step.
  long long padded = 0;
  int stable_step_passes = rates.stable_step_passes;  // the set-up's, where it runs here
  const bool small = e.particles <= o.exact_step_limit;
  if (small) {
    // Small enough to set up here: the solver's own numbers, exactly what breccia-solve gets.
    CaseConfig whole = c;
    whole.quasi_static = false;
    whole.dt.reset();
    whole.steps = 1;
    const solver::PdSystem s = solver::setup_system(whole);
    e.bonds = static_cast<long long>(s.bond_count());
    e.bonds_method = "the solver's set-up of the whole case (exact)";
    e.stable_dt_s = s.stable_dt;
    e.dt_method = "the solver's stable-step estimate on the whole case (exact)";
    stable_step_passes = s.stable_step_passes;
    padded = e.bonds;
  } else {
    if (c.lattice) {
      e.bonds = lattice_bond_count(lattice_counts(*c.lattice), e.dimension, e.horizon_factor);
      padded = e.bonds;
      e.bonds_method = "the lattice's family offsets counted over the box (exact for one horizon on a lattice)";
    } else if (e.particles <= o.exact_bond_limit) {
      const BondCount b = count_bonds(g, horizon);
      e.bonds = b.kept;
      padded = b.padded;
      e.bonds_method = "the solver's families (build_families) with set-up's partial-volume rule (exact)";
    } else {
      e.bonds = std::llround(e.particles * bulk_family_size(e.dimension, e.horizon_factor));
      padded = e.bonds;
      e.bonds_exact = false;
      e.bonds_method = "particles x bulk family size at m = " + std::to_string(e.horizon_factor) +
                       " (an upper bound: surface particles have fewer bonds)";
    }
    const double h_min = e.min_spacing_m;
    const double delta = c.horizon_m ? *c.horizon_m : c.horizon_factor * (c.variable_horizon ? h_min : e.spacing_m);
    e.stable_dt_s = sample_stable_dt(c, e.dimension, h_min, delta);
    e.dt_method = "the solver's stable-step estimate on a lattice block of the smallest spacing (" + std::to_string(h_min) +
                  " m) and the stiffest material";
    if (e.particles_kind == "tet")
      e.dt_method += "; irregular particles can be stiffer: breccia-solve computes the exact step";
  }
  if (c.dt && !c.quasi_static && c.check_stability && *c.dt > e.stable_dt_s)
    e.dt_method += "; time.dt = " + fmt_rate(*c.dt) + " s exceeds it: breccia-solve will refuse this case";
  if (c.quasi_static) {
    e.dt_s = 1.0;
    const double cells = g.longest_side_m / e.min_spacing_m;
    const double decades = std::log10(1.0 / c.adr_tolerance);
    const long long guess = std::llround(rates.adr_iterations_per_cell_decade * cells * decades);
    e.steps = std::min(guess, c.adr_max_steps);
    e.steps_method = "ADR iterations ~ " + std::to_string(rates.adr_iterations_per_cell_decade) + " x " +
                     std::to_string(std::llround(cells)) + " cells along the longest side x " + std::to_string(decades) +
                     " decades of residual (" + rates.adr_source + "), at most adr_max_steps";
  } else if (c.steps) {
    e.dt_s = c.dt ? *c.dt : c.safety * e.stable_dt_s;
    e.steps = *c.steps;
    e.steps_method = "time.steps";
  } else {
    e.dt_s = c.dt ? *c.dt : c.safety * e.stable_dt_s;
    e.steps = static_cast<long long>(std::ceil(*c.end_time / e.dt_s - 1e-9));  // as run.cpp counts them
    e.steps_method = c.dt ? "time.end / time.dt" : "time.end / (safety x stable step)";
  }

  // Memory: the run's arrays; set-up also holds the padded families and a few per-particle
  // temporaries (spacing, pad, counts, calibration sums: about 12 doubles).
  const PdModel model = c.model;
  e.bond_entry_bytes = bytes_per_bond(c.softening && c.fracture, shares_dual_halves(c, e.particles_kind, e.dimension),
                                    solver::own_volumes_counted(c));
  e.run_bytes = e.particles * bytes_per_particle(e.dimension, model) + e.bonds * e.bond_entry_bytes;
  e.setup_bytes = e.run_bytes + padded * sizeof(int32_t) + e.particles * (sizeof(int64_t) + 12 * sizeof(double));

  // Seconds: bond-updates over the measured per-core rate of the model and precision times
  // the threads. float32 without a measured float32 rate falls back to float64's, and says so.
  const bool f32 = c.precision == CaseConfig::Precision::Float32;
  const LoopRate* measured = f32 ? rates.find(model, e.threads, "float32") : nullptr;
  const LoopRate& r = measured ? *measured : rates.rate(model, e.threads);
  e.rate_source = r.source + (r.threads != e.threads ? " (measured at " + std::to_string(r.threads) +
                                                           " thread(s); per-core rate assumed to hold)"
                                                     : "");
  if (f32 && !measured) e.rate_source += " (float64 rate: no float32 rate measured for " + r.model + ")";
  // Softening bonds read two more floats per entry and evaluate the law's branch.
  double softening_factor = 1.0;
  if (c.softening && c.fracture)
    for (const auto& f : rates.softening)
      if (f.model == model_key(model)) {
        softening_factor = f.time_factor;
        e.rate_source += "; softening bonds x" + fmt_rate(f.time_factor) + " time (" + f.source + ")";
      }
  const double rate = r.bond_updates_per_core_s * e.threads / softening_factor;
  e.setup_source = "stable-step estimate (" + std::to_string(stable_step_passes) + " force passes" +
                   (small ? ", as the set-up ran here" : ", the documented count") + ") at that rate + " +
                   "other set-up work at " + fmt_rate(rates.setup_bonds_per_core_s) + " bond entries per core-second (" +
                   rates.setup_source + ")";
  e.loop_s = static_cast<double>(e.bonds) * static_cast<double>(e.steps) / rate;
  e.setup_s = static_cast<double>(e.bonds) / (rates.setup_bonds_per_core_s * e.threads) +
              stable_step_passes * static_cast<double>(e.bonds) / rate;
  if (rates.gpu_bond_updates_per_s) {
    e.gpu_loop_s = static_cast<double>(e.bonds) * e.steps / *rates.gpu_bond_updates_per_s;
    e.gpu_note = rates.gpu_source;
  } else {
    e.gpu_note = "no measured GPU throughput";
  }
  return e;
}

}  // namespace breccia::plan
