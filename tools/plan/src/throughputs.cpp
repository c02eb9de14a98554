// Measured throughputs: read from throughputs.yaml (each number with its source) or
// measured on this machine with a short breccia-solve run of a lattice shaped like the case.
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <ctime>
#include <filesystem>

#include "breccia/common/data_dir.hpp"
#include "breccia/common/error.hpp"
#include "breccia/common/yaml_input.hpp"
#include "breccia/plan/plan.hpp"
#include "breccia/solver/calibration.hpp"
#include "breccia/solver/run.hpp"

namespace breccia::plan {

using solver::PdModel;

std::string model_key(PdModel model) {
  return model == PdModel::LPS ? "lps" : model == PdModel::Correspondence ? "correspondence" : "pmb";
}

const LoopRate* Throughputs::find(PdModel model, int threads, const std::string& precision) const {
  const std::string name = model_key(model);
  const LoopRate* best = nullptr;
  for (const auto& r : loop) {
    if (r.model != name || r.precision != precision) continue;
    if (!best || std::abs(r.threads - threads) < std::abs(best->threads - threads)) best = &r;
  }
  return best;
}

const LoopRate& Throughputs::rate(PdModel model, int threads) const {
  if (const LoopRate* best = find(model, threads, "float64")) return *best;
  const std::string name = model_key(model);
  throw InputError(file, "loop", "no throughput for model " + name, "an entry {model: " + name + ", threads, ...}");
}

std::optional<double> Throughputs::float32_speedup(PdModel model, int threads) const {
  const LoopRate* f32 = find(model, threads, "float32");
  if (!f32) return std::nullopt;
  // Against the float64 entry at the same thread count (same benchmark run).
  for (const auto& r : loop)
    if (r.model == f32->model && r.precision == "float64" && r.threads == f32->threads)
      return f32->bond_updates_per_core_s / r.bond_updates_per_core_s;
  return std::nullopt;
}

std::optional<double> Throughputs::relative_cost(PdModel model, PdModel reference, int threads) const {
  const LoopRate* a = find(model, threads, "float64");
  const LoopRate* b = find(reference, threads, "float64");
  if (!a || !b) return std::nullopt;
  return b->bond_updates_per_core_s / a->bond_updates_per_core_s;
}

std::string default_throughputs_path() {
  // Installed as share/breccia/plan/throughputs.yaml (in the build tree: a link to tools/plan/).
  return data_path("BRECCIA_PLAN_THROUGHPUTS", "plan/throughputs.yaml").string();
}

Throughputs load_throughputs(const std::string& path) {
  const Section root = Section::load_file(path);
  root.allow_only({"loop", "setup", "adr", "gpu", "softening"});
  Throughputs t;
  t.file = path;
  for (const Section& l : root.list("loop")) {
    l.allow_only({"model", "threads", "bond_updates_per_core_s", "source", "precision"});
    LoopRate r;
    r.model = l.choice("model", {"pmb", "lps", "correspondence"});
    r.threads = static_cast<int>(l.integer("threads"));
    if (r.threads < 1) throw InputError(path, l.field("threads"), std::to_string(r.threads), "a thread count >= 1");
    r.bond_updates_per_core_s = l.positive("bond_updates_per_core_s", Quantity::Dimensionless);
    r.source = l.text("source", path);
    r.precision = l.choice("precision", {"float64", "float32"}, "float64");
    t.loop.push_back(r);
  }
  if (t.loop.empty()) throw InputError(path, "loop", "no entries", "measured loop throughputs per model");
  if (root.node()["softening"])
    for (const Section& l : root.list("softening")) {
      l.allow_only({"model", "time_factor", "source"});
      t.softening.push_back({l.choice("model", {"pmb", "lps"}), l.positive("time_factor", Quantity::Dimensionless),
                             l.text("source", path)});
    }
  const Section setup = root.section("setup");
  setup.allow_only({"bonds_per_core_s", "source", "stable_step_passes"});
  t.setup_bonds_per_core_s = setup.positive("bonds_per_core_s", Quantity::Dimensionless);
  t.setup_source = setup.text("source", path);
  t.stable_step_passes = static_cast<int>(setup.integer("stable_step_passes", t.stable_step_passes));
  if (t.stable_step_passes < 1)
    throw InputError(path, setup.field("stable_step_passes"), std::to_string(t.stable_step_passes),
                     "a count of force passes >= 1");
  const Section adr = root.section("adr");
  adr.allow_only({"iterations_per_cell_decade", "source"});
  t.adr_iterations_per_cell_decade = adr.positive("iterations_per_cell_decade", Quantity::Dimensionless);
  t.adr_source = adr.text("source", path);
  if (auto gpu = root.optional_section("gpu")) {
    gpu->allow_only({"bond_updates_per_s", "source"});
    const YAML::Node n = gpu->node()["bond_updates_per_s"];
    if (n && !n.IsNull()) t.gpu_bond_updates_per_s = gpu->positive("bond_updates_per_s", Quantity::Dimensionless);
    t.gpu_source = gpu->text("source", "");
  }
  return t;
}

Throughputs calibrate(const solver::CaseConfig& like, int threads, const Throughputs& base, double target_bonds,
                      double min_loop_s) {
  // A lattice block with the case's dimension, model, influence and horizon factor; no
  // loads and no breaking (the breaking check still runs), like the benchmark of
  // docs/performance.md. The loop is breccia-solve's own time loop (run_system), so
  // output-step diagnostics cost what they cost in a real run.
  solver::CaseConfig c;
  c.name = "calibration";
  c.file = "(calibration)";
  const int d = like.lattice ? like.lattice->dimension : (like.planar == solver::Planar::None ? 3 : 2);
  const double m = like.horizon_m && like.lattice ? *like.horizon_m / like.lattice->spacing : like.horizon_factor;
  const long long per_side = std::max<long long>(
      8, std::llround(std::pow(target_bonds / std::max(1.0, bulk_family_size(d, m)), 1.0 / d)));
  const double h = 1e-3;
  solver::LatticeSpec lat;
  lat.dimension = d;
  lat.spacing = h;
  lat.thickness = h;
  for (int k = 0; k < 2 * d; ++k) lat.box.push_back(k < d ? 0.0 : per_side * h);
  c.lattice = lat;
  c.model = like.model;
  c.model_name = model_key(like.model);
  c.stabilisation = like.stabilisation;  // correspondence: the penalty pass costs what it costs
  c.stabilisation_coefficient = like.stabilisation_coefficient;
  c.planar = d == 2 ? (like.planar == solver::Planar::None ? solver::Planar::PlaneStress : like.planar)
                    : solver::Planar::None;
  c.influence = like.influence;
  c.horizon_factor = m;
  solver::MaterialSpec mat = like.materials.empty() ? solver::MaterialSpec{} : like.materials.front();
  if (mat.density <= 0) mat.density = 2500;
  if (mat.youngs_modulus <= 0) mat.youngs_modulus = 50e9;
  if (c.model == PdModel::PMB) mat.poisson_ratio = solver::pmb_poisson_ratio(d, c.planar);
  mat.fracture_energy = 0;
  mat.name = "calibration";
  c.materials = {mat};
  c.write_results = false;
  c.precision = like.precision;  // a float32 case is calibrated in float32

  omp_set_num_threads(std::max(1, threads));
  const std::clock_t cpu0 = std::clock();
  c.steps = 1;
  solver::PdSystem s = solver::setup_system(c);
  const double setup_cpu_s = static_cast<double>(std::clock() - cpu0) / CLOCKS_PER_SEC;
  const double bonds = static_cast<double>(s.bond_count());
  // Enough steps for min_loop_s at the documented rate (a short loop is dominated by noise).
  const double guess = base.rate(c.model, threads).bond_updates_per_core_s;
  const long long steps = std::max<long long>(20, std::llround(min_loop_s * guess / std::max(1.0, bonds)));
  s.config.steps = steps;
  solver::RunOptions o;
  o.progress = false;
  o.out_dir = (std::filesystem::temp_directory_path() /
               ("breccia-plan-calibration-" + std::to_string(std::chrono::steady_clock::now().time_since_epoch().count())))
                  .string();
  const solver::RunResult r = solver::run_system(s, o);
  std::error_code ec;
  std::filesystem::remove_all(o.out_dir, ec);

  Throughputs t = base;
  const double loop_rate = bonds * static_cast<double>(r.steps) / std::max(r.cpu_s, 1e-9);  // per CPU-second
  const std::string what = std::to_string(s.n) + " particles, " + std::to_string(s.bond_count()) + " bonds, " +
                           std::to_string(r.steps) + " steps, " + std::to_string(threads) + " thread(s)";
  const bool f32 = c.precision == solver::CaseConfig::Precision::Float32;
  LoopRate lr{c.model_name, std::max(1, threads), loop_rate, "measured on this machine by --calibrate (" + what + ")",
              f32 ? "float32" : "float64"};
  // A float64 calibration replaces the model's entries (a float32 entry from another machine
  // would no longer compare); a float32 one only the float32 entries (float64 candidates of
  // the proposal still need their rate).
  std::erase_if(t.loop, [&](const LoopRate& x) { return x.model == lr.model && (!f32 || x.precision == "float32"); });
  t.loop.push_back(lr);
  // Set-up other than the stable-step estimate (its force passes as the set-up counted
  // them); never below a tenth of the documented rate's cost share (a very short set-up can
  // measure as ~0 on a coarse clock).
  const double stable_step_s = s.stable_step_passes * bonds / loop_rate;
  const double rest_s = std::max(setup_cpu_s - stable_step_s, 0.1 * setup_cpu_s);
  t.setup_bonds_per_core_s = bonds / rest_s;
  t.setup_source = "measured on this machine by --calibrate (" + what + ")";
  return t;
}

}  // namespace breccia::plan
