// The processes of one run. Under `mpirun -np R` each MPI rank is one
// process driving one OpenCL device and one contiguous group of PEs; the
// ranks exchange descriptors between rounds. Ranks is the transport as the
// collective code sees it; MpiRanks (mpi/mpi_ranks.h) is the one home of
// every MPI call: a build without MPI (or a run not started by an MPI
// launcher) gets one process, and the renderer never sees MPI. The tests
// run the collective code on simulated ranks (threads of one process).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace opsila {

// Another rank failed during set-up and said so (it prints the message);
// this rank stops with the same exit code, silently.
struct OtherRankFailed : std::runtime_error {
  int rank, code;
  OtherRankFailed(int r, int c) : std::runtime_error("rank " + std::to_string(r) + " failed"), rank(r), code(c) {}
};

class Ranks {
 public:
  virtual ~Ranks() = default;
  // The run's process group: the MPI transport (MpiRanks), one process
  // until start() joins an MPI job.
  static Ranks& world();

  // Joins the group when the transport needs it (MPI: when an MPI launcher
  // started this process; otherwise it stays one process). Safe to call
  // more than once.
  virtual void start() = 0;

  virtual bool built_with_mpi() const = 0;
  virtual int rank() const = 0;
  virtual int size() const = 0;
  virtual int local_rank() const = 0;  // among the ranks on this machine
  virtual int local_size() const = 0;
  virtual std::string host() const = 0;
  // "rank 2: " in runs of several ranks, "" otherwise: prefixes messages.
  std::string label() const;

  // Collectives (every rank calls them in the same order). Times spent in
  // them add up in mpi_seconds().
  virtual void barrier() = 0;
  virtual std::uint64_t sum(std::uint64_t value) = 0;        // over all ranks, result on all
  virtual void max(std::vector<std::uint64_t>& values) = 0;  // element-wise over all ranks, in place, on all
  virtual void sum(std::vector<std::uint64_t>& values) = 0;  // element-wise over all ranks, in place, on all
  // send[d] records of `record_bytes` bytes for rank d (laid out in rank
  // order); returns the counts received from each rank and fills `recv`
  // (also in rank order, then in the order each source sent them).
  virtual std::vector<std::uint64_t> all_to_all(const std::vector<unsigned char>& send,
                                                const std::vector<std::uint64_t>& send_counts,
                                                std::size_t record_bytes, std::vector<unsigned char>& recv) = 0;
  virtual void reduce_sum(std::vector<std::uint64_t>& values, int root) = 0;  // in place; valid on root
  virtual void broadcast(void* data, std::size_t bytes, int root) = 0;
  virtual std::vector<std::string> gather(const std::string& mine, int root) = 0;  // all ranks' strings on root
  // Every rank's bytes, concatenated in rank order, on every rank.
  virtual std::vector<unsigned char> all_gather(const std::vector<unsigned char>& mine) = 0;

  // Point to point (the item-buffer pipeline), in order between two ranks
  // for one tag. send() does not wait; the data must stay untouched until
  // wait_sends().
  virtual void send(const void* data, std::size_t bytes, int to, int tag) = 0;
  virtual void receive(void* data, std::size_t bytes, int from, int tag) = 0;
  virtual void wait_sends() = 0;

  // Failure agreement at a point every rank reaches: each passes its exit
  // code (0 = fine). Returns the lowest failing rank (-1 when none) and sets
  // `code` to that rank's code on every rank.
  virtual int agree(int& code) = 0;
  // Ends every rank after a failure seen by this rank, while the others
  // may wait in a collective. Several ranks may fail at once (every rank's
  // device faults in one round): they settle which one calls `report`
  // (prints the one error line) without any collective, and the others end
  // silently with it. Never returns.
  [[noreturn]] virtual void abort(int code, const std::function<void()>& report) = 0;

  // Phases of a run. Before begin_collective() each rank works alone
  // (reading, partitioning, uploading): a rank that fails there joins the
  // agreement (agree) from its error handler, and every rank stops cleanly.
  // Between begin_collective() and end_collective() ranks wait on each
  // other, so a failure ends the job (abort).
  void begin_collective();  // throws OtherRankFailed
  // A point every rank reaches outside the collective part (the end of a
  // command): throws OtherRankFailed when another rank failed before it.
  void checkpoint();
  void end_collective() { collective_ = false; }
  bool in_collective() const { return collective_; }

  virtual double mpi_seconds() const = 0;

 private:
  bool collective_ = false;
};

// One process alone (rank 0 of 1): what a caller that names no ranks gets,
// and a library user's. Only the program's entry (app/main.cpp) reads the
// world's Ranks; every other room is handed its Ranks.
class OneProcess final : public Ranks {
 public:
  void start() override {}
  bool built_with_mpi() const override { return false; }
  int rank() const override { return 0; }
  int size() const override { return 1; }
  int local_rank() const override { return 0; }
  int local_size() const override { return 1; }
  std::string host() const override;
  void barrier() override {}
  std::uint64_t sum(std::uint64_t value) override { return value; }
  void max(std::vector<std::uint64_t>&) override {}
  void sum(std::vector<std::uint64_t>&) override {}
  std::vector<std::uint64_t> all_to_all(const std::vector<unsigned char>& send,
                                        const std::vector<std::uint64_t>& send_counts, std::size_t record_bytes,
                                        std::vector<unsigned char>& recv) override;
  void reduce_sum(std::vector<std::uint64_t>&, int) override {}
  void broadcast(void*, std::size_t, int) override {}
  std::vector<std::string> gather(const std::string& mine, int) override { return {mine}; }
  std::vector<unsigned char> all_gather(const std::vector<unsigned char>& mine) override { return mine; }
  void send(const void*, std::size_t, int, int) override;
  void receive(void*, std::size_t, int, int) override;
  void wait_sends() override {}
  int agree(int& code) override { return code != 0 ? 0 : -1; }
  [[noreturn]] void abort(int code, const std::function<void()>& report) override;
  double mpi_seconds() const override { return 0; }
};

// True when an MPI launcher started this process (its environment says so).
bool launched_by_mpi();

}  // namespace opsila
