#include "mpi/mpi_ranks.h"

#include <unistd.h>

#include <chrono>
#include <climits>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

#ifdef OPSILA_HAVE_MPI
#include <mpi.h>

#include "core/fixed_point.h"
#include "core/last_words.h"
#endif

namespace opsila {

Ranks& Ranks::world() {
  static MpiRanks ranks;
  return ranks;
}

bool MpiRanks::built_with_mpi() const {
#ifdef OPSILA_HAVE_MPI
  return true;
#else
  return false;
#endif
}

#ifdef OPSILA_HAVE_MPI

struct MpiRanks::Failures {
  MPI_Comm comm = MPI_COMM_NULL;
  int token = 0;
};

namespace {

// Adds the time a call spends in MPI to mpi_seconds().
struct Timed {
  double& total;
  std::chrono::steady_clock::time_point t0 = std::chrono::steady_clock::now();
  explicit Timed(double& seconds) : total(seconds) {}
  ~Timed() { total += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); }
};

void finish_at_exit() { static_cast<MpiRanks&>(Ranks::world()).finish(); }

int checked_int(std::uint64_t n, const char* what) {
  if (n > std::uint64_t(INT_MAX))
    throw std::runtime_error(std::string(what) + ": " + std::to_string(n) + " items exceed one MPI message");
  return static_cast<int>(n);
}

}  // namespace

void MpiRanks::start() {
  char name[256] = {};
  if (gethostname(name, sizeof name - 1) == 0) host_ = name;
  if (started_ || !launched_by_mpi()) return;
  int already = 0;
  MPI_Initialized(&already);
  if (!already) MPI_Init(nullptr, nullptr);
  started_ = true;
  std::atexit(finish_at_exit);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
  set_last_words_rank(rank_, size_);
  // Ranks sharing this machine (MPI-3): the local rank picks the node's GPU.
  MPI_Comm local;
  MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, rank_, MPI_INFO_NULL, &local);
  MPI_Comm_rank(local, &local_rank_);
  MPI_Comm_size(local, &local_size_);
  MPI_Comm_free(&local);
  failures_ = std::make_unique<Failures>();
  MPI_Comm_dup(MPI_COMM_WORLD, &failures_->comm);
}

void MpiRanks::finish() {
  if (!started_ || finished_) return;
  finished_ = true;
  wait_sends();
  MPI_Finalize();
}

void MpiRanks::barrier() {
  if (size_ == 1) return;
  Timed t(mpi_seconds_);
  MPI_Barrier(MPI_COMM_WORLD);
}

std::uint64_t MpiRanks::sum(std::uint64_t value) {
  if (size_ == 1) return value;
  Timed t(mpi_seconds_);
  std::uint64_t total = 0;
  MPI_Allreduce(&value, &total, 1, MPI_UINT64_T, MPI_SUM, MPI_COMM_WORLD);
  return total;
}

void MpiRanks::max(std::vector<std::uint64_t>& values) {
  if (size_ == 1 || values.empty()) return;
  Timed t(mpi_seconds_);
  MPI_Allreduce(MPI_IN_PLACE, values.data(), checked_int(values.size(), "values"), MPI_UINT64_T, MPI_MAX,
                MPI_COMM_WORLD);
}

void MpiRanks::sum(std::vector<std::uint64_t>& values) {
  if (size_ == 1 || values.empty()) return;
  Timed t(mpi_seconds_);
  MPI_Allreduce(MPI_IN_PLACE, values.data(), checked_int(values.size(), "values"), MPI_UINT64_T, MPI_SUM,
                MPI_COMM_WORLD);
}

