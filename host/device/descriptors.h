// Device-side descriptor vectors and the SIMD scatter that moves them
// between banks. Shared by the renderer, the tests and the benchmarks.
#pragma once

#include <cstddef>
#include <string>
#include <tuple>
#include <vector>

#include "device/cl_runtime.h"
#include "device/device_buffers.h"
#include "device/kernel_args.h"
#include "device/launcher.h"
#include "opsila_shared.h"

namespace opsila {

// One descriptor as the host sees it, generated from the same field table as
// the kernels' (OPSILA_DESCRIPTOR_LANES in kernels/opsila_shared.h).
#define OPSILA_HOST_MEMBER(lane, name, type, host_type) host_type name;
struct HostDescriptor {
  OPSILA_DESCRIPTOR_LANES(OPSILA_HOST_MEMBER)
};
#undef OPSILA_HOST_MEMBER
#define OPSILA_HOST_LANE_CHECK(lane, name, type, host_type)                   \
  static_assert(offsetof(HostDescriptor, name) == (lane) * sizeof(cl_float4), \
                "HostDescriptor lane " #name " follows the field table");
OPSILA_DESCRIPTOR_LANES(OPSILA_HOST_LANE_CHECK)
#undef OPSILA_HOST_LANE_CHECK
static_assert(sizeof(HostDescriptor) == OPSILA_DESCRIPTOR_BYTES, "HostDescriptor is one 64-byte record");

// Named slots, as kernels/lib/descriptor.cl names them.
inline int desc_dest(const HostDescriptor& d) { return d.ids.s[3]; }  // destination PE, -1 NIL
inline int desc_meta(const HostDescriptor& d) { return d.ids.s[1]; }  // kind | level << 2
// The exchange's sort key of a record in a frame of this depth
// (OPSILA_STREAM_KEY): what the dense stream holds.
inline int desc_key(const HostDescriptor& d, int depth) { return OPSILA_STREAM_KEY(desc_dest(d), desc_meta(d), depth); }
inline int desc_pixel(const HostDescriptor& d) { return d.ids.s[0]; }

// One descriptor vector on the device: `capacity` records of kBytes, and
// the dense stream of their sort keys (kernels/lib/descriptor.cl,
// DESC_PARAMS): a kernel parameter pair, written together.
using DescriptorRecords = DeviceArray<struct DescriptorRecordsRole>;
using DescriptorKeys = DeviceArray<struct DescriptorKeysRole>;
struct DescriptorSet {
  DescriptorRecords records;
  DescriptorKeys dests;
  std::size_t capacity = 0;
  static constexpr std::size_t kBytes = OPSILA_DESCRIPTOR_BYTES;           // one record
  static constexpr std::size_t kSlotBytes = kBytes + sizeof(cl_int);       // device memory per slot
  // Writes count records from host memory at slot `at`, and their sort keys
  // for a frame of this depth.
  void write_raw(ClRuntime& rt, const unsigned char* bytes, std::size_t count, std::size_t at, int depth) const;
  void allocate(ClRuntime& rt, std::size_t n, const char* what);
  auto kernel_args() const { return std::tie(records, dests); }  // DESC_PARAMS (device/kernel_args.h)
  void copy_prefix_to(ClRuntime& rt, DescriptorSet& to, std::size_t count) const;
  void write(ClRuntime& rt, const std::vector<HostDescriptor>& v, std::size_t at, int depth) const;
  std::vector<HostDescriptor> read(ClRuntime& rt, std::size_t count, std::size_t at = 0) const;
};

// The exchange's tables (kernels/scatter.cl), a handle type each
// (device/kernel_args.h).
using SourceRanks = DeviceArray<struct SourceRanksRole>;      // each source entry's rank in its key
using BlockCounts = DeviceArray<struct BlockCountsRole>;      // per block and key: its count, then its offset
using KeyTotals = DeviceArray<struct KeyTotalsRole>;          // per sort key, all blocks
using PeTotals = DeviceArray<struct PeTotalsRole>;            // per PE, its entries (placed or not)
using ScatterCounts = DeviceArray<struct ScatterCountsRole>;  // {waiting, placed, SPMD work-groups}
using OutputCounts = DeviceArray<struct OutputCountsRole>;    // the SPMD phase's records, per work-item
using PlanTicket = DeviceArray<struct PlanTicketRole>;        // scatter_plan's work-groups that scanned
// Per PE: its bank's first slot and how many it holds (the SPMD phase's).
struct BankRanges {
  DeviceArray<struct BankBeginRole> begin;
  DeviceArray<struct BankCountRole> count;
  auto kernel_args() const { return std::tie(begin, count); }
};
// Per sort key: its first bank slot, how many fit there, and where the rest wait.
struct KeyRanges {
  DeviceArray<struct KeyBeginRole> begin;
  DeviceArray<struct KeyCountRole> count;
  DeviceArray<struct KeyBaseRole> base;
  auto kernel_args() const { return std::tie(begin, count, base); }
};
// The SPMD work-group table: each group's PE and first bank slot.
using GroupPes = DeviceArray<struct GroupPesRole>;
using GroupSlots = DeviceArray<struct GroupSlotsRole>;
struct WorkGroupTable {
  GroupPes pe;
  GroupSlots first;
  auto kernel_args() const { return std::tie(pe, first); }
};

// The argument structs of kernels/scatter.cl, in their signatures' order.
namespace scatter_kernels {
// What scatter_count and scatter_move_blocks walk block by block: the pool's
// blocks, then one block per SPMD work-group of outputs.
struct Sources {
  int pool_len = 0, pool_blocks = 0, num_blocks = 0, items_per_group = 1, spawn_slots = 1, num_keys = 0;
  DescriptorSet pool, outputs;
  OutputCounts out_count;
  auto kernel_args() const {
    return std::tie(pool_len, pool_blocks, num_blocks, items_per_group, spawn_slots, num_keys, pool, outputs,
                    out_count);
  }
};
struct CountArgs {
  Sources sources;
  BlockCounts hist;
  SourceRanks ranks;
  int write_rank = 0;  // the move by entry reads them
  PlanTicket ticket;   // reset for the plan
  auto kernel_args() const { return std::tie(sources, hist, ranks, write_rank, ticket); }
};
// The scan alone is any exclusive scan of ints (the hit list's blocks): its
// buffers are plain.
struct ScanArgs {
  int num_blocks = 0, num_keys = 1;
  cl::Buffer values, total;
  auto kernel_args() const { return std::tie(num_blocks, num_keys, values, total); }
};
// The scan of the block counts, then the plan.
struct PlanArgs {
  int num_blocks = 0, num_keys = 1;
  BlockCounts hist;
  KeyTotals key_total;
  PlanTicket ticket;
  int num_pes = 0, group_begin = 0, group_end = 0, slots = 1, cap = 1, group_size = 1, throttle = 0;
  PeTotals pe_total;
  BankRanges banks;
  KeyRanges keys;
  WorkGroupTable groups;
  ScatterCounts counts;
  auto kernel_args() const {
    return std::tie(num_blocks, num_keys, hist, key_total, ticket, num_pes, group_begin, group_end, slots, cap,
                    group_size, throttle, pe_total, banks, keys, groups, counts);
  }
};
// Where a move puts a record: its key's bank slots, else its waiting place.
struct Placement {
  KeyRanges keys;
  DescriptorSet banks, next;
  auto kernel_args() const { return std::tie(keys, banks, next); }
};
struct MoveEntriesArgs {
  Sources sources;
  SourceRanks ranks;
  BlockCounts hist;
  Placement to;
  auto kernel_args() const { return std::tie(sources, ranks, hist, to); }
};
struct MoveBlocksArgs {
  Sources sources;
  BlockCounts hist;
  Placement to;
  auto kernel_args() const { return std::tie(sources, hist, to); }
};
}  // namespace scatter_kernels

// The exchange Vd(I'(i)) = Vs(i) over source = [SPMD outputs | waiting pool]
// (kernels/scatter.cl). plan() ranks every entry and decides the banks of
// the next SPMD phase; move() puts each record in place. Between the two,
// `counts` = {waiting, placed, SPMD work-groups} may be read.
class ScatterPass {
 public:
  static constexpr int kBlock = OPSILA_SCATTER_BLOCK;
  ScatterPass(ClRuntime& rt, int num_pes);
  struct Args {
    int pool_len = 0;                       // waiting records (NIL holes allowed)
    const DescriptorSet* pool = nullptr;
    // SPMD outputs: out_groups work-groups of group_size work-items, each with
    // spawn_slots places and out_item_count[t] records at t * spawn_slots.
    int out_groups = 0, group_size = 1, spawn_slots = 1;
    const DescriptorSet* outputs = nullptr;
    const OutputCounts* out_item_count = nullptr;
    // Bank slots to fill (descriptors in flight), at most `cap` per PE
    // (0: no cap); banks start at multiples of group_size.
    int slots = 1, cap = 0;
    const DescriptorSet* banks = nullptr;
    const DescriptorSet* next_pool = nullptr;  // what finds no bank slot
    // This device's PEs [group_begin, group_end) (-1: all): only they get
    // bank slots here; what is bound elsewhere waits in next_pool, per PE in
    // PE order, for the rank exchange.
    int group_begin = 0, group_end = -1;
    // More wait than the frame planned for: banks take only the records
    // that end their ray tree, while there are any (kernels/scatter.cl).
    bool throttle = false;
  };
  // A pass over a pool alone, no SPMD outputs (the bench and the tests).
  static Args pool_only(const DescriptorSet& pool, std::size_t pool_len, const DescriptorSet& banks,
                        const DescriptorSet& next, int slots, int group_size);
  // The move by entry (GPUs) or by block (CPUs) is chosen from the device,
  // and with it the plan's scan (a work-group per key, or one); tests run
  // both on any device.
  void set_move_by_block(bool by_block) { by_block_ = by_block; }
  void plan(Launcher& launch, const Args& a, int round);
  // The exclusive scan of n ints in place (scatter_scan, one key), their
  // total in total[0], launched as `name`: the hit list's (kernels/primary.cl).
  void scan(Launcher& launch, const char* name, const cl::Buffer& values, int n, const cl::Buffer& total, int round);
  void move(Launcher& launch, const Args& a, int round);

  // Blocks of kBlock entries that hold n.
  static std::size_t blocks_of(std::size_t n) { return (n + kBlock - 1) / kBlock; }
  // What a pass over `sources` entries in `blocks` blocks, filling `slots`
  // bank slots in work-groups of group_size, needs of the buffers plan()
  // grows (in ints).
  struct Needs {
    std::size_t ranks = 0, block_counts = 0, groups = 0;
  };
  static Needs needs(std::size_t sources, std::size_t blocks, std::size_t slots, std::size_t group_size, int num_pes);
  // The pass's buffers, their names and sizes in ints, listed once for the
  // pass and for the frame's buffer table (frame/frame_buffers.cpp): those
  // plan() grows, at the sizes of `n` (the frame allocates them ahead, and
  // plan() grows them from there), and those the constructor allocates.
  struct Table {
    const char* name;
    std::size_t ints;
    cl::Buffer* buffer;
    std::size_t* capacity;  // grown ones: the size they have
  };
  std::vector<Table> grown_tables(const Needs& n);
  std::vector<Table> own_tables();

  // Results of plan(): per PE, per sort key (two a PE), and the SPMD
  // work-group table; pe_total: each PE's entries (placed or not).
  BankRanges bank_ranges;
  PeTotals pe_total;
  ScatterCounts counts;  // {waiting, placed, groups}
  KeyTotals key_total;
  PlanTicket ticket;
  KeyRanges key_ranges;
  // Buffers plan() sizes by the pass (capacity in ints) and grows when a
  // pass needs more (grown_tables).
  template <class Handle>
  struct Grown {
    Handle buffer;
    std::size_t capacity = 0;
  };
  Grown<SourceRanks> ranks;
  Grown<BlockCounts> block_counts;
  Grown<GroupPes> group_pe;  // the SPMD work-group table
  Grown<GroupSlots> group_first;
  WorkGroupTable group_table() const { return {group_pe.buffer, group_first.buffer}; }

 private:
  ClRuntime& rt_;
  int num_pes_;
  std::size_t wg_scan_ = 1, wg_plan_ = 1;
  // kernels/scatter.cl, bound by their argument structs (device/kernel_args.h).
  KernelBinding<scatter_kernels::CountArgs> count_;
  KernelBinding<scatter_kernels::ScanArgs> scan_;
  KernelBinding<scatter_kernels::PlanArgs> plan_;
  KernelBinding<scatter_kernels::MoveEntriesArgs> move_entries_;
  KernelBinding<scatter_kernels::MoveBlocksArgs> move_blocks_;
  // Move by block (one work-item walks a block in order: CPUs) or by entry
  // (one work-item per record, ranks stored by the count: GPUs); the plan's
  // scan follows (scatter_plan: one work-group in all, or one per key).
  bool by_block_ = false;
  // Stands for the SPMD outputs and their counts when a pass has none.
  cl::Buffer dummy_;
  DescriptorSet no_outputs_;
  OutputCounts no_counts_;
  int blocks(const Args& a) const;
  scatter_kernels::Sources sources_of(const Args& a) const;
  scatter_kernels::Placement placement(const Args& a) const;
  void grow(const Table& need, std::size_t size);
};

}  // namespace opsila
