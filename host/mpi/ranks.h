// The processes of one run. Under `mpirun -np R` each MPI rank is one
// process driving one OpenCL device and one contiguous group of PEs; the
// ranks exchange descriptors between rounds. Ranks is the transport as the
// collective code sees it; MpiRanks (mpi/mpi_ranks.h) is the one home of
// every MPI call: a build without MPI (or a run not started by an MPI
// launcher) gets one process, and the renderer never sees MPI. The tests
// run the collective code on simulated ranks (threads of one process).
// Every collective is made of one meeting (each rank's bytes to every rank)
// unless the transport has its own: MPI has; one process and the simulated
// ranks give only the meeting and the messages.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <functional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace opsila {

// Another rank failed during set-up and said so (it prints the message);
// this rank stops with the same exit code, silently.
struct OtherRankFailed : std::runtime_error {
  int rank, code;
  OtherRankFailed(int r, int c) : std::runtime_error("rank " + std::to_string(r) + " failed"), rank(r), code(c) {}
};

// Records sent between ranks as bytes (trivially copyable types).
template <typename T>
std::vector<unsigned char> bytes_of(const std::vector<T>& v) {
  std::vector<unsigned char> b(v.size() * sizeof(T));
  if (!v.empty()) std::memcpy(b.data(), v.data(), b.size());
  return b;
}

template <typename T>
std::vector<T> records_of(const std::vector<unsigned char>& b) {
  std::vector<T> v(b.size() / sizeof(T));
  if (!v.empty()) std::memcpy(v.data(), b.data(), v.size() * sizeof(T));
  return v;
}

class Ranks {
 public:
  using Bytes = std::vector<unsigned char>;
  virtual ~Ranks() = default;
  // The run's process group: the MPI transport (MpiRanks), one process
  // until start() joins an MPI job.
  static Ranks& world();

  // Joins the group when the transport needs it (MPI: when an MPI launcher
  // started this process; otherwise it stays one process). Safe to call
  // more than once.
  virtual void start() {}

  virtual bool built_with_mpi() const { return false; }
  // Where this process stands, as the transport placed it.
  int rank() const { return rank_; }
  int size() const { return size_; }
  int local_rank() const { return local_rank_; }  // among the ranks on this machine
  int local_size() const { return local_size_; }
  const std::string& host() const { return host_; }
  // "rank 2: " in runs of several ranks, "" otherwise: prefixes messages.
  std::string label() const;

  // Collectives (every rank calls them in the same order). Times spent in
  // them add up in mpi_seconds(). Each is made of meet() (below) unless the
  // transport has its own (MPI's).
  virtual void barrier();
  virtual std::uint64_t sum(std::uint64_t value);        // over all ranks, result on all
  virtual void max(std::vector<std::uint64_t>& values);  // element-wise over all ranks, in place, on all
  virtual void sum(std::vector<std::uint64_t>& values);  // element-wise over all ranks, in place, on all
  // send[d] records of `record_bytes` bytes for rank d (laid out in rank
  // order); returns the counts received from each rank and fills `recv`
  // (also in rank order, then in the order each source sent them).
  virtual std::vector<std::uint64_t> all_to_all(const Bytes& send, const std::vector<std::uint64_t>& send_counts,
                                                std::size_t record_bytes, Bytes& recv);
  // Element-wise sums of pixel sums and counters (core/fixed_point.h,
  // add_sums: a sum that reached 2^63 stays marked), in place; valid on root.
  virtual void reduce_sum(std::vector<std::uint64_t>& values, int root);
  virtual void broadcast(void* data, std::size_t bytes, int root);
  virtual std::vector<std::string> gather(const std::string& mine, int root);  // all ranks' strings on root
  // Every rank's bytes, concatenated in rank order, on every rank.
  virtual Bytes all_gather(const Bytes& mine);

  // Point to point (the item-buffer pipeline), in order between two ranks
  // for one tag. send() does not wait; the data must stay untouched until
  // wait_sends().
  virtual void send(const void* data, std::size_t bytes, int to, int tag) = 0;
  virtual void receive(void* data, std::size_t bytes, int from, int tag) = 0;
  virtual void wait_sends() = 0;

  // Failure agreement at a point every rank reaches: each passes its exit
  // code (0 = fine). Returns the lowest failing rank (-1 when none) and sets
  // `code` to that rank's code on every rank.
  virtual int agree(int& code);
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

  double mpi_seconds() const { return mpi_seconds_; }

 protected:
  // The one collective every transport has: each rank brings `mine` and
  // gets every rank's bytes, in rank order. `op` names the collective it
  // serves (a transport may check that every rank called the same).
  virtual std::vector<Bytes> meet(const std::string& op, Bytes mine) = 0;

  // Set by the transport: this process's place, and the time it spent
  // waiting on the others.
  int rank_ = 0, size_ = 1, local_rank_ = 0, local_size_ = 1;
  std::string host_;
  double mpi_seconds_ = 0;

 private:
  // Every rank's values, element-wise by `op` ("sum" wraps modulo 2^64 as
  // MPI's does).
  std::vector<std::uint64_t> reduce(const std::string& op, const std::vector<std::uint64_t>& values);

  bool collective_ = false;
};

// One process alone (rank 0 of 1): what a caller that names no ranks gets,
// and a library user's. Only the program's entry (app/main.cpp) reads the
// world's Ranks; every other room is handed its Ranks.
class OneProcess final : public Ranks {
 public:
  OneProcess();
  void send(const void*, std::size_t, int, int) override;
  void receive(void*, std::size_t, int, int) override;
  void wait_sends() override {}
  [[noreturn]] void abort(int code, const std::function<void()>& report) override;

 protected:
  std::vector<Bytes> meet(const std::string&, Bytes mine) override { return {std::move(mine)}; }
};

// True when an MPI launcher started this process (its environment says so).
bool launched_by_mpi();

}  // namespace opsila
