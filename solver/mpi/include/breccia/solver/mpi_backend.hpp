#pragma once
// Distributed runs (docs/parallel.md): `mpirun -np P breccia-solve CASE.yaml`. Each rank
// steps its own share of the particles (rank_system.hpp) with the step of step.hpp, through
// an execution space that adds the halo exchanges; the time loop (run.hpp) is the one every
// backend uses; with serial HDF5 rank 0 gathers the state when a file is written, with
// parallel HDF5 every rank writes its rows and rank 0 gathers no whole array.
#include <mpi.h>

#include <memory>
#include <string>

#include "breccia/solver/run.hpp"

namespace breccia::solver {

// MPI_Init_thread on construction when an MPI launcher started this process (mpirun, srun:
// mpi_launch.hpp), MPI_Finalize on destruction. Otherwise MPI is not initialised, so
// `breccia-solve` run directly behaves as a build without MPI.
class MpiSession {
public:
  MpiSession(int& argc, char**& argv);
  ~MpiSession();
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;
  bool active() const { return active_; }
  int rank() const { return rank_; }
  int size() const { return size_; }
  // Ranks other than 0 write nothing to stderr (one message per run, not one per rank)
  // until fatal() needs to say why this rank stops the others.
  void quiet_other_ranks();
  // A failure on this rank alone: its message (with the rank), then every rank stops.
  [[noreturn]] void fatal(const std::string& message, int exit_code);

private:
  bool active_ = false;
  int rank_ = 0, size_ = 1;
};

// Prints `message` (naming the rank when there are several) on this rank's real stderr and
// stops every rank with `exit_code` (MPI_Abort); without MPI initialised, exits.
[[noreturn]] void mpi_abort_all(const std::string& message, int exit_code);
// True on every rank when `ok` is true on all of them (a collective check point).
bool mpi_all_agree(bool ok);

// The time loop's backend for rank `rank` of `comm`: builds the rank's system from the
// (replicated) global one and keeps it between steps; measure() sums over ranks,
// download() gathers the owned ranges into the global system on rank 0 (serial HDF5 only).
// Throws InputError for a case it cannot distribute (naming the key). `cuda`: each rank steps
// on a GPU (the node-local rank's, modulo the node's GPUs), the halo packed on the device and
// carried through pinned host buffers, or device buffers with a CUDA-aware MPI.
std::unique_ptr<StepBackend> make_mpi_backend(PdSystem& global, MPI_Comm comm, bool cuda = false);

// Whether the MPI library loaded takes device memory in its messages (OpenMPI:
// MPIX_Query_cuda_support, asked at run time where mpi-ext.h declares it; false otherwise,
// and with BRECCIA_MPI_CUDA_AWARE=0 in the environment).
bool mpi_cuda_aware();

// SetupHooks::stable_step_forces for a distributed run: the set-up's stable-step estimate
// with its force passes shared between the ranks (the step comes out as one process's).
ForcePass mpi_stable_step_forces(PdSystem& global);
// SetupHooks::stable_step_ranks for a distributed run: the rank's share of the estimate's
// vectors over the system mpi_stable_step_forces built (StableStepRanks: its owned
// particles, their sums chained over the ranks in rank order). Empty on one process.
StableStepRanks mpi_stable_step_ranks();

// The distributed set-up's collective (pd_system.hpp, DistributedSetup) over MPI_COMM_WORLD.
DistributedSetup mpi_distributed_setup();

// RunOptions::relax for a distributed run: dynamic relaxation on every rank's share, the
// history line (rank 0's `history`, null elsewhere; the probes' values from their owners) and
// the output group written (with parallel HDF5 by every rank together: each its rows, nothing
// gathered; else by rank 0's `results`, null elsewhere, from the state gathered into `global`);
// returns the iterations (-1: not converged) and the final energies summed over ranks.
std::pair<long long, Energies> mpi_relax(PdSystem& global, const RunOptions& options, ResultsWriter* results,
                                         HistoryWriter* history);

// RunOptions::backend_loop for a distributed run (options.backend "cuda": on the ranks' GPUs).
RunResult mpi_time_loop(PdSystem& global, const RunOptions& options, ResultsWriter* results,
                        HistoryWriter* history);

}  // namespace breccia::solver