std::vector<std::uint64_t> MpiRanks::all_to_all(const Bytes& send, const std::vector<std::uint64_t>& send_counts,
                                                std::size_t record_bytes, Bytes& recv) {
  std::vector<std::uint64_t> recv_counts(size_, 0);
  if (size_ == 1) {
    recv = send;
    recv_counts[0] = send_counts[0];
    return recv_counts;
  }
  Timed t(mpi_seconds_);
  MPI_Alltoall(send_counts.data(), 1, MPI_UINT64_T, recv_counts.data(), 1, MPI_UINT64_T, MPI_COMM_WORLD);
  std::vector<int> sc(size_), sd(size_), rc(size_), rd(size_);
  std::uint64_t s_at = 0, r_at = 0;
  for (int q = 0; q < size_; ++q) {
    sc[q] = checked_int(send_counts[q], "descriptors sent");
    rc[q] = checked_int(recv_counts[q], "descriptors received");
    sd[q] = checked_int(s_at, "descriptors sent");
    rd[q] = checked_int(r_at, "descriptors received");
    s_at += send_counts[q];
    r_at += recv_counts[q];
  }
  recv.resize(r_at * record_bytes);
  MPI_Datatype record;
  MPI_Type_contiguous(checked_int(record_bytes, "record size"), MPI_BYTE, &record);
  MPI_Type_commit(&record);
  MPI_Alltoallv(send.data(), sc.data(), sd.data(), record, recv.data(), rc.data(), rd.data(), record,
                MPI_COMM_WORLD);
  MPI_Type_free(&record);
  return recv_counts;
}

namespace {

// MPI's side of add_sums: MPI_SUM would wrap a marked (saturated) sum.
void add_sums_op(void* in, void* inout, int* len, MPI_Datatype*) {
  const auto* a = static_cast<const std::uint64_t*>(in);
  auto* b = static_cast<std::uint64_t*>(inout);
  for (int i = 0; i < *len; ++i) b[i] = add_sums(a[i], b[i]);
}

}  // namespace

void MpiRanks::reduce_sum(std::vector<std::uint64_t>& values, int root) {
  if (size_ == 1) return;
  Timed t(mpi_seconds_);
  static const MPI_Op op = [] {
    MPI_Op made;
    MPI_Op_create(&add_sums_op, 1, &made);  // commutative, as the device's atomics
    return made;
  }();
  const std::size_t step = std::size_t(INT_MAX) / 8;
  for (std::size_t at = 0; at < values.size(); at += step) {
    const int n = static_cast<int>(std::min(step, values.size() - at));
    if (rank_ == root)
      MPI_Reduce(MPI_IN_PLACE, values.data() + at, n, MPI_UINT64_T, op, root, MPI_COMM_WORLD);
    else
      MPI_Reduce(values.data() + at, nullptr, n, MPI_UINT64_T, op, root, MPI_COMM_WORLD);
  }
}

void MpiRanks::broadcast(void* data, std::size_t bytes, int root) {
  if (size_ == 1) return;
  Timed t(mpi_seconds_);
  auto* p = static_cast<unsigned char*>(data);
  for (std::size_t at = 0; at < bytes; at += INT_MAX / 2)
    MPI_Bcast(p + at, static_cast<int>(std::min<std::size_t>(INT_MAX / 2, bytes - at)), MPI_BYTE, root,
              MPI_COMM_WORLD);
}

// Every rank's bytes, whatever their sizes: their sizes first, then the bytes.
std::vector<Ranks::Bytes> MpiRanks::meet(const std::string&, Bytes mine) {
  if (size_ == 1) return {std::move(mine)};
  Timed t(mpi_seconds_);
  int n = checked_int(mine.size(), "gathered bytes");
  std::vector<int> sizes(size_), at(size_);
  MPI_Allgather(&n, 1, MPI_INT, sizes.data(), 1, MPI_INT, MPI_COMM_WORLD);
  std::uint64_t total = 0;
  for (int q = 0; q < size_; ++q) at[q] = checked_int(total, "gathered bytes"), total += sizes[q];
  Bytes all(total);
  MPI_Allgatherv(mine.data(), n, MPI_BYTE, all.data(), sizes.data(), at.data(), MPI_BYTE, MPI_COMM_WORLD);
  std::vector<Bytes> each;
  for (int q = 0; q < size_; ++q) each.emplace_back(all.begin() + at[q], all.begin() + at[q] + sizes[q]);
  return each;
}

void MpiRanks::send(const void* data, std::size_t bytes, int to, int tag) {
  Timed t(mpi_seconds_);
  auto* request = new MPI_Request;
  MPI_Isend(data, checked_int(bytes, "message bytes"), MPI_BYTE, to, tag, MPI_COMM_WORLD, request);
  pending_.push_back(request);
}

