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
struct DescriptorSet {
  cl::Buffer records;
  cl::Buffer dests;
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
    const cl::Buffer* out_item_count = nullptr;
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
  // The move by entry (GPUs) or by block (CPUs) is chosen from the device;
  // tests run both on any device.
  void set_move_by_block(bool by_block) { by_block_ = by_block; }
  void plan(Launcher& launch, const Args& a, int round);
  // The exclusive scan of n ints in place (scatter_scan, one key), their
  // total in total[0], launched as `name`: the hit list's (kernels/primary.cl).
  void scan(Launcher& launch, const char* name, const cl::Buffer& values, int n, const cl::Buffer& total, int round);
  void move(Launcher& launch, const Args& a, int round);
  // Results of plan(): per PE, per sort key (two a PE), and the SPMD
  // work-group table; pe_total: each PE's entries (placed or not).
  cl::Buffer bank_begin, bank_count, pe_total, counts;  // counts = {waiting, placed, groups}
  cl::Buffer key_total, key_begin, key_count, key_base;
  // Buffers plan() sizes by the pass (capacity in ints) and grows when a
  // pass needs more; a frame allocates them ahead, at the sizes its memory
  // plan counts (the buffer table, frame/frame_buffers.cpp).
  struct Grown {
    cl::Buffer buffer;
    std::size_t capacity = 0;
  };
  Grown ranks, block_counts;    // each source entry's rank; per block and key, its count, then its offset
  Grown group_pe, group_first;  // the SPMD work-group table: each group's PE and first bank slot

 private:
  ClRuntime& rt_;
  int num_pes_;
  std::size_t wg_scan_ = 1, wg_plan_ = 1;
  // kernels/scatter.cl, their parameters as bound (device/kernel_args.h).
  using Buf = cl::Buffer;
  using Set = DescriptorSet;
  KernelBinding<int, int, int, int, int, int, Set, Buf, Buf, Buf, Buf, Buf, int> count_;
  KernelBinding<int, int, Buf, Buf> scan_;
  KernelBinding<int, int, int, int, int, int, int, Buf, Buf, Buf, Buf, Buf, Buf, Buf, Buf, Buf, Buf> plan_;
  KernelBinding<int, int, int, Set, Buf, Buf, Buf, Buf, Buf, Set, Set> move_pool_;
  KernelBinding<int, int, int, int, int, Set, Buf, Buf, Buf, Buf, Buf, Buf, Set, Set> move_out_;
  KernelBinding<int, int, int, int, int, int, Set, Buf, Buf, Buf, Buf, Buf, Buf, Buf, Set, Set> move_blocks_;
  // Move by block (one work-item walks a block in order: CPUs) or by entry
  // (one work-item per record, ranks stored by the count: GPUs).
  bool by_block_ = false;
  cl::Buffer dummy_;
  int blocks(const Args& a) const;
  void grow(Grown& g, std::size_t need, std::size_t size, const char* what);
};

}  // namespace opsila
