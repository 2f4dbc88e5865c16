#include "frame/rank_exchange.h"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <stdexcept>

namespace opsila {

namespace {

double since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

constexpr int kRelayTag = 12;

template <typename T>
void read_range(ClRuntime& rt, const cl::Buffer& b, std::size_t begin, std::vector<T>& v, const char* what) {
  cl_check(rt.queue().enqueueReadBuffer(b, CL_TRUE, begin * sizeof(T), v.size() * sizeof(T), v.data()), what);
}
template <typename T>
void write_range(ClRuntime& rt, const cl::Buffer& b, std::size_t begin, const std::vector<T>& v, const char* what) {
  cl_check(rt.queue().enqueueWriteBuffer(b, CL_TRUE, begin * sizeof(T), v.size() * sizeof(T), v.data()), what);
}

void read_states(ClRuntime& rt, const ItemBuffers& b, std::size_t begin, std::size_t count,
                 std::vector<ItemState>& out) {
  std::vector<cl_int2> items(b.with_items ? count : 0);
  std::vector<cl_int> tri(count);
  std::vector<cl_int2> key(count);
  std::vector<cl_float> t(count);
  if (b.with_items) read_range(rt, *b.items, begin, items, "clEnqueueReadBuffer(item buffer)");
  read_range(rt, *b.tri, begin, tri, "clEnqueueReadBuffer(item buffer hits)");
  read_range(rt, *b.key, begin, key, "clEnqueueReadBuffer(item buffer keys)");
  read_range(rt, *b.t, begin, t, "clEnqueueReadBuffer(item buffer distances)");
  out.resize(count);
  for (std::size_t i = 0; i < count; ++i)
    out[i] = {t[i], tri[i], key[i], b.with_items ? items[i].s[0] : -1, b.with_items ? items[i].s[1] : -1};
}

void write_states(ClRuntime& rt, const ItemBuffers& b, std::size_t begin, const std::vector<ItemState>& in) {
  const std::size_t count = in.size();
  std::vector<cl_int2> items(count);
  std::vector<cl_int> tri(count);
  std::vector<cl_int2> key(count);
  std::vector<cl_float> t(count);
  for (std::size_t i = 0; i < count; ++i) {
    t[i] = in[i].t, tri[i] = in[i].tri, key[i] = in[i].key;
    items[i].s[0] = in[i].object, items[i].s[1] = in[i].item_facet;
  }
  if (b.with_items) write_range(rt, *b.items, begin, items, "clEnqueueWriteBuffer(item buffer)");
  write_range(rt, *b.tri, begin, tri, "clEnqueueWriteBuffer(item buffer hits)");
  write_range(rt, *b.key, begin, key, "clEnqueueWriteBuffer(item buffer keys)");
  write_range(rt, *b.t, begin, t, "clEnqueueWriteBuffer(item buffer distances)");
}

}  // namespace

void ItemRelay::receive(std::size_t begin, std::size_t count) {
  Ranks& ranks = ranks_;
  ClRuntime& rt = rt_;
  const ItemBuffers& b = buffers_;
  if (ranks.rank() == 0 || count == 0) return;
  std::vector<ItemState> state(count);
  ranks.receive(state.data(), count * sizeof(ItemState), ranks.rank() - 1, kRelayTag);
  write_states(rt, b, begin, state);
}

void ItemRelay::send(std::size_t begin, std::size_t count) {
  if (ranks_.rank() + 1 >= ranks_.size() || count == 0) return;
  outbox_.emplace_back();
  read_states(rt_, buffers_, begin, count, outbox_.back());
  ranks_.send(outbox_.back().data(), count * sizeof(ItemState), ranks_.rank() + 1, kRelayTag);
}

void ItemRelay::share(std::size_t npix) {
  Ranks& ranks = ranks_;
  ClRuntime& rt = rt_;
  const ItemBuffers& b = buffers_;
  ranks.wait_sends();
  outbox_.clear();
  const int last = ranks.size() - 1;
  std::vector<ItemState> state(npix);
  if (ranks.rank() == last) read_states(rt, b, 0, npix, state);
  ranks.broadcast(state.data(), npix * sizeof(ItemState), last);
  if (ranks.rank() != last) write_states(rt, b, 0, state);
}

RankExchange::RankExchange(ClRuntime& rt, Ranks& ranks, const PeGroup& group, int num_pes, int depth,
                           std::size_t round_cap)
    : rt_(rt),
      ranks_(ranks),
      group_(group),
      num_pes_(num_pes),
      depth_(depth),
      round_cap_(std::max<std::size_t>(1, round_cap)),
      totals_(num_pes) {}

void RankExchange::reset() {
  sent.clear();
  received.clear();
  staging_seconds.clear();
  mpi_seconds.clear();
}

void RankExchange::start(const cl::Buffer& pe_total, const DescriptorSet& next, std::size_t waiting) {
  const auto t0 = std::chrono::steady_clock::now();
  keep_round(staging_seconds, 0.0, round_cap_);
  keep_round(mpi_seconds, 0.0, round_cap_);
  cl_check(rt_.queue().enqueueReadBuffer(pe_total, CL_TRUE, 0, totals_.size() * sizeof(cl_int), totals_.data()),
           "clEnqueueReadBuffer(exchange totals)");
  // [bound for lower ranks | this group's waiting | bound for higher ranks]
  const int R = ranks_.size();
  send_counts_.assign(R, 0);
  lo_ = 0;
  std::uint64_t hi = 0;
  for (int p = 0; p < num_pes_; ++p) {
    if (p >= group_.begin && p < group_.end) continue;
    const std::uint64_t total = std::uint64_t(std::max(0, totals_[p]));
    send_counts_[rank_of_pe(num_pes_, R, p)] += total;
    (p < group_.begin ? lo_ : hi) += total;
  }
  if (lo_ + hi > waiting) throw std::logic_error("rank exchange: more records bound elsewhere than waiting");
  waiting_ = waiting - lo_ - hi;
  const std::size_t B = DescriptorSet::kBytes;
  send_.resize((lo_ + hi) * B);
  reads_.clear();
  auto read = [&](std::uint64_t from, std::uint64_t count, std::uint64_t to) {
    if (count == 0) return;
    reads_.emplace_back();
    cl_check(rt_.queue().enqueueReadBuffer(next.records, CL_FALSE, from * B, count * B, send_.data() + to * B,
                                           nullptr, &reads_.back()),
             "clEnqueueReadBuffer(records bound for other ranks)");
  };
  read(0, lo_, 0);
  read(lo_ + waiting_, hi, lo_);
  staging_seconds.back() += since(t0);
}

void RankExchange::exchange() {
  const auto t0 = std::chrono::steady_clock::now();
  if (!reads_.empty()) cl_check(cl::Event::waitForEvents(reads_), "clWaitForEvents(records bound for other ranks)");
  const auto t1 = std::chrono::steady_clock::now();
  staging_seconds.back() += std::chrono::duration<double>(t1 - t0).count();
  // Records are sent as they lie, in destination-rank order; each source's
  // arrive in rank order, each in its own (stable) order.
  std::vector<std::uint64_t> got = ranks_.all_to_all(send_, send_counts_, DescriptorSet::kBytes, recv_);
  keep_round(sent, send_counts_, round_cap_);
  keep_round(received, got, round_cap_);
  mpi_seconds.back() += since(t1);
}

std::size_t RankExchange::finish(const DescriptorSet& next, DescriptorSet& into, std::size_t spare) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::size_t B = DescriptorSet::kBytes, in = recv_.size() / B, len = waiting_ + in;
  if (into.capacity < len + spare) into.allocate(rt_, (len + spare) * 3 / 2, "descriptor pool");
  auto& q = rt_.queue();
  // What arrived leads: it was spawned by the phase that just ran elsewhere,
  // and the exchange takes the newest records first (kernels/scatter.cl), so
  // the ray trees are worked depth first on every rank as on one.
  // Only records travel between ranks; their destinations are read from them.
  into.write_raw(rt_, recv_.data(), in, 0, depth_);
  if (waiting_ > 0) {
    cl_check(q.enqueueCopyBuffer(next.records, into.records, lo_ * B, in * B, waiting_ * B),
             "clEnqueueCopyBuffer(waiting records)");
    cl_check(q.enqueueCopyBuffer(next.dests, into.dests, lo_ * sizeof(cl_int), in * sizeof(cl_int),
                                 waiting_ * sizeof(cl_int)),
             "clEnqueueCopyBuffer(waiting records' sort keys)");
  }
  staging_seconds.back() += since(t0);
  return len;
}

void reduce_to_root(Ranks& ranks, std::vector<std::uint64_t>& values) { ranks.reduce_sum(values, 0); }

}  // namespace opsila
