// breccia-atlas: speed against accuracy of the PD solver on problems with known answers,
// and the measured stability map (docs/atlas.md; `make atlas`).
//
//   breccia-atlas [--quick] [--csv docs/atlas/atlas.csv] [--stability-csv docs/atlas/stability.csv]
//                 [--problems wave_speed_bar,strain_energy,fracture_energy,quasi_static_bar,kalthoff_winkler,
//                             softening_strength,mps_wave_speed,thick_cylinder,thick_cylinder_hill]
//                 [--models pmb,lps] [--kinds lattice,tet] [--m 2,3,4,5] [--backends cpu,cuda] [--no-stability] [--only-stability]
//                 [--stability-studies pd,graded,mps] [--gradings 1.5,2,3] [--append] [--threads N] [--work DIR] [--mesh-exe PATH] [--place-exe PATH]
//
// Each run appends one row to the CSV (rewritten atomically after every row). Tet-centroid
// particles come from breccia-mesh + breccia-place (found next to this executable unless
// given). The precision and backend columns say how each row ran; --backends cuda runs the
// time-stepping problems (wave speed bar, Kalthoff-Winkler) on the GPU too.
#include <omp.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>

#include "atlas.hpp"
#include "breccia/common/error.hpp"
#ifdef BRECCIA_WITH_CUDA
#include "breccia/solver/cuda_backend.hpp"
#endif

namespace {

const char* kUsage =
    "usage: breccia-atlas [--quick] [--csv FILE] [--stability-csv FILE] [--problems a,b] [--models pmb,lps]\n"
    "                     [--kinds lattice,tet] [--m 2,3,4,5] [--no-stability] [--only-stability] [--append]\n"
    "                     [--precisions float64,float32] (default float64)\n"
    "                     [--backends cpu,cuda] (default cpu; cuda: wave_speed_bar and kalthoff_winkler on the GPU)\n"
    "                     [--stability-studies pd,graded,mps] (default: all; stability_graded.csv, stability_mps.csv beside the stability CSV)\n"
    "                     [--gradings 1.5,2,3] (grading ratios of the graded study; default 1,1.5,2,3,4,6, --quick 2,4)\n"
    "                     [--threads N] [--work DIR] [--mesh-exe PATH] [--place-exe PATH]\n"
    "problems: wave_speed_bar strain_energy fracture_energy quasi_static_bar kalthoff_winkler softening_strength\n"
    "          mps_wave_speed thick_cylinder thick_cylinder_hill (MPS stress solid)\n";

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream in(s);
  for (std::string item; std::getline(in, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
}

void require_known(const std::vector<std::string>& given, const std::vector<std::string>& known,
                   const std::string& option) {
  for (const auto& g : given) {
    bool ok = false;
    for (const auto& k : known) ok = ok || g == k;
    if (ok) continue;
    std::string list;
    for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
    throw breccia::InputError("command line", option, "'" + g + "'", "one of " + list);
  }
}

// Another table in the folder of the stability CSV.
std::string sibling_csv(const std::string& csv, const std::string& name) {
  return (std::filesystem::path(csv).parent_path() / name).string();
}

}  // namespace

int main(int argc, char** argv) {
  using namespace breccia::atlas;
  try {
    SweepPlan plan;
    plan.problems = {"wave_speed_bar", "strain_energy", "fracture_energy", "quasi_static_bar", "kalthoff_winkler",
                     "softening_strength", "mps_wave_speed", "thick_cylinder", "thick_cylinder_hill"};
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
    for (int k = 1; k < argc; ++k) {
      const std::string a = argv[k];
      auto value = [&]() -> std::string {
        if (k + 1 >= argc) throw breccia::InputError("command line", a, "no value", "a value after " + a);
        return argv[++k];
      };
      if (a == "--quick") plan.quick = true;
      else if (a == "--csv") csv = value();
      else if (a == "--stability-csv") stability_csv = value();
      else if (a == "--problems") plan.problems = split(value());
      else if (a == "--models") plan.models = split(value());
      else if (a == "--kinds") plan.kinds = split(value());
      else if (a == "--precisions") plan.precisions = split(value());
      else if (a == "--backends") plan.backends = split(value());
      else if (a == "--m") {
        plan.m_values.clear();
        for (const auto& v : split(value())) plan.m_values.push_back(std::stod(v));
      } else if (a == "--gradings") {
        for (const auto& g : split(value())) plan.gradings.push_back(std::stod(g));
      } else if (a == "--stability-studies") stability_studies = split(value());
      else if (a == "--no-stability") stability = false;
      else if (a == "--only-stability") sweeps = false;
      else if (a == "--append") append = true;
      else if (a == "--threads") threads = std::stoi(value());
      else if (a == "--work") maker.work_dir = value();
      else if (a == "--mesh-exe") maker.mesh_exe = value();
      else if (a == "--place-exe") maker.place_exe = value();
      else if (a == "-h" || a == "--help") {
        std::fputs(kUsage, stdout);
        return 0;
      } else {
        throw breccia::InputError("command line", a, "unknown option",
                                  "--quick, --csv, --stability-csv, --problems, --models, --kinds, --precisions, --backends, --m, "
                                  "--stability-studies, --gradings, --no-stability, --only-stability, --append, --threads, --work, --mesh-exe, --place-exe");
      }
    }
    require_known(plan.problems,
                  {"wave_speed_bar", "strain_energy", "fracture_energy", "quasi_static_bar", "kalthoff_winkler",
                   "softening_strength", "mps_wave_speed", "thick_cylinder", "thick_cylinder_hill"},
                  "--problems");
    require_known(plan.models, {"pmb", "lps", "correspondence"}, "--models");
    require_known(stability_studies, {"pd", "graded", "mps"}, "--stability-studies");
    require_known(plan.kinds, {"lattice", "tet"}, "--kinds");
    require_known(plan.precisions, {"float64", "float32"}, "--precisions");
    require_known(plan.backends, {"cpu", "cuda"}, "--backends");
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
    std::filesystem::create_directories(maker.work_dir);
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
    }
    if (stability) {
      if (stability_studies.empty() || has_study("pd")) {
        CsvTable table(stability_csv, kStabilityHeader, append);
        stability_map(plan, maker, table);
      }
      if (stability_studies.empty() || has_study("graded")) {
        CsvTable graded(sibling_csv(stability_csv, "stability_graded.csv"), kGradedHeader, append);
        graded_stability(plan, maker, graded);
      }
      if (stability_studies.empty() || has_study("mps")) {
        CsvTable mps(sibling_csv(stability_csv, "stability_mps.csv"), kMpsStabilityHeader, append);
        mps_tension_stability(plan, mps);
      }
    }
    std::fprintf(stderr, "[atlas] done in %.0f s\n", seconds_since(t0));
    return 0;
  } catch (const breccia::InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return breccia::kExitBadInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return breccia::kExitRunFailed;
  }
}
