#pragma once
// How this process was started: by an MPI launcher (mpirun, srun) or not, read from the
// launcher's environment. No MPI here, so a build without MPI asks the same question
// (breccia-solve refuses to run one case several times into one folder) with the same answer.
namespace breccia::solver {

struct MpiLaunch {
  bool by_launcher = false;  // OMPI_COMM_WORLD_SIZE, PMIX_RANK, PMI_RANK or PMI_SIZE is set
  int size = 1;              // processes started together (1 when the launcher does not say)
  int rank = 0;              // this one's place among them (0 when the launcher does not say)
};

MpiLaunch mpi_launch_from_environment();

}  // namespace breccia::solver