void MpiRanks::receive(void* data, std::size_t bytes, int from, int tag) {
  Timed t(mpi_seconds_);
  MPI_Recv(data, checked_int(bytes, "message bytes"), MPI_BYTE, from, tag, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
}

void MpiRanks::wait_sends() {
  if (pending_.empty()) return;
  Timed t(mpi_seconds_);
  for (void* p : pending_) {
    auto* request = static_cast<MPI_Request*>(p);
    MPI_Wait(request, MPI_STATUS_IGNORE);
    delete request;
  }
  pending_.clear();
}

int MpiRanks::agree(int& code) {
  if (size_ == 1) return code != 0 ? 0 : -1;
  Timed t(mpi_seconds_);
  const int mine = code != 0 ? rank_ : size_;
  int first = size_;
  MPI_Allreduce(&mine, &first, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  if (first == size_) return -1;
  MPI_Bcast(&code, 1, MPI_INT, first, MPI_COMM_WORLD);
  return first;
}

// The failures of the collective part are told on a communicator of their
// own (no collective can match them): a failing rank tells every other
// that it failed, then listens for kReportGrace seconds. It stays silent
// when a lower rank failed too or another already reports; else it says it
// reports, and does. A message takes far less than half the grace, so of
// ranks failing at once only one reports, and the lowest failing rank is
// silent only when another reports.
namespace {
constexpr int kFailedTag = 1, kReportsTag = 2;
constexpr double kReportGrace = 1.0;
constexpr double kSilentWait = 30.0;  // then a silent rank ends the job itself
}  // namespace

void MpiRanks::tell_others(int tag) {
  for (int q = 0; q < size_; ++q) {
    if (q == rank_) continue;
    MPI_Request request;
    MPI_Isend(&failures_->token, 1, MPI_INT, q, tag, failures_->comm, &request);
    MPI_Request_free(&request);
  }
}

bool MpiRanks::reports_the_failure() {
  tell_others(kFailedTag);
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(kReportGrace);
  while (std::chrono::steady_clock::now() < end) {
    int arrived = 0;
    MPI_Status status;
    MPI_Iprobe(MPI_ANY_SOURCE, MPI_ANY_TAG, failures_->comm, &arrived, &status);
    if (!arrived) {
      usleep(1000);
      continue;
    }
    int token = 0;
    MPI_Recv(&token, 1, MPI_INT, status.MPI_SOURCE, status.MPI_TAG, failures_->comm, MPI_STATUS_IGNORE);
    if (status.MPI_TAG == kReportsTag || status.MPI_SOURCE < rank_) return false;
  }
  tell_others(kReportsTag);
  return true;
}

void MpiRanks::abort(int code, const std::function<void()>& report) {
  if (!started_ || size_ == 1 || !failures_ || failures_->comm == MPI_COMM_NULL) {
    report();
    if (started_) MPI_Abort(MPI_COMM_WORLD, code);
    std::_Exit(code);
  }
  if (reports_the_failure()) {
    report();
  } else {
    usleep(useconds_t(kSilentWait * 1e6));  // the reporting rank ends the job before
  }
  MPI_Abort(MPI_COMM_WORLD, code);
  std::_Exit(code);
}

#else  // no MPI: one process

struct MpiRanks::Failures {};

void MpiRanks::start() {}
void MpiRanks::finish() {}
void MpiRanks::barrier() {}
std::uint64_t MpiRanks::sum(std::uint64_t value) { return value; }
void MpiRanks::max(std::vector<std::uint64_t>&) {}
void MpiRanks::sum(std::vector<std::uint64_t>&) {}
std::vector<std::uint64_t> MpiRanks::all_to_all(const Bytes& send, const std::vector<std::uint64_t>& send_counts,
                                                std::size_t, Bytes& recv) {
  recv = send;
  return {send_counts.at(0)};
}
void MpiRanks::reduce_sum(std::vector<std::uint64_t>&, int) {}
void MpiRanks::broadcast(void*, std::size_t, int) {}
std::vector<Ranks::Bytes> MpiRanks::meet(const std::string&, Bytes mine) { return {std::move(mine)}; }
void MpiRanks::send(const void*, std::size_t, int, int) { throw std::logic_error("Ranks::send without MPI"); }
void MpiRanks::receive(void*, std::size_t, int, int) { throw std::logic_error("Ranks::receive without MPI"); }
void MpiRanks::wait_sends() {}
int MpiRanks::agree(int& code) { return code != 0 ? 0 : -1; }
void MpiRanks::abort(int code, const std::function<void()>& report) {
  report();
  std::_Exit(code);
}

#endif

MpiRanks::MpiRanks() = default;
MpiRanks::~MpiRanks() = default;  // here, where Failures is complete

}  // namespace opsila
