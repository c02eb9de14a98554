// breccia-plan: what a PD case will cost and what error to expect, before running it, and
// the cheapest setup that meets a tolerance (docs/plan.md).
//   breccia-plan CASE.yaml --tolerance X [--write PROPOSED.yaml] [--atlas atlas.csv]
//                [--throughputs throughputs.yaml] [--calibrate] [--threads N]
// Example: breccia-plan cases/kalthoff-winkler/case.yaml --tolerance 0.05 --calibrate
#include <omp.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include "breccia/common/error.hpp"
#include "breccia/plan/plan.hpp"
#include "breccia/solver/case_config.hpp"

namespace {

void usage() {
  std::fprintf(stderr,
               "usage: breccia-plan CASE.yaml --tolerance X [--write PROPOSED.yaml] [--atlas atlas.csv]\n"
               "                    [--throughputs throughputs.yaml] [--calibrate] [--threads N]\n"
               "  X: the relative error you accept (0.02 = 2%%), as the atlas measures it\n");
}

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
  for (int k = 1; k < argc; ++k) {
    const std::string a = argv[k];
    auto value = [&](const char* name) -> std::string {
      if (k + 1 >= argc) {
        std::fprintf(stderr, "error: %s needs a value\n", name);
        std::exit(kExitBadInput);
      }
      return argv[++k];
    };
    try {
      if (a == "--tolerance") tolerance = std::stod(value("--tolerance"));
      else if (a == "--write") write_path = value("--write");
      else if (a == "--atlas") atlas_path = value("--atlas");
      else if (a == "--throughputs") rates_path = value("--throughputs");
      else if (a == "--calibrate") calibrate = true;
      else if (a == "--threads") opt.threads = std::stoi(value("--threads"));
      else if (a == "-h" || a == "--help") { usage(); return 0; }
      else if (!a.empty() && a[0] == '-') {
        std::fprintf(stderr, "error: unknown option %s\n", a.c_str());
        usage();
        return kExitBadInput;
      } else case_file = a;
    } catch (const std::exception&) {
      std::fprintf(stderr, "error: option %s: '%s' is not a number\n", a.c_str(), argv[k]);
      return kExitBadInput;
    }
  }
  if (case_file.empty()) {
    std::fprintf(stderr, "error: no case file given\n");
    usage();
    return kExitBadInput;
  }
  if (!tolerance) {
    std::fprintf(stderr, "error: --tolerance: missing (expected a relative error > 0, e.g. --tolerance 0.02)\n");
    return kExitBadInput;
  }
  if (!(*tolerance > 0) || !std::isfinite(*tolerance)) {
    std::fprintf(stderr, "error: --tolerance: %g (expected a relative error > 0, e.g. 0.02)\n", *tolerance);
    return kExitBadInput;
  }
  if (opt.threads < 1) {
    std::fprintf(stderr, "error: --threads: %d (expected 1 or more)\n", opt.threads);
    return kExitBadInput;
  }
  try {
    if (!std::filesystem::exists(case_file))
      throw InputError(case_file, "", "no such case file", "a case YAML (docs/case-format.md)");
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
    if (std::filesystem::exists(atlas_path)) {
      atlas = plan::read_atlas(atlas_path);
      atlas_note = std::to_string(atlas.size()) + " rows from " + atlas_path;
    } else {
      atlas_note = "no atlas at " + atlas_path + " (run `make atlas`, or pass --atlas FILE)";
    }

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
  }
}
