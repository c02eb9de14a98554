// breccia-atlas: speed against accuracy of the PD solver on problems with known answers,
// and the measured stability map (docs/atlas.md; `make atlas`).
//
//   breccia-atlas [--quick] [--csv docs/atlas/atlas.csv] [--stability-csv docs/atlas/stability.csv]
//                 [--problems wave_speed_bar,strain_energy,fracture_energy,quasi_static_bar,kalthoff_winkler,
//                             softening_strength,mps_wave_speed,thick_cylinder,thick_cylinder_hill]
//                 [--models pmb,lps] [--kinds lattice,tet] [--m 2,3,4,5] [--backends cpu,cuda] [--no-stability]
//                 [--only-stability]
//                 [--stability-studies pd,graded,mps] [--gradings 1.5,2,3] [--append] [--threads N] [--work DIR]
//                 [--mesh-exe PATH] [--place-exe PATH]
//
// Each run appends one row to the CSV (rewritten atomically after every row). Tet-centroid
// particles come from breccia-mesh + breccia-place (found next to this executable unless
// given). The precision and backend columns say how each row ran; --backends cuda runs the
// time-stepping problems (wave speed bar, Kalthoff-Winkler) on the GPU too. The command line
// is CLI11's with the tools' conventions (common/cli.hpp).
#include <omp.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "atlas.hpp"
#include "breccia/common/cli.hpp"
#include "breccia/common/error.hpp"
#ifdef BRECCIA_WITH_CUDA
#include "breccia/solver/cuda_backend.hpp"
#endif

namespace {

constexpr const char* kAbout =
    "breccia-atlas: speed against accuracy of the PD (and MPS) solvers on problems with known answers,\n"
    "and the measured stability maps, as CSV tables (docs/atlas.md; `make atlas`).";
constexpr const char* kFooter =
    "Problems: wave_speed_bar strain_energy fracture_energy quasi_static_bar kalthoff_winkler\n"
    "          softening_strength mps_wave_speed thick_cylinder thick_cylinder_hill (MPS stress solid).\n"
    "Output: one row per run appended to the CSV (rewritten atomically after every row); the stability\n"
    "studies write the stability CSV and stability_graded.csv, stability_mps.csv beside it. Tet-centroid\n"
    "particles come from breccia-mesh + breccia-place, found next to this executable unless given.\n"
    "Lists are comma-separated (--models pmb,lps).";

// Another table in the folder of the stability CSV.
std::string sibling_csv(const std::string& csv, const std::string& name) {
  return (std::filesystem::path(csv).parent_path() / name).string();
}

}  // namespace

