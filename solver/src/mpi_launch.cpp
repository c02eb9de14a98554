#include "breccia/solver/mpi_launch.hpp"

#include <cstdlib>
#include <initializer_list>

namespace breccia::solver {
namespace {

// The first of `names` that is set, as a number; `fallback` when none is.
int first_number(std::initializer_list<const char*> names, int fallback) {
  for (const char* name : names)
    if (const char* value = std::getenv(name)) return std::atoi(value);
  return fallback;
}

}  // namespace

MpiLaunch mpi_launch_from_environment() {
  MpiLaunch l;
  // OpenMPI's mpirun sets OMPI_COMM_WORLD_*; PMIx-based and PMI-based launchers (srun,
  // MPICH's hydra) set PMIX_RANK or PMI_RANK / PMI_SIZE.
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE"})
    if (std::getenv(name)) l.by_launcher = true;
  l.size = first_number({"OMPI_COMM_WORLD_SIZE", "PMI_SIZE"}, 1);
  l.rank = first_number({"OMPI_COMM_WORLD_RANK", "PMIX_RANK", "PMI_RANK"}, 0);
  return l;
}

}  // namespace breccia::solver
