// Simulated ranks: R ranks of one process as R threads sharing memory, a
// Ranks transport (mpi/ranks.h) for the tests of the collective code
// without a launcher. The semantics are MPI's as MpiRanks uses them: every
// collective is a meeting of every rank (each gets the others' data once
// all have come, in rank order), point-to-point messages between two
// ranks arrive in the order sent for one tag. The meetings also check what
// MPI leaves undefined: every rank in the same collective, vectors of the
// same length. A rank that waits longer than the timeout, a rank that
// returns while others wait for it, and a rank that throws, all end every
// rank's wait: the test fails, it never hangs.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "mpi/ranks.h"

namespace opsila::test {

// Thrown by every rank still waiting when the simulated ranks cannot go
// on; the message says why (a timeout, a rank that left, mismatched
// collectives, a failure elsewhere).
struct SimRanksBroken : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Thrown by Ranks::abort on the rank that called it: the run ended there.
struct SimRanksAborted : std::runtime_error {
  int rank, code;
  SimRanksAborted(int r, int c)
      : std::runtime_error("rank " + std::to_string(r) + " aborted, exit code " + std::to_string(c)),
        rank(r),
        code(c) {}
};

// Long enough for any test's collective work under the sanitizers; a
// deadlock is usually seen at once (a rank that left).
constexpr std::chrono::milliseconds kSimTimeout{60000};

using Bytes = Ranks::Bytes;

// What the ranks share: the meeting place of the collectives and the
// mailboxes of the point-to-point messages.
class SimGroup {
 public:
  SimGroup(int size, std::chrono::milliseconds timeout);
  int size() const { return size_; }
  // Every rank's bytes, in rank order, once every rank has met here in the
  // collective `op`.
  std::shared_ptr<const std::vector<Bytes>> meet(int rank, const std::string& op, Bytes mine);
  void post(int from, int to, int tag, Bytes message);
  Bytes take(int from, int to, int tag);
  // Ends every wait: the waiting ranks throw SimRanksBroken(why). The first
  // reason given is kept.
  void fail(const std::string& why);
  void left(int rank);  // its work is done: a rank waiting for it is stuck
  // Whether the caller is the first to report a failure (abort()).
  bool first_report();

 private:
  template <class Done>
  void wait(std::unique_lock<std::mutex>& lock, int rank, int on, const std::string& what, const Done& done);
  void fail_locked(const std::string& why);
  std::string stuck_on(int rank, int on) const;

  const int size_;
  const std::chrono::milliseconds timeout_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::string broken_;  // why the ranks cannot go on; empty while they can
  // The meeting being filled: each rank's bytes and collective, how many came.
  std::vector<Bytes> slots_;
  std::vector<std::string> ops_;
  int arrived_ = 0;
  std::uint64_t meeting_ = 0;                       // meetings completed
  std::shared_ptr<const std::vector<Bytes>> last_;  // the last completed one's data
  std::map<std::tuple<int, int, int>, std::deque<Bytes>> mail_;  // (from, to, tag): in the order posted
  std::vector<char> gone_;
  bool reported_ = false;
};

// One rank: the collectives are the meetings Ranks makes them of.
class SimRanks final : public Ranks {
 public:
  SimRanks(SimGroup& group, int rank);
  // Sends are copied at once: wait_sends() has nothing to wait for.
  void send(const void* data, std::size_t bytes, int to, int tag) override;
  void receive(void* data, std::size_t bytes, int from, int tag) override;
  void wait_sends() override {}
  [[noreturn]] void abort(int code, const std::function<void()>& report) override;

 protected:
  std::vector<Bytes> meet(const std::string& op, Bytes mine) override;

 private:
  SimGroup& group_;
};

// Runs body(ranks) on `size` simulated ranks, each on a thread of its own,
// and returns once all have returned. When any threw, rethrows after every
// thread ended: the exception that stopped them (a rank's own failure
// before the SimRanksBroken it caused elsewhere; the lowest rank's first).
void run_ranks(int size, const std::function<void(Ranks&)>& body, std::chrono::milliseconds timeout = kSimTimeout);

}  // namespace opsila::test
