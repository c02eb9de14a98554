// breccia-solve: run a peridynamics (or MPS) case.
//   breccia-solve CASE.yaml [-o DIR] [--threads N] [--restart FILE] [--steps N] [--backend cpu|cuda|auto]
//                [--kernel-times WARMUP] [--quiet]
//   breccia-solve CASE.yaml --decomposition 2,4,...   (set up, print the domain decomposition's figures, exit)
// The command line is CLI11's with the tools' conventions (common/cli.hpp).
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <algorithm>
#include <climits>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

#include "breccia/common/cli.hpp"
#include "breccia/common/output_file.hpp"
#include "breccia/common/error.hpp"
#include "breccia/common/yaml_input.hpp"
#include "breccia/solver/lattice_model.hpp"
#include "breccia/solver/mpi_launch.hpp"
#include "breccia/solver/partition.hpp"
#include "breccia/solver/rank_system.hpp"
#include "breccia/solver/sell_layout.hpp"
#include "breccia/solver/run.hpp"
#ifdef BRECCIA_WITH_MPS
#include "breccia/mps/run_case.hpp"
#endif
#ifdef BRECCIA_WITH_CUDA
#include "breccia/solver/cuda_backend.hpp"
#include "breccia/solver/cuda_families.hpp"
#endif
#ifdef BRECCIA_WITH_MPI
#include "breccia/solver/mpi_backend.hpp"
#endif
#ifdef BRECCIA_WITH_MPS_CUDA
#include "breccia/mps/cuda_simulation.hpp"
#include "breccia/mps/cuda_solid.hpp"
#endif

namespace {

constexpr const char* kAbout =
    "breccia-solve: run a peridynamics (PMB, LPS, correspondence) or MPS case: particles from the case's\n"
    "specimen, loads and boundaries over time, fracture; results in a folder.";
constexpr const char* kFooter =
    "Input: CASE.yaml (docs/case-format.md). Output in DIR: results.h5 (+ .xdmf), history.csv,\n"
    "summary.json and checkpoint.h5 (docs/formats.md); progress on stderr unless --quiet.\n"
    "  --variant NAME                                     apply the case file's variants.NAME overrides\n"
    "                                                     (before any --set)\n"
    "  --set time.end=\"100 us\" --set 'loads[0].history.peak=4 MPa'   a variant of the case, the file\n"
    "                                                     untouched: KEY as error messages name fields,\n"
    "                                                     VALUE as YAML\n"
    "  breccia-solve CASE.yaml --decomposition P1,P2,...   the domain decomposition's figures per rank\n"
    "                                                     count (CSV on stdout), without running\n"
    "  mpirun -np P breccia-solve CASE.yaml ...            a distributed run (docs/parallel.md)\n"
    "Exit codes: 0 done, 2 bad input or usage, 3 the run failed (unstable, not converged), 130 interrupted\n"
    "(Ctrl-C: a checkpoint is written).";

bool gpu_available() {
#ifdef BRECCIA_WITH_CUDA
  return breccia::solver::cuda_device_available();
#else
  return false;
#endif
}

}  // namespace

