#include "mpi/ranks.h"

#include "core/fixed_point.h"

#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <stdexcept>

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

// ---- the collectives made of meetings

std::vector<std::uint64_t> Ranks::reduce(const std::string& op, const std::vector<std::uint64_t>& values) {
  const std::vector<Bytes> all = meet(op, bytes_of(values));
  std::vector<std::uint64_t> out = records_of<std::uint64_t>(all[0]);
  for (int q = 0; q < size(); ++q) {
    const std::vector<std::uint64_t> v = records_of<std::uint64_t>(all[std::size_t(q)]);
    if (v.size() != values.size())
      throw std::logic_error(op + ": rank " + std::to_string(q) + " gave " + std::to_string(v.size()) +
                             " values, rank " + std::to_string(rank()) + " " + std::to_string(values.size()));
    for (std::size_t i = 0; q > 0 && i < v.size(); ++i)
      out[i] = op == "max" ? std::max(out[i], v[i]) : op == "reduce_sum" ? add_sums(out[i], v[i]) : out[i] + v[i];
  }
  return out;
}

void Ranks::barrier() { meet("barrier", Bytes()); }

std::uint64_t Ranks::sum(std::uint64_t value) { return reduce("sum", {value})[0]; }

// As MPI's: nothing to add up, no meeting.
void Ranks::max(std::vector<std::uint64_t>& values) {
  if (!values.empty()) values = reduce("max", values);
}

void Ranks::sum(std::vector<std::uint64_t>& values) {
  if (!values.empty()) values = reduce("sum", values);
}

std::vector<std::uint64_t> Ranks::all_to_all(const Bytes& send, const std::vector<std::uint64_t>& send_counts,
                                             std::size_t record_bytes, Bytes& recv) {
  const std::size_t R = std::size_t(size());
  std::uint64_t total = 0;
  for (std::size_t d = 0; d < R; ++d) total += send_counts.at(d);
  if (send.size() < total * record_bytes) throw std::logic_error("all_to_all: fewer bytes than the counts say");
  // Each rank's message: the record size, its counts, then its records.
  std::vector<std::uint64_t> head = {record_bytes};
  head.insert(head.end(), send_counts.begin(), send_counts.begin() + std::ptrdiff_t(R));
  Bytes mine = bytes_of(head);
  mine.insert(mine.end(), send.begin(), send.begin() + std::ptrdiff_t(total * record_bytes));
  const std::vector<Bytes> all = meet("all_to_all", std::move(mine));
  std::vector<std::uint64_t> recv_counts(R, 0);
  recv.clear();
  const std::size_t head_bytes = (R + 1) * sizeof(std::uint64_t);
  for (std::size_t q = 0; q < R; ++q) {
    const Bytes& m = all[q];
    const Bytes head_of = Bytes(m.begin(), m.begin() + std::ptrdiff_t(head_bytes));
    const std::vector<std::uint64_t> h = records_of<std::uint64_t>(head_of);
    if (h[0] != record_bytes) throw std::logic_error("all_to_all: the ranks' record sizes differ");
    std::uint64_t before = 0;
    for (std::size_t d = 0; d < std::size_t(rank()); ++d) before += h[1 + d];
    recv_counts[q] = h[1 + std::size_t(rank())];
    const auto first = m.begin() + std::ptrdiff_t(head_bytes + before * record_bytes);
    recv.insert(recv.end(), first, first + std::ptrdiff_t(recv_counts[q] * record_bytes));
  }
  return recv_counts;
}

void Ranks::reduce_sum(std::vector<std::uint64_t>& values, int root) {
  const std::vector<std::uint64_t> total = reduce("reduce_sum", values);
  if (rank() == root) values = total;
}

void Ranks::broadcast(void* data, std::size_t bytes, int root) {
  const auto* p = static_cast<const unsigned char*>(data);
  const std::vector<Bytes> all = meet("broadcast", rank() == root ? Bytes(p, p + bytes) : Bytes());
  const Bytes& from = all.at(std::size_t(root));
  if (from.size() != bytes) throw std::logic_error("broadcast: the ranks' sizes differ");
  if (rank() != root && bytes > 0) std::memcpy(data, from.data(), bytes);
}

std::vector<std::string> Ranks::gather(const std::string& mine, int root) {
  const std::vector<Bytes> all = meet("gather", Bytes(mine.begin(), mine.end()));
  std::vector<std::string> out;
  if (rank() == root)
    for (const Bytes& b : all) out.emplace_back(b.begin(), b.end());
  return out;
}

Ranks::Bytes Ranks::all_gather(const Bytes& mine) {
  Bytes out;
  for (const Bytes& b : meet("all_gather", mine)) out.insert(out.end(), b.begin(), b.end());
  return out;
}

int Ranks::agree(int& code) {
  Bytes mine(sizeof code);
  std::memcpy(mine.data(), &code, sizeof code);
  const std::vector<Bytes> all = meet("agree", std::move(mine));
  for (std::size_t q = 0; q < all.size(); ++q) {
    int theirs = 0;
    std::memcpy(&theirs, all[q].data(), sizeof theirs);
    if (theirs != 0) {
      code = theirs;
      return static_cast<int>(q);
    }
  }
  return -1;
}

// ---- one process

OneProcess::OneProcess() {
  char name[256] = {};
  if (::gethostname(name, sizeof name - 1) == 0) host_ = name;
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
