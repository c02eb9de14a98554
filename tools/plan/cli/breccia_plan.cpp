// breccia-plan: what a PD case will cost and what error to expect, before running it, and
// the cheapest setup that meets a tolerance (docs/plan.md).
//   breccia-plan CASE.yaml --tolerance X [--write PROPOSED.yaml] [--atlas atlas.csv]
//                [--throughputs throughputs.yaml] [--calibrate] [--threads N]
// Example: breccia-plan cases/kalthoff-winkler/case.yaml --tolerance 0.05 --calibrate
// The command line is CLI11's with the tools' conventions (common/cli.hpp).
#include <omp.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "breccia/common/cli.hpp"
#include "breccia/common/error.hpp"
#include "breccia/common/yaml_input.hpp"
#include "breccia/plan/plan.hpp"
#include "breccia/solver/case_config.hpp"

namespace {

constexpr const char* kAbout =
    "breccia-plan: what a peridynamics case will cost (particles, bonds, steps, memory, CPU/GPU time)\n"
    "and what error to expect, before running it, and the cheapest setup that meets a tolerance.";
constexpr const char* kFooter =
    "Input: CASE.yaml (docs/case-format.md); the accuracy atlas (docs/atlas/atlas.csv, `make atlas`) and\n"
    "the measured throughputs (tools/plan/throughputs.yaml, or this machine's with --calibrate).\n"
    "Output: the estimates and the proposal on stdout; with --write, the proposed case as YAML.\n"
    "Example: breccia-plan cases/kalthoff-winkler/case-quick.yaml -o RUN --tolerance 0.05 (docs/plan.md; RUN:\n"
    "the run folder holding the case's particles.h5, written there as the case README says)";

std::string human_bytes(double b) {
  char s[32];
  if (b >= 1e9) std::snprintf(s, sizeof s, "%.2f GB", b / 1e9);
  else std::snprintf(s, sizeof s, "%.1f MB", b / 1e6);
  return s;
}

void print_cost(const breccia::plan::CostEstimate& e) {
  std::printf("  particles      %lld (%dD, %s)\n", e.particles, e.dimension, e.particles_kind.c_str());
  std::printf("  bonds          %lld entries, %.1f per particle, from %s\n", e.bonds,
              static_cast<double>(e.bonds) / std::max(1LL, e.particles), e.bonds_method.c_str());
  std::printf("  horizon        %.4g m = %.4g x spacing %.4g m (model %s)\n", e.horizon_m, e.horizon_factor, e.spacing_m,
              e.model.c_str());
  if (e.quasi_static) {
    std::printf("  iterations     %lld (estimate: %s)\n", e.steps, e.steps_method.c_str());
  } else {
    std::printf("  stable step    %.4e s, from %s\n", e.stable_dt_s, e.dt_method.c_str());
    std::printf("  steps          %lld of %.4e s (%s)\n", e.steps, e.dt_s, e.steps_method.c_str());
  }
  std::printf("  memory         %s during the run, %s peak during set-up (PdSystem arrays)\n",
              human_bytes(e.run_bytes).c_str(), human_bytes(e.setup_bytes).c_str());
  std::printf("  CPU            %.3g s with %d thread(s): set-up %.3g s + time loop %.3g s\n", e.total_s(), e.threads,
              e.setup_s, e.loop_s);
  std::printf("                 rate: %s\n", e.rate_source.c_str());
  std::printf("                 set-up: %s\n", e.setup_source.c_str());
  if (e.gpu_loop_s) std::printf("  GPU            time loop %.3g s (%s)\n", *e.gpu_loop_s, e.gpu_note.c_str());
  else std::printf("  GPU            %s\n", e.gpu_note.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  using namespace breccia;
  std::string case_file, write_path, atlas_path = plan::default_atlas_path(),
                                      rates_path = plan::default_throughputs_path();
  std::optional<double> tolerance;
  bool calibrate = false;
  plan::CostOptions opt;
  opt.threads = omp_get_max_threads();
  CLI::App app{kAbout, "breccia-plan"};
  cli::configure(app, kFooter);
  app.add_option("CASE", case_file, "the case file")->required()->type_name("CASE.yaml");
  // As breccia-solve reads the case: a relative input file is looked for in the run folder
  // first (-o), the case's variants and --set overrides applied.
  std::string run_dir, variant;
  std::vector<std::string> overrides;
  app.add_option("-o,--out", run_dir, "the run folder the case will write into: relative input files are looked for there first")
      ->type_name("DIR");
  app.add_option("--variant", variant, "apply the case file's variants.NAME overrides (before any --set)")->type_name("NAME");
  app.add_option("--set", overrides, "override a value of the case file (repeatable)")
      ->type_name("KEY=VALUE")
      ->allow_extra_args(false);
  app.add_option_function<double>(
         "--tolerance", [&](double x) { tolerance = x; },
         "the relative error you accept (0.02 = 2%), as the atlas measures it")
      ->type_name("X")
      ->check(cli::real_number());
  app.add_option("--write", write_path, "write the proposed case here")->type_name("PROPOSED.yaml");
  CLI::Option* atlas_option =
      app.add_option("--atlas", atlas_path, "the accuracy atlas")->type_name("atlas.csv")->capture_default_str();
  app.add_option("--throughputs", rates_path, "the measured throughputs")
      ->type_name("throughputs.yaml")
      ->capture_default_str();
  app.add_flag("--calibrate", calibrate,
               "measure this machine first (a short time loop, seconds) instead of the documented throughputs");
  app.add_option("--threads", opt.threads, "the thread count to cost (default: OpenMP's)")
      ->type_name("N")
      ->check(cli::whole_number(1));
  if (const auto code = cli::parse(app, argc, argv)) return *code;
  const bool atlas_given = atlas_option->count() > 0;
  if (!tolerance) {
    std::fprintf(stderr, "error: --tolerance: missing (expected a relative error > 0, e.g. --tolerance 0.02)\n");
    return kExitBadInput;
  }
  if (!(*tolerance > 0) || !std::isfinite(*tolerance)) {
    std::fprintf(stderr, "error: --tolerance: %g (expected a relative error > 0, e.g. 0.02)\n", *tolerance);
    return kExitBadInput;
  }
  try {
    if (!std::filesystem::exists(case_file))
      throw InputError(case_file, "", "no such case file", "a case YAML (docs/case-format.md)");
    Section::set_overrides(case_file, overrides, variant, run_dir);
    const solver::CaseConfig config = solver::parse_case_file(case_file);
    plan::Throughputs rates = plan::load_throughputs(rates_path);
    omp_set_num_threads(opt.threads);
    if (calibrate) {
      std::fprintf(stderr, "calibrating on this machine (%d thread(s))...\n", opt.threads);
      // Both models, so candidates of either are compared on this machine's rates; the
      // case's own model last, so the set-up rate is measured with it.
      solver::CaseConfig other = config;
      other.model = config.model == solver::PdModel::LPS ? solver::PdModel::PMB : solver::PdModel::LPS;
      other.model_name = other.model == solver::PdModel::LPS ? "lps" : "pmb";
      rates = plan::calibrate(other, opt.threads, rates);
      rates = plan::calibrate(config, opt.threads, rates);
      omp_set_num_threads(opt.threads);
    }
    std::vector<plan::AtlasRow> atlas;
    std::string atlas_note;
    // A missing default atlas is a note (run `make atlas`); a file named by --atlas that is
    // not there is a typo the user should hear about.
    if (atlas_given && !std::filesystem::exists(atlas_path))
      throw InputError(atlas_path, "--atlas", "no such file", "an atlas CSV (docs/atlas/atlas.csv, or `make atlas`)");
    if (std::filesystem::exists(atlas_path)) {
      atlas = plan::read_atlas(atlas_path);
      atlas_note = std::to_string(atlas.size()) + " rows from " + atlas_path;
    } else {
      atlas_note = "no atlas at " + atlas_path + " (run `make atlas`, or pass --atlas FILE)";
    }

    // Where --write will go, checked before the estimates are printed (a path it cannot write
    // was an error after them, exit 3).
    if (!write_path.empty())
      breccia::cli::require_writable_folder("--write", std::filesystem::path(write_path).parent_path());
    std::printf("breccia-plan: %s (%s)\n\nCost of the case as given\n", config.name.c_str(), case_file.c_str());
    const plan::CostEstimate given = plan::estimate_cost(config, rates, opt);
    print_cost(given);

    const plan::ProblemClass problem = plan::classify_problem(config);
    std::printf("\nExpected error (atlas: %s)\n  problem class  %s\n", atlas_note.c_str(), problem.problem.c_str());
    const double resolution = std::pow(static_cast<double>(given.particles), 1.0 / given.dimension);
    const plan::ErrorEstimate err = plan::expected_error(atlas, problem.problem, given.model, given.dimension,
                                                         given.particles_kind, given.horizon_factor, resolution);
    if (err.known) std::printf("  expected error %.3g (%s)\n", err.error, err.how.c_str());
    else std::printf("  expected error unknown: %s\n", err.how.c_str());

    const plan::Proposal p = plan::propose(config, atlas, *tolerance, rates, opt);
    std::printf("\nProposal for a tolerance of %g\n", *tolerance);
    for (const auto& line : p.reasoning) std::printf("  %s\n", line.c_str());
    std::printf("\nProposed setup: %dD %s%s, m = %.4g, spacing %.4g m%s\n", p.dimension, p.model.c_str(),
                p.dimension == 2 ? (p.planar == solver::Planar::PlaneStrain ? " plane strain" : " plane stress") : "",
                p.horizon_factor, p.spacing_m,
                p.from_atlas ? (p.tolerance_met ? ", meets the tolerance by the atlas" : ", does NOT meet the tolerance")
                             : ", error unknown (no atlas rows)");
    print_cost(p.cost);
    if (!write_path.empty()) {
      plan::write_proposed_case(config, p, write_path);
      std::printf("\nwrote %s (parsed back with breccia-solve's case loader)\n", write_path.c_str());
    }
    return 0;
  } catch (const InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return kExitBadInput;
  } catch (const std::exception& e) {  // a message and exit 3, not an abort
    std::fprintf(stderr, "error: %s\n", breccia::cli::failure_message(e).c_str());
    return kExitRunFailed;
  }
}