int main(int argc, char** argv) {
  using namespace breccia;
#ifdef BRECCIA_WITH_MPI
  // Under mpirun (and only then) MPI is initialised; ranks other than 0 stay silent, so a
  // message appears once, and a failure on one rank stops all (MpiSession::fatal).
  solver::MpiSession mpi(argc, argv);
  mpi.quiet_other_ranks();
  const int ranks = mpi.size(), rank = mpi.rank();
#else
  const int ranks = 1, rank = 0;
  // Started by mpirun with several processes, a build without MPI would run the case that
  // many times into the same folder: refuse (once, from the first process).
  if (const solver::MpiLaunch launch = solver::mpi_launch_from_environment(); launch.size > 1) {
    if (launch.rank == 0)
      std::fprintf(stderr, "error: started by mpirun with %d processes, but this breccia-solve was built without MPI "
                           "(-DBRECCIA_MPI=OFF or no MPI found); rebuild with OpenMPI (make deps) or run one process\n",
                   launch.size);
    return kExitBadInput;
  }
#endif
  const bool distributed = ranks > 1;
  std::string case_file;
  solver::RunOptions opt;
  std::string backend = "auto";
  std::string decomposition;  // rank counts: print the decomposition's figures instead of running
  std::vector<std::string> overrides;  // --set KEY=VALUE
  std::string variant;                 // --variant NAME
  CLI::App app{kAbout, "breccia-solve"};
  cli::configure(app, kFooter);
  app.add_option("CASE", case_file, "the case file")->required()->type_name("CASE.yaml");
  app.add_option("-o,--output", opt.out_dir, "the folder for the results (default: out)")->type_name("DIR");
  app.add_option("--threads", opt.threads, "OpenMP threads (default: OpenMP's, all cores)")
      ->type_name("N")
      ->check(cli::whole_number(1));
  app.add_option("--restart", opt.restart_file, "continue from this checkpoint")->type_name("FILE");
  app.add_option_function<long long>(
         "--steps", [&](long long n) { opt.steps = n; }, "override the number of steps")
      ->type_name("N")
      ->check(cli::whole_number(0, LLONG_MAX));
  app.add_option_function<long long>(
         "--kernel-times", [&](long long n) { opt.kernel_times_warmup = n; },
         "time every GPU kernel with CUDA events after WARMUP steps (summary.json kernel_times)")
      ->type_name("WARMUP")
      ->check(cli::whole_number(0, LLONG_MAX));
  app.add_option("--backend", backend, "where the time loop runs (default: auto, the GPU when there is one)")
      ->type_name("cpu|cuda|auto")
      ->check(cli::one_of({"cpu", "cuda", "auto"}));
  app.add_flag_callback(
      "--quiet", [&] { opt.progress = false; }, "no progress or notes on stderr");
  app.add_option("--set", overrides, "override a value of the case file (repeatable; below)")
      ->type_name("KEY=VALUE")
      ->allow_extra_args(false);
  app.add_option("--variant", variant, "apply the case file's variants.NAME overrides (before any --set)")
      ->type_name("NAME");
  app.add_option("--decomposition", decomposition, "print the domain decomposition's figures per rank count and exit")
      ->type_name("P1,P2,...");
  // Every rank parses; only rank 0 speaks, and all leave with the same code.
  if (const auto code = cli::parse(app, argc, argv, rank == 0)) return *code;
  if (backend == "cuda" && !gpu_available()) {
    std::fprintf(stderr, "error: --backend cuda: no CUDA device is available on this machine"
#ifndef BRECCIA_WITH_CUDA
                         " (this build has no CUDA backend)"
#endif
                         "; use --backend cpu or auto\n");
    return kExitBadInput;
  }
  // Under mpirun a rank takes its GPU only when asked (--backend cuda): auto stays on the CPU.
  if (distributed && backend == "auto") backend = "cpu";
  opt.backend = (backend == "cuda" || (backend == "auto" && gpu_available())) ? "cuda" : "cpu";
  if (backend == "auto" && opt.progress)
    std::fprintf(stderr, "note: --backend auto: %s\n",
                 opt.backend == "cuda" ? "a CUDA device is present, running on it"
                                       : "no CUDA device found, running on the CPU");
#ifdef BRECCIA_WITH_CUDA
  if (opt.backend == "cuda") opt.backend_loop = solver::cuda_time_loop;
  // The bond families on the GPU too (one process: a distributed run's ranks build theirs on
  // the host); on the host, with a note, if the device path cannot run.
  if (opt.backend == "cuda" && !distributed)
    opt.setup_hooks.families = [notes = opt.progress](std::span<const double> x, std::span<const double> h,
                                                      std::span<const double> pad, int64_t begin, int64_t end) {
      return solver::cuda_build_families(x, h, pad, begin, end, notes);
    };
#endif
  try {
    Section::set_overrides(case_file, overrides, variant, opt.out_dir);
    // The model decides the solver: PD here, MPS in its own library.
    const Section root = Section::load_file(case_file);
    if (root.has("model") && root.section("model").text("type", "") == "mps") {
      if (distributed)
        throw InputError(case_file, "model.type", "mps under mpirun -np " + std::to_string(ranks),
                         "one process (MPS particles move between ranks: not distributed, docs/parallel.md)");
#ifdef BRECCIA_WITH_MPS
      if (opt.kernel_times_warmup && opt.progress)
        std::fprintf(stderr, "note: --kernel-times: the MPS launchers are not timed per kernel yet; nothing is timed\n");
      mps::RunCaseOptions mps_options;
      mps_options.threads = opt.threads;
      mps_options.max_steps = opt.steps.value_or(-1);
      mps_options.quiet = !opt.progress;
      if (opt.backend == "cuda") {
        // Both formulations have a CUDA launcher. A stress case using a feature its launcher
        // does not run is refused under --backend cuda (run_case names the key) and runs on
        // the CPU under auto.
#ifdef BRECCIA_WITH_MPS_CUDA
        mps_options.device = mps::make_cuda_step_device;
        mps_options.solid_device = mps::make_cuda_solid_device;
        mps_options.cpu_when_refused = backend == "auto";
#else
        if (backend == "cuda")
          throw InputError(case_file, "model.type", "mps with --backend cuda",
                           "--backend cpu (this build has no MPS CUDA launcher)");
#endif
      }
      return mps::run_case(case_file, opt.out_dir, mps_options);
#else
      throw InputError(case_file, "model.type", "'mps' but this build has no MPS solver", "pmb or lps");
#endif
    }
    const solver::CaseConfig config = solver::parse_case_file(case_file);
    if (!decomposition.empty()) {
      if (rank != 0) return 0;  // figures, not a run: one process prints them
      // The partition of the distributed runs (partition.hpp) on this case's families: load
      // balance, ghosts and halo bytes per rank count, without launching any process.
      const double bytes_per_ghost = config.model == solver::PdModel::PMB ? 24.0 : 48.0;
      std::vector<int> rank_counts;
      for (size_t at = 0; at <= decomposition.size();) {
        const size_t comma = std::min(decomposition.find(',', at), decomposition.size());
        const std::string item = decomposition.substr(at, comma - at);
        const long long ranks_here = cli::to_whole_number(item).value_or(0);
        if (ranks_here < 1 || ranks_here > (1 << 30))
          throw InputError("--decomposition", "", "'" + item + "'", "comma-separated rank counts >= 1");
        rank_counts.push_back(static_cast<int>(ranks_here));
        at = comma + 1;
      }
      auto print_row = [](int r, const solver::DecompositionStats& st) {
        std::printf("%d,%lld,%lld,%.4f,%.4f,%.4f,%.0f,%.0f,%d\n", r, static_cast<long long>(st.min_owned),
                    static_cast<long long>(st.max_owned), st.max_over_mean_bonds, st.mean_ghost_ratio,
                    st.max_ghost_ratio, st.mean_halo_bytes, st.max_halo_bytes, st.max_neighbour_ranks);
      };
      const char* header = "ranks,owned_min,owned_max,bonds_max_over_mean,ghosts_per_owned_mean,ghosts_per_owned_max,"
                           "halo_bytes_mean,halo_bytes_max,neighbour_ranks_max\n";
      if (config.lattice && config.lattice->dimension == 3 && !config.horizon_m && !config.variable_horizon) {
        // A box lattice: its families are one stencil clipped to the box, so the figures
        // need no set-up (10^8 particles and more; partition.hpp).
        const std::array<int64_t, 3> n = solver::lattice_point_counts(*config.lattice);
        const auto stencil = solver::lattice_family_stencil(config.horizon_factor, config.partial_volume);
        const int64_t total = n[0] * n[1] * n[2];
        const int64_t sample = std::max<int64_t>(1, total / 4000000);
        std::printf("# %s: %lld x %lld x %lld lattice = %lld particles, %zu-point family stencil (partial volumes, m = "
                    "%g), %s; Morton order of the lattice indices; ghosts counted on every %lld-th particle; halo "
                    "bytes at %g B per ghost per step\n",
                    case_file.c_str(), static_cast<long long>(n[0]), static_cast<long long>(n[1]),
                    static_cast<long long>(n[2]), static_cast<long long>(total), stencil.size(),
                    config.horizon_factor, config.model_name.c_str(), static_cast<long long>(sample), bytes_per_ghost);
        std::printf("%s", header);
        const auto stats = solver::lattice_decomposition_stats(n, stencil, rank_counts, bytes_per_ghost, sample);
        for (size_t q = 0; q < stats.size(); ++q) print_row(rank_counts[q], stats[q]);
        return 0;
      }
      solver::PdSystem s = solver::setup_system(config);
      std::printf("# %s: %zu particles, %zu bond entries, %s; halo bytes at %g B per ghost per step\n", case_file.c_str(),
                  s.n, s.bond_count(), config.model_name.c_str(), bytes_per_ghost);
      // The padding of the CUDA backend's SELL-C-sigma layout on these families (docs/cuda.md).
      for (const int sigma : {1, 256, 1024, 4096})
        std::printf("# SELL-C-sigma C = 32, sigma = %d: %.4f padded entries per bond entry\n", sigma,
                    solver::build_sell_layout(s.offsets, 32, sigma).padding_factor());
      std::printf("%s", header);
      for (const int ranks_here : rank_counts) {
        solver::Partition p;
        try {
          p = solver::MortonRangePartitioner().partition(s.offsets, ranks_here);
        } catch (const std::invalid_argument& e) {
          throw InputError(case_file, "--decomposition", e.what(), "at most one rank per particle");
        }
        print_row(ranks_here, solver::decomposition_stats(p, s.offsets, s.neighbor, bytes_per_ghost));
      }
      return 0;
    }
    // The contact search of the short-range forces (contact_cells.hpp) is built on the host;
    // the CUDA backend does not run it yet.
    if (opt.backend == "cuda" && config.short_range_forces) {
      if (backend == "cuda")
        throw InputError(case_file, "model.short_range_forces", "true with --backend cuda",
                         "--backend cpu or auto (the CUDA backend has no contact search yet)");
      if (opt.progress) std::fprintf(stderr, "note: --backend auto: model.short_range_forces runs on the CPU\n");
      opt.backend = "cpu";
      opt.backend_loop = nullptr;
      opt.setup_hooks.families = nullptr;
    }
    if (distributed) {
#ifdef BRECCIA_WITH_MPI
      // One GPU per rank (the rank's system on it, the halo through the host or, with a
      // CUDA-aware MPI, device buffers): what it does not run yet is refused before set-up.
      if (opt.backend == "cuda") solver::check_cuda_ranks_support(config, case_file);
      opt.root = rank == 0;
      opt.ranks = ranks;
      opt.progress = opt.progress && rank == 0;
      opt.backend_loop = solver::mpi_time_loop;
      opt.relax = solver::mpi_relax;
      opt.setup_hooks.stable_step_forces = solver::mpi_stable_step_forces;
      opt.setup_hooks.stable_step_ranks = solver::mpi_stable_step_ranks;
      opt.setup_hooks.distributed = solver::mpi_distributed_setup();
      // Only rank 0 writes: make sure it can before the others set up and wait for it.
      const std::string why = rank == 0 ? breccia::folder_write_problem(opt.out_dir) : std::string();
      if (!solver::mpi_all_agree(why.empty())) cli::unwritable_folder_error("-o", opt.out_dir, why);
#endif
    } else {
      cli::require_writable_folder("-o", opt.out_dir);  // one process: before the set-up, as on ranks
    }
    const solver::RunResult r = solver::run_case(config, opt);
    if (r.status == "unstable" || r.status == "not_converged") {
      std::fprintf(stderr, "error: %s\n", r.message.c_str());
      return kExitRunFailed;
    }
    if (r.status == "interrupted") {
      std::fprintf(stderr, "%s\n", r.message.c_str());
      return 130;
    }
    if (opt.progress)
      std::fprintf(stderr,
                   "done: %lld steps in %.2f s, %.3g bond-updates/s; results in %s (header %.2f s, final checkpoint "
                   "%.2f s)\n",
                   r.steps, r.wall_s, r.bond_updates_per_s, opt.out_dir.c_str(), r.results_header_wall_s,
                   r.final_checkpoint_wall_s);
    return 0;
  } catch (const InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return kExitBadInput;
  } catch (const RunError& e) {
#ifdef BRECCIA_WITH_MPI
    if (distributed) mpi.fatal(e.what(), kExitRunFailed);  // may be this rank's alone
#endif
    std::fprintf(stderr, "error: %s\n", e.what());
    return kExitRunFailed;
  } catch (const std::exception& e) {  // a message and exit 3 (under MPI on every rank), not an abort
    const std::string message = cli::failure_message(e);
#ifdef BRECCIA_WITH_MPI
    if (distributed) mpi.fatal(message, kExitRunFailed);
#endif
    std::fprintf(stderr, "error: %s\n", message.c_str());
    return kExitRunFailed;
  }
}
