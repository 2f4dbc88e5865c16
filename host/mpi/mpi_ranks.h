// The MPI transport: Ranks over MPI_COMM_WORLD, the one home of every MPI
// call. One per process (Ranks::world()): MPI joins a process to one job
// once. Built without MPI, or not started by an MPI launcher, it is one
// process: every collective returns this rank's own values.
#pragma once

#include <memory>

#include "mpi/ranks.h"

namespace opsila {

class MpiRanks final : public Ranks {
 public:
  ~MpiRanks() override;
  // Joins the MPI job when this process was started by an MPI launcher
  // (mpirun, mpiexec, srun); otherwise stays a single process, exactly as a
  // build without MPI. Registers finish() at exit.
  void start() override;
  void finish();  // MPI_Finalize when started

  bool built_with_mpi() const override;

  // MPI's own collectives; gather and all_gather are meetings
  // (MPI_Allgatherv).
  void barrier() override;
  std::uint64_t sum(std::uint64_t value) override;
  void max(std::vector<std::uint64_t>& values) override;
  void sum(std::vector<std::uint64_t>& values) override;
  std::vector<std::uint64_t> all_to_all(const Bytes& send, const std::vector<std::uint64_t>& send_counts,
                                        std::size_t record_bytes, Bytes& recv) override;
  void reduce_sum(std::vector<std::uint64_t>& values, int root) override;
  void broadcast(void* data, std::size_t bytes, int root) override;

  void send(const void* data, std::size_t bytes, int to, int tag) override;
  void receive(void* data, std::size_t bytes, int from, int tag) override;
  void wait_sends() override;

  int agree(int& code) override;
  [[noreturn]] void abort(int code, const std::function<void()>& report) override;

 protected:
  std::vector<Bytes> meet(const std::string& op, Bytes mine) override;

 private:
  MpiRanks();
  friend Ranks& Ranks::world();
  bool reports_the_failure();
  void tell_others(int tag);

  bool started_ = false, finished_ = false;
  std::vector<void*> pending_;  // MPI_Request handles of send()
  // abort's own communicator (made by start), and what it sends: the tag
  // and the source say it all, the buffer outlives the sends.
  struct Failures;
  std::unique_ptr<Failures> failures_;
};

}  // namespace opsila
