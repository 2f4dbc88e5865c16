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
  int rank() const override { return rank_; }
  int size() const override { return size_; }
  int local_rank() const override { return local_rank_; }
  int local_size() const override { return local_size_; }
  std::string host() const override { return host_; }

  void barrier() override;
  std::uint64_t sum(std::uint64_t value) override;
  void max(std::vector<std::uint64_t>& values) override;
  void sum(std::vector<std::uint64_t>& values) override;
  std::vector<std::uint64_t> all_to_all(const std::vector<unsigned char>& send,
                                        const std::vector<std::uint64_t>& send_counts, std::size_t record_bytes,
                                        std::vector<unsigned char>& recv) override;
  void reduce_sum(std::vector<std::uint64_t>& values, int root) override;
  void broadcast(void* data, std::size_t bytes, int root) override;
  std::vector<std::string> gather(const std::string& mine, int root) override;
  std::vector<unsigned char> all_gather(const std::vector<unsigned char>& mine) override;

  void send(const void* data, std::size_t bytes, int to, int tag) override;
  void receive(void* data, std::size_t bytes, int from, int tag) override;
  void wait_sends() override;

  int agree(int& code) override;
  [[noreturn]] void abort(int code, const std::function<void()>& report) override;

  double mpi_seconds() const override { return mpi_seconds_; }

 private:
  MpiRanks();
  friend Ranks& Ranks::world();
  bool reports_the_failure();
  void tell_others(int tag);

  bool started_ = false, finished_ = false;
  int rank_ = 0, size_ = 1, local_rank_ = 0, local_size_ = 1;
  std::string host_;
  double mpi_seconds_ = 0;
  std::vector<void*> pending_;  // MPI_Request handles of send()
  // abort's own communicator (made by start), and what it sends: the tag
  // and the source say it all, the buffer outlives the sends.
  struct Failures;
  std::unique_ptr<Failures> failures_;
};

}  // namespace opsila
