// Between MPI ranks (one group of PEs and one device each): the stages that
// cross a rank boundary. Every MPI call goes through Ranks (ranks.h); with
// one rank none of this runs.
//  - item buffer relay: the ranks extend each pixel's nearest hit in turn
//    (the least in the one hit order, kernels/hit_order.h), pipelined over
//    bands of pixel rows; the last rank shares the result;
//  - descriptor exchange, once per round: what the scatter left for PEs of
//    other ranks is read back, sent with MPI_Alltoall (counts) and
//    MPI_Alltoallv (records), and appended to the receiving rank's queue in
//    (source rank, source order) order; the SPMD phase runs meanwhile;
//  - the final reductions of pixel sums and counters to rank 0.
#pragma once

#include <cstdint>
#include <string>
#include <type_traits>
#include <vector>

#include "device/cl_runtime.h"
#include "device/descriptors.h"
#include "partition/pe_group.h"
#include "mpi/ranks.h"

namespace opsila {

// Item buffer relay buffers on the device.
struct ItemBuffers {
  const cl::Buffer* items = nullptr;  // int2 (object, facet): the output, relayed when the pass writes it
  const cl::Buffer* tri = nullptr;    // int, global facet triangle of the nearest hit so far
  const cl::Buffer* t = nullptr;      // float, its distance
  const cl::Buffer* key = nullptr;    // int2, its (facet id, fan index): the hit order's keys
  bool with_items = false;
};
// One pixel of the item buffer as the relay carries it: the nearest hit so
// far (distance, global triangle, (facet, fan) key) and the (object, facet)
// output.
struct ItemState {
  cl_float t;
  cl_int tri;
  cl_int2 key;
  cl_int object, item_facet;
};
static_assert(sizeof(ItemState) == 24, "ItemState layout");

// The item buffer's relay along the ranks, band after band of pixels.
class ItemRelay {
 public:
  ItemRelay(Ranks& ranks, ClRuntime& rt, const ItemBuffers& buffers) : ranks_(ranks), rt_(rt), buffers_(buffers) {}
  // Before the item-buffer launch over pixels [begin, begin + count): ranks
  // after the first receive the state left by the rank before them.
  void receive(std::size_t begin, std::size_t count);
  // After it: ranks before the last pass their state on (without waiting).
  void send(std::size_t begin, std::size_t count);
  // After the last band: the last rank holds the final item buffer; every
  // rank gets its hits (to build the primary descriptors of its PEs).
  void share(std::size_t npix);

 private:
  Ranks& ranks_;
  ClRuntime& rt_;
  ItemBuffers buffers_;
  std::vector<std::vector<ItemState>> outbox_;  // sent bands, alive until the sends complete
};

// One round's figures kept per round for the first `cap` rounds of a
// frame; later rounds are added into the last kept one, so that an endless
// render's records stay bounded and every sum over the rounds stays exact.
template <typename Row>
void keep_round(std::vector<Row>& rounds, const Row& row, std::size_t cap) {
  if (rounds.size() < cap || rounds.empty()) {
    rounds.push_back(row);
    return;
  }
  Row& last = rounds.back();
  if constexpr (std::is_arithmetic_v<Row>) {
    last += row;
  } else {
    if (last.size() < row.size()) last.resize(row.size());
    for (std::size_t i = 0; i < row.size(); ++i) last[i] += row[i];
  }
}

class RankExchange {
 public:
  // Rounds whose figures are kept one by one (keep_round): 2^16, some
  // 16 x ranks + 16 bytes each, far more rounds than any finite scene of
  // this repository takes.
  static constexpr std::size_t kRoundCap = std::size_t(1) << 16;
  // depth: the frame's, for the received records' sort keys.
  RankExchange(ClRuntime& rt, Ranks& ranks, const PeGroup& group, int num_pes, int depth,
               std::size_t round_cap = kRoundCap);
  // After the exchange's move (before the SPMD launch): `next` holds
  // `waiting` records per destination PE in PE order (other groups' PEs had
  // no bank here, so all of theirs waits). Reads the per-PE totals and
  // enqueues the read-back of the blocks bound for other ranks.
  void start(const cl::Buffer& pe_total, const DescriptorSet& next, std::size_t waiting);
  // While the SPMD phase runs: the MPI exchange.
  void exchange();
  // The next pool: the received records, then this rank's waiting ones
  // (still in `next`), written into `into` (free: the exchange consumed it),
  // grown to hold `spare` more. Returns its length.
  std::size_t finish(const DescriptorSet& next, DescriptorSet& into, std::size_t spare);
  std::uint64_t waiting() const { return waiting_; }  // own records that found no bank slot
  void reset();  // a new frame: forget the rounds' records
  // [round][rank]; past round_cap rounds, the last row sums the rest.
  std::vector<std::vector<std::uint64_t>> sent, received;
  // Host wall time per round (the same rows): staging (reading back,
  // writing the received records) and inside MPI (Alltoall + Alltoallv).
  std::vector<double> staging_seconds, mpi_seconds;
  std::size_t round_cap() const { return round_cap_; }

 private:
  ClRuntime& rt_;
  Ranks& ranks_;
  PeGroup group_;
  int num_pes_, depth_;
  std::size_t round_cap_;
  std::vector<cl_int> totals_;
  std::uint64_t lo_ = 0, waiting_ = 0;
  std::vector<std::uint64_t> send_counts_;
  std::vector<unsigned char> send_, recv_;
  std::vector<cl::Event> reads_;
};

// Sums every rank's values on rank 0 (pixel sums, counters, traffic).
void reduce_to_root(Ranks& ranks, std::vector<std::uint64_t>& values);

}  // namespace opsila
