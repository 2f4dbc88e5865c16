#include "mpi/ranks.h"

#include <cstdlib>

namespace opsila {

bool launched_by_mpi() {
  // Open MPI, MPICH/Hydra and PMIx launchers, and Slurm's srun with PMI.
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK", "PMI_RANK", "MPI_LOCALNRANKS"})
    if (std::getenv(name)) return true;
  return false;
}

std::string Ranks::label() const { return size() > 1 ? "rank " + std::to_string(rank()) + ": " : std::string(); }

void Ranks::checkpoint() {
  if (size() == 1) return;
  int code = 0;
  const int failed = agree(code);
  if (failed >= 0) throw OtherRankFailed(failed, code);
}

void Ranks::begin_collective() {
  checkpoint();
  collective_ = size() > 1;
}

}  // namespace opsila
