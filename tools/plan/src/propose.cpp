// The cheapest setup that meets a tolerance: 2D where the case is plane, PMB where
// Poisson's ratio allows, the coarsest spacing and the horizon factor the atlas says are
// enough; and the proposed case file.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <set>

#include "breccia/common/error.hpp"
#include "breccia/common/expression.hpp"
#include "breccia/common/output_file.hpp"
#include "breccia/common/yaml_input.hpp"
#include "breccia/plan/plan.hpp"
#include "breccia/solver/calibration.hpp"

namespace breccia::plan {

using solver::CaseConfig;
using solver::PdModel;
using solver::Planar;

namespace {

// A number as a case file holds it: 15 significant digits (round-trips any input value).
std::string yaml_number(double v) {
  char b[48];
  std::snprintf(b, sizeof b, "%.15g", v);
  return b;
}

std::string fmt(double v, int digits = 3) {
  char b[48];
  std::snprintf(b, sizeof b, "%.*g", digits, v);
  return b;
}

const std::set<std::string> kInPlaneFaces{"xmin", "xmax", "ymin", "ymax"};

bool zero(double v) { return std::fabs(v) < 1e-300; }

// Why a value given by expression (a boundary's in x, y, z, t; an initial condition's in
// x, y, z) is not the same in every z-slice or has a z part, or empty when it is neither:
// an expression that names z varies through the thickness, and a z component that names a
// variable or is a constant other than 0 moves the body along z.
std::string expression_out_of_plane(const std::vector<std::string>& expression, const std::string& what) {
  const std::vector<std::string> variables{"x", "y", "z", "t"};
  for (size_t d = 0; d < expression.size(); ++d) {
    const Expression e(expression[d], variables, "", "");
    if (e.uses("z")) return what + " expression '" + expression[d] + "' varies with z";
    if (d == 2 && (e.uses("x") || e.uses("y") || e.uses("t") || !zero(e({0.0, 0.0, 0.0, 0.0}))))
      return what + " expression has a z part ('" + expression[d] + "')";
  }
  return {};
}

// A 3D polygon pre-crack that is a through-thickness extrusion of a segment: its points
// project onto exactly two in-plane points. Returns them.
std::optional<std::array<solver::Vec3, 2>> extruded_segment(const solver::PrecrackSpec& p, double tol) {
  std::vector<solver::Vec3> distinct;
  for (const auto& q : p.points) {
    const bool seen = std::any_of(distinct.begin(), distinct.end(), [&](const solver::Vec3& d) {
      return std::hypot(d[0] - q[0], d[1] - q[1]) < tol;
    });
    if (!seen) distinct.push_back({q[0], q[1], 0.0});
  }
  if (distinct.size() != 2) return std::nullopt;
  return std::array<solver::Vec3, 2>{distinct[0], distinct[1]};
}

bool pmb_allowed(const CaseConfig& c, int dimension, Planar planar) {
  const double nu = solver::pmb_poisson_ratio(dimension, planar);
  return std::all_of(c.materials.begin(), c.materials.end(),
                     [&](const auto& m) { return std::fabs(m.poisson_ratio - nu) <= 1e-6; });
}

// Exact particle count of a lattice box at spacing h (set-up's rounding).
long long lattice_particles(const std::vector<double>& box, int d, double h) {
  long long n = 1;
  for (int k = 0; k < d; ++k) n *= std::max(1LL, std::llround((box[k + d] - box[k]) / h));
  return n;
}

std::vector<double> in_plane_box(const solver::LatticeSpec& l) {
  if (l.dimension == 2) return l.box;
  return {l.box[0], l.box[1], l.box[3], l.box[4]};
}

}  // namespace

double spacing_for_resolution(const std::vector<double>& box, int d, double resolution) {
  double longest = 0.0;
  for (int k = 0; k < d; ++k) longest = std::max(longest, box[k + d] - box[k]);
  // A hair below resolution^d: the resolution is a row's particle count to the 1/d, and
  // pow(pow(500, 1/2), 2) = 500.00000000000006 would miss the measured 500-particle lattice.
  const double target = std::pow(resolution, d) * (1.0 - 1e-9);
  double lo = longest * 1e-6, hi = longest;  // lo meets the target, hi (one cell) does not, unless target <= 1
  if (lattice_particles(box, d, hi) >= target) return hi;
  for (int it = 0; it < 80; ++it) {
    const double mid = std::sqrt(lo * hi);
    (lattice_particles(box, d, mid) >= target ? lo : hi) = mid;
  }
  return longest / std::ceil(longest / lo - 1e-9);
}

namespace {

struct Candidate {
  int dimension;
  Planar planar;
  PdModel model;
  double m;
  double spacing;
  double expected_error;
  double cost_s;
  std::string how;
};

std::string describe(int d, Planar planar, const std::string& model, double m, double h) {
  std::string s = std::to_string(d) + "D";
  if (planar == Planar::PlaneStress) s += " plane stress";
  if (planar == Planar::PlaneStrain) s += " plane strain";
  return s + " " + model + ", m = " + fmt(m, 4) + ", spacing " + fmt(h, 4) + " m";
}

}  // namespace

PlaneCheck plane_check(const CaseConfig& c) {
  PlaneCheck p;
  if (!c.lattice) {
    p.why = "the particles come from a file: a 2D model needs a 2D mesh (breccia-mesh with a 2D specimen), which "
            "the planner cannot make for you";
    return p;
  }
  const auto& l = *c.lattice;
  if (l.dimension == 2) {
    p.plane = true;
    p.planar = c.planar;
    p.why = "the case is already 2D";
    return p;
  }
  const double lx = l.box[3] - l.box[0], ly = l.box[4] - l.box[1], lz = l.box[5] - l.box[2];
  const long long layers = std::max(1LL, std::llround(lz / l.spacing));
  auto no = [&](const std::string& why) {
    p.why = why;
    return p;
  };
  // Everything that acts on the body must be the same in every z-slice and have no z part.
  for (const auto& ld : c.loads) {
    if (ld.kind == solver::LoadSpec::Kind::BodyForce) {
      if (!ld.set.empty() && !kInPlaneFaces.count(ld.set)) return no("body force on set '" + ld.set + "' is not extrusion-invariant");
    } else if (!kInPlaneFaces.count(ld.surface)) {
      return no("a load acts on surface '" + ld.surface + "', which is not a side face (xmin, xmax, ymin, ymax)");
    }
    if (!zero(ld.vector[2])) return no("a load has a z component");
  }
  bool z_min_held = false, z_max_held = false;
  for (const auto& b : c.boundaries) {
    if (b.set == "zmin" || b.set == "zmax") {
      const bool only_z = !b.components[0] && !b.components[1] && b.components[2];
      const bool held = b.kind == solver::BoundarySpec::Kind::Fixed || zero(b.value[2]);
      if (!only_z || !held) return no("boundary on '" + b.set + "' is not a zero normal displacement (plane strain)");
      (b.set == "zmin" ? z_min_held : z_max_held) = true;
      continue;
    }
    if (!kInPlaneFaces.count(b.set)) return no("a boundary acts on set '" + b.set + "', not a side face");
    if (!zero(b.value[2])) return no("a boundary prescribes motion along z");
    if (const std::string why = expression_out_of_plane(b.expression, "a boundary's"); !why.empty()) return no(why);
  }
  for (const auto& ic : c.initial) {
    if (!ic.set.empty() && !kInPlaneFaces.count(ic.set)) return no("an initial condition acts on set '" + ic.set + "'");
    if (!ic.field_file.empty()) return no("an initial condition is read from a file (" + ic.field_file + "), per particle in 3D");
    if (ic.kind != solver::InitialSpec::Kind::RadialVelocity && !zero(ic.value[2]))
      return no(std::string("an initial ") + (ic.kind == solver::InitialSpec::Kind::Velocity ? "velocity" : "displacement") +
                " has a z part");
    if (const std::string why = expression_out_of_plane(ic.expression, "an initial condition's"); !why.empty())
      return no(why);
    if (ic.kind == solver::InitialSpec::Kind::RadialVelocity && !ic.cylindrical)
      return no("a spherical radial velocity has a z part");
  }
  for (const auto& s : c.no_fail_sets)
    if (!kInPlaneFaces.count(s)) return no("no_fail set '" + s + "' is not a side face");
  if (c.indenter.enabled) return no("a spherical indenter is a 3D load");
  for (const auto& pc : c.precracks)
    if (pc.kind != solver::PrecrackSpec::Kind::Polygon || !extruded_segment(pc, 0.25 * l.spacing))
      return no("a pre-crack is not a through-thickness extrusion of a segment");
  if (z_min_held != z_max_held) return no("only one z face is held: neither plane stress nor plane strain");
  if (z_min_held) {
    p.plane = true;
    p.planar = Planar::PlaneStrain;
    p.why = "both z faces are held in z and every load, constraint and crack is the same in each z-slice: plane strain "
            "(exact)";
    return p;
  }
  // Free z faces: plane stress holds when the body is thin against its in-plane extent.
  const double thin_limit = 0.25 * std::min(lx, ly);
  if (layers == 1 || lz <= thin_limit) {
    p.plane = true;
    p.planar = Planar::PlaneStress;
    p.why = (layers == 1 ? std::string("the lattice is one layer thick")
                         : "the z thickness " + fmt(lz) + " m is at most a quarter of the smaller in-plane side (" +
                               fmt(std::min(lx, ly)) + " m)") +
            ", its z faces are free, and every load, constraint and crack is the same in each z-slice: plane stress";
    return p;
  }
  return no("the z faces are free but the thickness " + fmt(lz) + " m exceeds a quarter of the smaller in-plane side (" +
            fmt(std::min(lx, ly)) + " m): neither plane stress nor plane strain is safe");
}

CaseConfig proposed_config(const CaseConfig& c, const Proposal& p) {
  CaseConfig out = c;
  out.model = p.model == "lps" ? PdModel::LPS : p.model == "correspondence" ? PdModel::Correspondence : PdModel::PMB;
  out.model_name = p.model;
  out.horizon_factor = p.horizon_factor;
  out.horizon_m.reset();
  // The proposal's precision either way: a float32 case the atlas did not clear for float32
  // is proposed (costed, written) in float64, as the reasoning says.
  out.precision = p.precision == "float32" ? solver::CaseConfig::Precision::Float32 : solver::CaseConfig::Precision::Float64;
  // The atlas measures PMB and LPS with the energy surface correction where a free surface
  // matters (tools/atlas, model_yaml): a proposal must run as its rows ran to have their error.
  if (p.from_atlas && (p.model == "pmb" || p.model == "lps")) out.surface_correction = true;
  if (!c.lattice) return out;
  solver::LatticeSpec l = *c.lattice;
  l.spacing = p.spacing_m;
  if (c.lattice->dimension == 3 && p.dimension == 2) {
    l.thickness = l.box[5] - l.box[2];
    l.box = in_plane_box(*c.lattice);
    l.dimension = 2;
    out.planar = p.planar;
    std::erase_if(out.boundaries, [](const auto& b) { return b.set == "zmin" || b.set == "zmax"; });
    for (auto& b : out.boundaries) b.components[2] = false;
    for (auto& pc : out.precracks) {
      const auto seg = extruded_segment(pc, 0.25 * c.lattice->spacing);
      pc.kind = solver::PrecrackSpec::Kind::Segment;
      pc.points = {(*seg)[0], (*seg)[1]};
    }
    for (auto& pr : out.probes) pr.position[2] = 0.0;
  }
  out.lattice = l;
  return out;
}

Proposal propose(const CaseConfig& c, const std::vector<AtlasRow>& atlas, double tolerance, const Throughputs& rates,
                 const CostOptions& options) {
  if (!(tolerance > 0)) throw InputError("", "--tolerance", fmt(tolerance), "a relative error > 0 (e.g. 0.02)");
  Proposal best;
  auto& why = best.reasoning;
  const CostEstimate given = estimate_cost(c, rates, options);
  const ProblemClass problem = classify_problem(c);
  why.push_back("Problem class: " + problem.problem + ", because " + problem.why + ".");
  const std::string kind = given.particles_kind;
  // Correspondence (docs/plan.md): dearer per bond than LPS, CPU and float64 only, and it needs
  // stabilisation; the atlas measures PMB and LPS, which are the candidates below.
  const bool correspondence = c.model == PdModel::Correspondence;
  const std::optional<double> corr_cost = rates.relative_cost(PdModel::Correspondence, PdModel::LPS, options.threads);
  if (correspondence) {
    std::string text = "The case asks for correspondence PD (model.type: correspondence). Its time loop costs ";
    if (corr_cost) {
      const LoopRate* r = rates.find(PdModel::Correspondence, options.threads, "float64");
      text += fmt(*corr_cost) + "x LPS's per bond entry (" + r->source + ")";
    } else {
      text += "an unmeasured multiple of LPS's per bond entry (no correspondence rate in " + rates.file + ")";
    }
    text += "; it runs on the CPU in float64 only, and it needs stabilisation against its zero-energy (hourglass) "
            "modes: the stability map stopped every unstabilised run and none at penalty G >= 1 (docs/atlas.md)";
    if (c.stabilisation == "none") text += ", and this case has model.stabilisation: none";
    text += ". For the elastic response LPS gives the same constants for any Poisson's ratio, and the atlas has no "
            "correspondence rows, so the candidates are LPS (and PMB where Poisson's ratio allows): one that meets "
            "the tolerance is proposed instead. Keep correspondence if the case needs a constitutive law through the "
            "deformation gradient.";
    why.push_back(text);
  }

  // Dimensions worth trying.
  const PlaneCheck plane = plane_check(c);
  std::vector<std::pair<int, Planar>> dims{{given.dimension, c.planar}};
  if (given.dimension == 3 && plane.plane) {
    dims.insert(dims.begin(), {2, plane.planar});
    why.push_back("2D is enough: " + plane.why + ".");
  } else if (given.dimension == 3) {
    why.push_back("Staying in 3D: " + plane.why + ".");
  }

  // Models per dimension: PMB where every material's Poisson ratio is the one PMB fixes.
  auto models_for = [&](int d, Planar planar) {
    std::vector<PdModel> ms{PdModel::LPS};
    if (pmb_allowed(c, d, planar)) ms.insert(ms.begin(), PdModel::PMB);
    return ms;
  };
  for (const auto& [d, planar] : dims) {
    const double nu = solver::pmb_poisson_ratio(d, planar);
    why.push_back(std::string(pmb_allowed(c, d, planar) ? "PMB (bond-based, the cheaper kernel) is allowed"
                                                         : "PMB is not allowed") +
                  " in " + std::to_string(d) + "D" + (planar == Planar::PlaneStress ? " plane stress" : planar == Planar::PlaneStrain ? " plane strain" : "") +
                  ": it fixes Poisson's ratio at " + fmt(nu) + (pmb_allowed(c, d, planar) ? ", which the materials have." : "; LPS takes any ratio."));
  }

  const double tol = tolerance;
  std::vector<Candidate> candidates;
  bool any_rows = false;
  for (const auto& [d, planar] : dims) {
    for (PdModel model : models_for(d, planar)) {
      const std::string mname = model == PdModel::LPS ? "lps" : "pmb";
      std::vector<double> ms;
      for (const auto& r : atlas)
        if (r.problem == problem.problem && r.model == mname && r.dimension == d && r.particles_kind == kind &&
            std::none_of(ms.begin(), ms.end(), [&](double x) { return std::fabs(x - r.m) < 1e-6; }))
          ms.push_back(r.m);
      for (double m : ms) {
        const ResolutionNeed need = resolution_for(atlas, problem.problem, mname, d, kind, m, tol);
        if (need.resolution <= 0) continue;
        any_rows = true;
        Candidate cand{d, planar, model, m, given.spacing_m, need.error_at_need, 0.0, need.how};
        if (!need.met) {
          cand.cost_s = -1;  // marks "does not meet"
          candidates.push_back(cand);
          continue;
        }
        if (c.lattice) {
          const std::vector<double> box = d == 2 ? in_plane_box(*c.lattice) : c.lattice->box;
          cand.spacing = spacing_for_resolution(box, d, need.resolution);
        } else {
          // A particle file keeps its particles: it meets the tolerance only if it is already
          // fine enough, and its expected error is the atlas's at its own resolution.
          const double r_case = std::pow(static_cast<double>(given.particles), 1.0 / d);
          cand.expected_error = expected_error(atlas, problem.problem, mname, d, kind, m, r_case).error;
          if (r_case < need.resolution) {
            cand.cost_s = -1;
            cand.how += "; the particle file has " + fmt(r_case) + " particles per side: re-mesh about " +
                        fmt(need.resolution / r_case) + "x finer";
            candidates.push_back(cand);
            continue;
          }
        }
        // Quick cost of the candidate: exact particle count, bulk family size (upper
        // bound), stable step of a sample block at the candidate's spacing.
        Proposal trial;
        trial.dimension = d;
        trial.planar = planar;
        trial.model = mname;
        trial.horizon_factor = horizon_factor_of_row_m(m);
        trial.spacing_m = cand.spacing;
        trial.from_atlas = true;
        CostOptions quick = options;
        quick.exact_bond_limit = 0;
        quick.exact_step_limit = 0;
        const CostEstimate ce = estimate_cost(proposed_config(c, trial), rates, quick);
        cand.cost_s = ce.total_s();
        candidates.push_back(cand);
      }
    }
  }

  const auto meets = [](const Candidate& x) { return x.cost_s >= 0; };
  const auto cheapest = std::min_element(candidates.begin(), candidates.end(), [&](const auto& a, const auto& b) {
    if (meets(a) != meets(b)) return meets(a);
    return meets(a) ? a.cost_s < b.cost_s : a.expected_error < b.expected_error;
  });
  if (!any_rows || candidates.empty()) {
    // No atlas evidence: only the choices that do not change the error much are made.
    best.from_atlas = false;
    best.dimension = dims.front().first;
    best.planar = dims.front().second;
    best.model = models_for(best.dimension, best.planar).front() == PdModel::PMB ? "pmb" : "lps";
    // Without atlas rows nothing shows LPS meets the tolerance either: correspondence stays.
    if (correspondence) best.model = "correspondence";
    best.horizon_factor = given.horizon_factor;
    best.spacing_m = given.spacing_m;
    why.push_back("The atlas has no float64 rows for " + problem.problem + " with " + kind +
                  " particles: the expected error is unknown, so the spacing and horizon factor are kept as given "
                  "and the tolerance cannot be checked.");
    if (correspondence)
      why.push_back("Correspondence is kept: LPS would cost " +
                    (corr_cost ? fmt(1.0 / *corr_cost) + "x as much per bond entry" : std::string("less")) +
                    ", but without atlas rows nothing shows that it meets the tolerance.");
    else if (best.model != c.model_name)
      why.push_back("The switch to " + best.model + " rests on Poisson's ratio alone (both models give the same "
                    "elastic constants then); near free surfaces and in fracture they differ, and without atlas rows "
                    "that difference is not checked. Keep " + c.model_name + " if that matters more than the cost.");
  } else {
    const Candidate& pick = *cheapest;
    best.from_atlas = true;
    best.tolerance_met = meets(pick);
    best.dimension = pick.dimension;
    best.planar = pick.planar;
    best.model = pick.model == PdModel::LPS ? "lps" : "pmb";
    best.horizon_factor = horizon_factor_of_row_m(pick.m);
    best.spacing_m = pick.spacing;
    best.expected_error = pick.expected_error;
    for (const auto& x : candidates)
      why.push_back(std::string(&x == &pick ? "* " : "  ") + "Candidate " +
                    describe(x.dimension, x.planar, x.model == PdModel::LPS ? "lps" : "pmb", x.m, x.spacing) + ": " +
                    (meets(x) ? "meets " + fmt(tol) + " (" + x.how + "), about " + fmt(x.cost_s) + " s on the CPU"
                              : "does not meet " + fmt(tol) + ": " + x.how) +
                    ".");
    if (best.tolerance_met) {
      why.push_back("Chosen: the cheapest candidate that meets the tolerance (" +
                    describe(best.dimension, best.planar, best.model, best.horizon_factor, best.spacing_m) + ").");
      why.push_back("The atlas measures " + best.model + " with the energy surface correction, so the proposal "
                    "turns it on (model.surface_correction: energy).");
      if (correspondence)
        why.push_back("Correspondence is replaced by " + best.model + ": the atlas shows it meets the tolerance, and "
                      "correspondence would cost " + (corr_cost ? fmt(*corr_cost) + "x LPS's time per bond entry" :
                      std::string("more per bond entry (not measured)")) + " and need stabilisation "
                      "(model.stabilisation is dropped from the proposed case).");
    } else {
      why.push_back("No measured setting meets " + fmt(tol) + ": proposed the setting with the smallest measured error (" +
                    fmt(pick.expected_error) + "); the tolerance is NOT met by anything the atlas has measured.");
    }
    if (!c.lattice && best.tolerance_met) {
      const double r_case = std::pow(static_cast<double>(given.particles), 1.0 / given.dimension);
      const auto need = resolution_for(atlas, problem.problem, best.model, best.dimension, kind, pick.m, tol);
      const double factor = r_case / need.resolution;
      why.push_back("The particles come from a mesh, which the planner cannot re-make: the atlas needs about " +
                    fmt(need.resolution) + " particles per side, the case has " + fmt(r_case) + "; " +
                    (factor >= 1 ? "a mesh size up to " + fmt(factor) + "x coarser would do (re-mesh to save time)."
                                 : "re-mesh about " + fmt(1 / factor) + "x finer to meet the tolerance."));
    }
  }

  // Refinement where it matters: dual horizon on graded meshes.
  if (!c.lattice && given.max_spacing_m > 1.5 * given.min_spacing_m) {
    why.push_back(std::string("The particle file is graded (spacing ") + fmt(given.min_spacing_m) + " to " +
                  fmt(given.max_spacing_m) + " m): " +
                  (c.variable_horizon ? "the case already uses a per-particle (dual) horizon, which keeps the coarse "
                                        "region from dragging the fine one's horizon up."
                                      : "set model.variable_horizon: true (dual horizon) so each region uses its own "
                                        "horizon; with one horizon the fine region pays for the coarse spacing."));
  } else {
    why.push_back("Refinement only near loads and pre-cracks (not done automatically): mesh the specimen with "
                  "breccia-mesh size fields that are fine there and coarse elsewhere, place particles with "
                  "breccia-place, and run with model.variable_horizon: true (dual horizon); for a uniform lattice "
                  "this can cut the particle count several-fold when the loads and cracks occupy a small region.");
  }
  // Precision: float32 where every float32 atlas row at the proposed model has the error of
  // its float64 twin within a tenth of the tolerance (then the spacing chosen from float64
  // rows holds for float32 too), and the measured throughputs show a gain of 10% at least
  // (docs/plan.md, Precision).
  const auto is_f32 = [](const std::string& p) { return p == "float32" || p == "fp32" || p == "single"; };
  int f32_rows = 0, f32_safe = 0;
  double worst_shift = 0.0;
  for (const auto& r : atlas) {
    if (r.problem != problem.problem || r.model != best.model || !is_f32(r.precision)) continue;
    for (const auto& d : atlas)
      if (d.problem == r.problem && d.model == r.model && d.dimension == r.dimension &&
          d.particles_kind == r.particles_kind && std::fabs(d.m - r.m) < 1e-6 &&
          std::fabs(d.spacing_m - r.spacing_m) <= 1e-6 * d.spacing_m && d.precision == "float64") {
        ++f32_rows;
        worst_shift = std::max(worst_shift, std::fabs(r.error - d.error));
        f32_safe += std::fabs(r.error - d.error) <= 0.1 * tol;
      }
  }
  const solver::PdModel best_model = best.model == "lps"              ? solver::PdModel::LPS
                                     : best.model == "correspondence" ? solver::PdModel::Correspondence
                                                                      : solver::PdModel::PMB;
  const std::optional<double> speedup = rates.float32_speedup(best_model, options.threads);
  const bool safe = f32_rows > 0 && f32_safe == f32_rows;
  const bool faster = speedup && *speedup >= 1.1;
  if (safe && faster && !c.quasi_static && best_model != PdModel::Correspondence) best.precision = "float32";
  std::string text = "Precision: ";
  if (f32_rows == 0) {
    text += "the atlas has no float32 rows for " + problem.problem + " with " + best.model +
            ", so float32 is not shown safe";
  } else {
    text += std::to_string(f32_safe) + " of " + std::to_string(f32_rows) + " float32 atlas rows for " +
            problem.problem + " with " + best.model + " have float64's error within a tenth of the tolerance " +
            "(largest shift " + fmt(worst_shift) + ")";
  }
  if (!speedup) text += "; no float32 throughput is measured (throughputs.yaml), so no speed gain is shown";
  else text += "; measured float32 / float64 throughput " + fmt(*speedup) + (faster ? "" : " (no real gain)");
  if (c.quasi_static) text += "; ADR with float forces stalls near a residual of 1e-5 (docs/theory.md)";
  if (best_model == PdModel::Correspondence) text += "; the correspondence kernels exist in float64 only";
  text += best.precision == "float32" ? ": propose model.precision: float32." : ": the proposal stays float64.";
  why.push_back(text);

  best.cost = estimate_cost(proposed_config(c, best), rates, options);
  if (!best.from_atlas) best.expected_error = 0.0;
  const double saving = given.total_s() / std::max(best.cost.total_s(), 1e-12);
  why.push_back("Cost: " + fmt(best.cost.total_s()) + " s against " + fmt(given.total_s()) + " s as given (" +
                (saving >= 1 ? fmt(saving) + "x cheaper" : fmt(1 / saving) + "x dearer, to meet the tolerance") + ").");
  return best;
}

void write_proposed_case(const CaseConfig& c, const Proposal& p, const std::string& path) {
  YAML::Node root = YAML::Clone(Section::load_file(c.file).node());
  const std::filesystem::path case_dir = c.directory.empty() ? std::filesystem::path(".") : std::filesystem::path(c.directory);
  auto absolute = [&](const std::string& rel) {
    const std::filesystem::path q(rel);
    return (q.is_absolute() ? q : std::filesystem::absolute(case_dir / q)).lexically_normal().string();
  };
  const CaseConfig pc = proposed_config(c, p);
  if (pc.lattice) {
    YAML::Node lat;
    lat["dimension"] = pc.lattice->dimension;
    for (double v : pc.lattice->box) lat["box"].push_back(yaml_number(v));
    lat["box"].SetStyle(YAML::EmitterStyle::Flow);
    lat["spacing"] = yaml_number(pc.lattice->spacing);
    if (pc.lattice->dimension == 2) lat["thickness"] = yaml_number(pc.lattice->thickness);
    root["specimen"] = YAML::Node(YAML::NodeType::Map);
    lat.SetStyle(YAML::EmitterStyle::Flow);
    root["specimen"]["lattice"] = lat;
  } else {
    root["specimen"]["particles"] = absolute(root["specimen"]["particles"].as<std::string>());
  }
  YAML::Node model = root["model"];
  model["type"] = p.model;
  model.remove("horizon");
  model["horizon_factor"] = yaml_number(p.horizon_factor);
  if (p.precision == "float32") model["precision"] = "float32";
  else model.remove("precision");  // float64, the default
  if (p.model != "correspondence") model.remove("stabilisation");  // the loader refuses it for PMB and LPS
  if (pc.surface_correction) model["surface_correction"] = "energy";
  if (pc.lattice && pc.lattice->dimension == 2)
    model["planar"] = pc.planar == Planar::PlaneStrain ? "plane_strain" : "plane_stress";
  // History tables are read relative to the case file: make them absolute.
  if (root["loads"])
    for (auto ld : root["loads"])
      if (ld["history"] && ld["history"]["file"]) ld["history"]["file"] = absolute(ld["history"]["file"].as<std::string>());
  if (c.lattice && c.lattice->dimension == 3 && p.dimension == 2) {
    if (root["boundary"]) {
      YAML::Node kept(YAML::NodeType::Sequence);
      for (auto b : root["boundary"]) {
        const std::string set = b["set"] ? b["set"].as<std::string>() : "";
        if (set == "zmin" || set == "zmax") continue;
        if (b["components"]) {
          YAML::Node comps(YAML::NodeType::Sequence);
          for (auto x : b["components"])
            if (x.as<std::string>() != "z") comps.push_back(x.as<std::string>());
          if (comps.size() == 0) continue;  // it held only z, which is no degree of freedom in 2D
          b["components"] = comps;
        }
        kept.push_back(b);
      }
      root["boundary"] = kept;
    }
    if (root["precracks"]) {
      YAML::Node cracks(YAML::NodeType::Sequence);
      for (const auto& pcrack : pc.precracks) {
        YAML::Node n;
        n["type"] = "segment";
        for (int k = 0; k < 2; ++k) n["from"].push_back(yaml_number(pcrack.points[0][k]));
        for (int k = 0; k < 2; ++k) n["to"].push_back(yaml_number(pcrack.points[1][k]));
        n.SetStyle(YAML::EmitterStyle::Flow);
        cracks.push_back(n);
      }
      root["precracks"] = cracks;
    }
    if (root["output"] && root["output"]["probes"])
      for (auto pr : root["output"]["probes"])
        if (pr["position"] && pr["position"].size() == 3) pr["position"][2] = 0.0;
  }
  root["description"] = "proposed by breccia-plan from " + std::filesystem::absolute(c.file).string() +
                        (p.from_atlas ? " (expected error " + fmt(p.expected_error) + ")" : "");
  YAML::Emitter em;
  em << root;
  write_text_file(path, std::string("# Proposed by breccia-plan; the reasoning is in its output.\n") + em.c_str() + "\n");
  // The file must be a case breccia-solve accepts: parse it back with the solver's loader.
  (void)solver::parse_case_file(path);
}

}  // namespace breccia::plan
