#include "mpi/ranks.h"

#include <unistd.h>

#include <stdexcept>

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

std::string OneProcess::host() const {
  char name[256] = {};
  return ::gethostname(name, sizeof name - 1) == 0 ? std::string(name) : std::string();
}

std::vector<std::uint64_t> OneProcess::all_to_all(const std::vector<unsigned char>& send,
                                                  const std::vector<std::uint64_t>& send_counts, std::size_t,
                                                  std::vector<unsigned char>& recv) {
  recv = send;  // every record is for this rank
  return {send_counts.empty() ? 0 : send_counts[0]};
}

void OneProcess::send(const void*, std::size_t, int, int) {
  throw std::logic_error("OneProcess::send: one process has no other rank");
}

void OneProcess::receive(void*, std::size_t, int, int) {
  throw std::logic_error("OneProcess::receive: one process has no other rank");
}

void OneProcess::abort(int code, const std::function<void()>& report) {
  report();
  std::_Exit(code);
}

}  // namespace opsila
