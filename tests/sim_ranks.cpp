#include "sim_ranks.h"

#include <cstring>
#include <exception>
#include <thread>

#include "core/util.h"

namespace opsila::test {

SimGroup::SimGroup(int size, std::chrono::milliseconds timeout)
    : size_(size), timeout_(timeout), slots_(std::size_t(size)), ops_(std::size_t(size)), gone_(std::size_t(size), 0) {
  if (size < 1) throw std::invalid_argument("simulated ranks: at least one");
}

void SimGroup::fail_locked(const std::string& why) {
  if (broken_.empty()) broken_ = why;
  changed_.notify_all();
}

void SimGroup::fail(const std::string& why) {
  std::lock_guard<std::mutex> hold(mutex_);
  fail_locked(why);
}

void SimGroup::left(int rank) {
  std::lock_guard<std::mutex> hold(mutex_);
  gone_[std::size_t(rank)] = 1;
  changed_.notify_all();
}

bool SimGroup::first_report() {
  std::lock_guard<std::mutex> hold(mutex_);
  const bool first = !reported_;
  reported_ = true;
  return first;
}

template <class Done>
void SimGroup::wait(std::unique_lock<std::mutex>& lock, int rank, int on, const std::string& what, const Done& done) {
  const auto deadline = std::chrono::steady_clock::now() + timeout_;
  for (;;) {
    if (done()) return;
    if (!broken_.empty()) throw SimRanksBroken(broken_);
    if (const std::string why = stuck_on(rank, on); !why.empty()) {
      fail_locked(why + " while rank " + std::to_string(rank) + " waits in " + what);
      throw SimRanksBroken(broken_);
    }
    if (changed_.wait_until(lock, deadline) == std::cv_status::timeout && !done()) {
      fail_locked("rank " + std::to_string(rank) + " waited " + std::to_string(timeout_.count()) + " ms in " + what +
                  ": the ranks deadlocked");
      throw SimRanksBroken(broken_);
    }
  }
}

// A rank that returned can neither come to a meeting nor send: whoever
// waits on it (`on`, or any rank: -1) waits forever.
std::string SimGroup::stuck_on(int rank, int on) const {
  for (int q = 0; q < size_; ++q)
    if (q != rank && (on < 0 || q == on) && gone_[std::size_t(q)]) return "rank " + std::to_string(q) + " returned";
  return std::string();
}

std::shared_ptr<const std::vector<Bytes>> SimGroup::meet(int rank, const std::string& op, Bytes mine) {
  std::unique_lock<std::mutex> lock(mutex_);
  if (!broken_.empty()) throw SimRanksBroken(broken_);
  slots_[std::size_t(rank)] = std::move(mine);
  ops_[std::size_t(rank)] = op;
  const std::uint64_t meeting = meeting_;
  if (++arrived_ == size_) {
    for (int q = 1; q < size_; ++q)
      if (ops_[std::size_t(q)] != ops_[0]) {
        fail_locked("rank " + std::to_string(q) + " called " + ops_[std::size_t(q)] + " while rank 0 called " +
                    ops_[0]);
        throw SimRanksBroken(broken_);
      }
    last_ = std::make_shared<const std::vector<Bytes>>(std::move(slots_));
    slots_.assign(std::size_t(size_), Bytes());
    arrived_ = 0;
    ++meeting_;
    changed_.notify_all();
    return last_;
  }
  // The next meeting cannot end before this rank comes to it: last_ is this one's.
  wait(lock, rank, -1, op, [&] { return meeting_ != meeting; });
  return last_;
}

void SimGroup::post(int from, int to, int tag, Bytes message) {
  std::lock_guard<std::mutex> hold(mutex_);
  mail_[{from, to, tag}].push_back(std::move(message));
  changed_.notify_all();
}

Bytes SimGroup::take(int from, int to, int tag) {
  std::unique_lock<std::mutex> lock(mutex_);
  std::deque<Bytes>& box = mail_[{from, to, tag}];
  const std::string what = "receive from rank " + std::to_string(from) + " (tag " + std::to_string(tag) + ")";
  wait(lock, to, from, what, [&] { return !box.empty(); });
  Bytes message = std::move(box.front());
  box.pop_front();
  return message;
}

SimRanks::SimRanks(SimGroup& group, int rank) : group_(group) {
  rank_ = local_rank_ = rank;  // every rank on this machine
  size_ = local_size_ = group.size();
  host_ = "simulated";
}

// The time spent waiting on the other ranks adds up in mpi_seconds().
std::vector<Bytes> SimRanks::meet(const std::string& op, Bytes mine) {
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<Bytes> all = *group_.meet(rank_, op, std::move(mine));
  mpi_seconds_ += seconds_since(t0);
  return all;
}

void SimRanks::send(const void* data, std::size_t bytes, int to, int tag) {
  if (to < 0 || to >= size() || to == rank_) throw std::logic_error("send: no rank " + std::to_string(to));
  const auto* p = static_cast<const unsigned char*>(data);
  group_.post(rank_, to, tag, Bytes(p, p + bytes));
}

void SimRanks::receive(void* data, std::size_t bytes, int from, int tag) {
  if (from < 0 || from >= size() || from == rank_) throw std::logic_error("receive: no rank " + std::to_string(from));
  const auto t0 = std::chrono::steady_clock::now();
  const Bytes message = group_.take(from, rank_, tag);
  mpi_seconds_ += seconds_since(t0);
  if (message.size() > bytes)  // MPI_ERR_TRUNCATE
    throw std::logic_error("receive: " + std::to_string(message.size()) + " bytes into a buffer of " +
                           std::to_string(bytes));
  if (!message.empty()) std::memcpy(data, message.data(), message.size());
}

void SimRanks::abort(int code, const std::function<void()>& report) {
  // The first rank to fail reports; the others end silently with it.
  if (group_.first_report()) report();
  group_.fail("rank " + std::to_string(rank_) + " aborted, exit code " + std::to_string(code));
  throw SimRanksAborted(rank_, code);
}

void run_ranks(int size, const std::function<void(Ranks&)>& body, std::chrono::milliseconds timeout) {
  SimGroup group(size, timeout);
  std::vector<std::exception_ptr> errors(static_cast<std::size_t>(size));
  std::vector<char> own(static_cast<std::size_t>(size), 0);  // its own failure, not the broken group's
  std::vector<std::thread> threads;
  for (int r = 0; r < size; ++r)
    threads.emplace_back([&, r] {
      SimRanks ranks(group, r);
      try {
        body(ranks);
      } catch (const SimRanksBroken&) {
        errors[std::size_t(r)] = std::current_exception();
      } catch (const std::exception& e) {
        errors[std::size_t(r)] = std::current_exception();
        own[std::size_t(r)] = 1;
        group.fail("rank " + std::to_string(r) + " failed: " + e.what());
      } catch (...) {
        errors[std::size_t(r)] = std::current_exception();
        own[std::size_t(r)] = 1;
        group.fail("rank " + std::to_string(r) + " failed");
      }
      group.left(r);
    });
  for (std::thread& t : threads) t.join();
  for (int pass = 0; pass < 2; ++pass)
    for (std::size_t r = 0; r < errors.size(); ++r)
      if (errors[r] && (pass == 1 || own[r])) std::rethrow_exception(errors[r]);
}

}  // namespace opsila::test
