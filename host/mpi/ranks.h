// The processes of one run. Under `mpirun -np R` each MPI rank is one
// process driving one OpenCL device and one contiguous group of PEs; the
// ranks exchange descriptors between rounds. This is the one home of every
// MPI call: a build without MPI (or a run not started by an MPI launcher)
// gets the single-process implementation, and the renderer never sees MPI.
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
  // A Ranks never started is one process (rank 0 of 1): what a caller that
  // names no ranks gets. Only the program's entry (app/main.cpp) reads the
  // world's; every other room is handed its Ranks.
  Ranks() = default;
  Ranks(const Ranks&) = delete;
  Ranks& operator=(const Ranks&) = delete;
  // The run's process group: one process until start() joins an MPI job.
  static Ranks& world();

  // Joins the MPI job when this process was started by an MPI launcher
  // (mpirun, mpiexec, srun); otherwise stays a single process, exactly as a
  // build without MPI. Safe to call more than once. Registers finish() at exit.
  void start();
  void finish();  // MPI_Finalize when started

  bool built_with_mpi() const;
  int rank() const { return rank_; }
  int size() const { return size_; }
  int local_rank() const { return local_rank_; }  // among the ranks on this machine
  int local_size() const { return local_size_; }
  std::string host() const { return host_; }
  // "rank 2: " in runs of several ranks, "" otherwise: prefixes messages.
  std::string label() const;

  // Collectives (every rank calls them in the same order). Times spent in
  // them add up in mpi_seconds().
  void barrier();
  std::uint64_t sum(std::uint64_t value);        // over all ranks, result on all
  void max(std::vector<std::uint64_t>& values);  // element-wise over all ranks, in place, on all
  void sum(std::vector<std::uint64_t>& values);  // element-wise over all ranks, in place, on all
  // send[d] records of `record_bytes` bytes for rank d (laid out in rank
  // order); returns the counts received from each rank and fills `recv`
  // (also in rank order, then in the order each source sent them).
  std::vector<std::uint64_t> all_to_all(const std::vector<unsigned char>& send,
                                        const std::vector<std::uint64_t>& send_counts, std::size_t record_bytes,
                                        std::vector<unsigned char>& recv);
  void reduce_sum(std::vector<std::uint64_t>& values, int root);  // in place; valid on root
  void broadcast(void* data, std::size_t bytes, int root);
  std::vector<std::string> gather(const std::string& mine, int root);  // all ranks' strings on root
  // Every rank's bytes, concatenated in rank order, on every rank.
  std::vector<unsigned char> all_gather(const std::vector<unsigned char>& mine);

  // Point to point (the item-buffer pipeline). send() does not wait; the
  // data must stay untouched until wait_sends().
  void send(const void* data, std::size_t bytes, int to, int tag);
  void receive(void* data, std::size_t bytes, int from, int tag);
  void wait_sends();

  // Failure agreement at a point every rank reaches: each passes its exit
  // code (0 = fine). Returns the lowest failing rank (-1 when none) and sets
  // `code` to that rank's code on every rank.
  int agree(int& code);
  // Ends every rank (MPI_Abort) after a failure seen by this rank, while
  // the others may wait in a collective. Several ranks may fail at once
  // (every rank's device faults in one round): they settle which one calls
  // `report` (prints the one error line) without any collective, and the
  // others end silently with it. Never returns.
  [[noreturn]] void abort(int code, const std::function<void()>& report);

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

  double mpi_seconds() const { return mpi_seconds_; }

 private:
  bool started_ = false, finished_ = false, collective_ = false;
  int rank_ = 0, size_ = 1, local_rank_ = 0, local_size_ = 1;
  std::string host_;
  double mpi_seconds_ = 0;
  std::vector<void*> pending_;  // MPI_Request handles of send()
  friend struct RanksTimer;
};

// True when an MPI launcher started this process (its environment says so).
bool launched_by_mpi();

}  // namespace opsila