int main(int argc, char** argv) {
  using namespace breccia::atlas;
  return breccia::cli::run_reporting_errors([&]() -> int {
    SweepPlan plan;
    const std::vector<std::string> all_problems = {"wave_speed_bar",   "strain_energy",    "fracture_energy",
                                                   "quasi_static_bar", "kalthoff_winkler", "softening_strength",
                                                   "mps_wave_speed",   "thick_cylinder",   "thick_cylinder_hill"};
    plan.problems = all_problems;
    plan.models = {"pmb", "lps"};
    plan.kinds = {"lattice", "tet"};
    std::string csv = "docs/atlas/atlas.csv", stability_csv = "docs/atlas/stability.csv";
    bool stability = true, sweeps = true, append = false;
    std::vector<std::string> stability_studies;  // empty: all
    auto has_study = [&](const char* name) {
      for (const auto& q : stability_studies) if (q == name) return true;
      return false;
    };
    int threads = 0;
    const std::filesystem::path bin = std::filesystem::absolute(argv[0]).parent_path();
    SpecimenMaker maker{"runs/atlas", (bin / "breccia-mesh").string(), (bin / "breccia-place").string()};
    CLI::App app{kAbout, "breccia-atlas"};
    breccia::cli::configure(app, kFooter);
    // A comma-separated list, one per occurrence (CLI11 would otherwise take the following
    // arguments too).
    const auto list = [&](const std::string& name, auto& into, const std::string& what) {
      return app.add_option(name, into, what)->delimiter(',')->allow_extra_args(false);
    };
    app.add_flag("--quick", plan.quick, "fewer spacings and steps: about 2 minutes for every study instead of 8");
    app.add_option("--csv", csv, "the sweep table")->type_name("FILE")->capture_default_str();
    app.add_option("--stability-csv", stability_csv, "the stability table")->type_name("FILE")->capture_default_str();
    using breccia::cli::one_of;
    list("--problems", plan.problems, "problems to run (default: all)")->type_name("a,b")->check(one_of(all_problems));
    list("--models", plan.models, "pmb, lps, correspondence (default: pmb,lps)")
        ->type_name("a,b")
        ->check(one_of({"pmb", "lps", "correspondence"}));
    list("--kinds", plan.kinds, "particle kinds: lattice, tet (default: both)")
        ->type_name("a,b")
        ->check(one_of({"lattice", "tet"}));
    list("--precisions", plan.precisions, "float64, float32 (default: float64)")
        ->type_name("a,b")
        ->check(one_of({"float64", "float32"}));
    list("--backends", plan.backends, "cpu, cuda (default: cpu; cuda: wave_speed_bar and kalthoff_winkler on the GPU)")
        ->type_name("a,b")
        ->check(one_of({"cpu", "cuda"}));
    list("--m", plan.m_values, "horizon factors (default: 2,3,4,5)")
        ->type_name("2,3,...")
        ->check(breccia::cli::real_number(0.0, false));
    list("--stability-studies", stability_studies, "pd, graded, mps (default: all)")
        ->type_name("a,b")
        ->check(one_of({"pd", "graded", "mps"}));
    list("--gradings", plan.gradings, "grading ratios of the graded study (default 1,1.5,2,3,4,6; --quick 2,4)")
        ->type_name("1.5,2,...")
        ->check(breccia::cli::real_number(1.0, true));
    app.add_flag_callback(
        "--no-stability", [&] { stability = false; }, "skip the stability studies");
    app.add_flag_callback(
        "--only-stability", [&] { sweeps = false; }, "only the stability studies");
    app.add_flag("--append", append, "append to the CSVs instead of starting them anew");
    app.add_option("--threads", threads, "OpenMP threads (default: all cores)")
        ->type_name("N")
        ->check(breccia::cli::whole_number(1));
    app.add_option("--work", maker.work_dir, "folder for meshes and particle files")
        ->type_name("DIR")
        ->capture_default_str();
    app.add_option("--mesh-exe", maker.mesh_exe, "breccia-mesh to run")->type_name("PATH");
    app.add_option("--place-exe", maker.place_exe, "breccia-place to run")->type_name("PATH");
    if (const auto code = breccia::cli::parse(app, argc, argv)) return *code;
    for (const auto& b : plan.backends) {
      if (b != "cuda") continue;
#ifdef BRECCIA_WITH_CUDA
      if (!breccia::solver::cuda_device_available())
        throw breccia::InputError("command line", "--backends", "cuda, but no CUDA device is available on this machine",
                                  "cpu, or a machine with an NVIDIA GPU and driver");
      plan.cuda_backend = breccia::solver::make_cuda_step_backend;
#else
      throw breccia::InputError("command line", "--backends", "cuda, but this build has no CUDA backend",
                                "cpu, or a build with CUDA=ON");
#endif
    }
    if (threads > 0) omp_set_num_threads(threads);
    plan.threads = omp_get_max_threads();
    maker.work_dir = std::filesystem::absolute(maker.work_dir).string();
    breccia::cli::require_writable_folder("--work", maker.work_dir);
    const auto t0 = std::chrono::steady_clock::now();
    if (sweeps) {
      CsvTable table(csv, kAtlasHeader, append);
      const RowSink sink = [&](const AtlasRow& r) {
        table.add(csv_line(r));
        std::fprintf(stderr, "[atlas] %-17s %s %-7s m=%g dx=%.3g mm  N=%zu  %.2f s  error %.3e%s\n", r.problem.c_str(),
                     r.model.c_str(), r.particles_kind.c_str(), r.m, r.spacing_m * 1e3, r.particles, r.wall_s,
                     r.error, r.backend == "cpu" ? "" : ("  (" + r.backend + ")").c_str());
      };
      auto has = [&](const char* p) {
        for (const auto& q : plan.problems) if (q == p) return true;
        return false;
      };
      if (has("wave_speed_bar")) wave_speed_bar(plan, maker, sink);
      static_calibration(plan, maker, sink);
      if (has("quasi_static_bar")) quasi_static_bar(plan, maker, sink);
      if (has("kalthoff_winkler")) kalthoff_winkler(plan, maker, sink);
      if (has("softening_strength")) softening_strength(plan, maker, sink);
      mps_problems(plan, sink);  // the MPS stress solid (mps_atlas.cpp)
      table.commit();
    }
    if (stability) {
      if (stability_studies.empty() || has_study("pd")) {
        CsvTable table(stability_csv, kStabilityHeader, append);
        stability_map(plan, maker, table, sibling_csv(stability_csv, "stability_correspondence_series.csv"));
        table.commit();
      }
      if (stability_studies.empty() || has_study("graded")) {
        CsvTable graded(sibling_csv(stability_csv, "stability_graded.csv"), kGradedHeader, append);
        graded_stability(plan, maker, graded);
        graded.commit();
      }
      if (stability_studies.empty() || has_study("mps")) {
        CsvTable mps(sibling_csv(stability_csv, "stability_mps.csv"), kMpsStabilityHeader, append);
        mps_tension_stability(plan, mps);
        mps.commit();
      }
    }
    std::fprintf(stderr, "[atlas] done in %.0f s\n", seconds_since(t0));
    return 0;
  });
}
