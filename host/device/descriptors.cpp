#include "device/descriptors.h"

#include <algorithm>
#include <cstring>
#include <vector>

namespace opsila {

void DescriptorSet::allocate(ClRuntime& rt, std::size_t n, const char* what) {
  n = std::max<std::size_t>(n, 1);
  records.buffer = device_buffer(rt, n * kBytes, what);
  dests.buffer = device_buffer(rt, n * sizeof(cl_int), what);
  capacity = n;
}

void DescriptorSet::copy_prefix_to(ClRuntime& rt, DescriptorSet& to, std::size_t count) const {
  if (count == 0) return;
  cl_check(rt.queue().enqueueCopyBuffer(records, to.records, 0, 0, count * kBytes), "clEnqueueCopyBuffer(descriptors)");
  cl_check(rt.queue().enqueueCopyBuffer(dests, to.dests, 0, 0, count * sizeof(cl_int)),
           "clEnqueueCopyBuffer(descriptor destinations)");
}

void DescriptorSet::write_raw(ClRuntime& rt, const unsigned char* bytes, std::size_t count, std::size_t at,
                              int depth) const {
  if (count == 0) return;
  std::vector<cl_int> d(count);
  for (std::size_t i = 0; i < count; ++i) {
    HostDescriptor h;
    std::memcpy(&h, bytes + i * kBytes, kBytes);
    d[i] = desc_key(h, depth);
  }
  cl_check(rt.queue().enqueueWriteBuffer(records, CL_TRUE, at * kBytes, count * kBytes, bytes),
           "clEnqueueWriteBuffer(descriptors)");
  cl_check(rt.queue().enqueueWriteBuffer(dests, CL_TRUE, at * sizeof(cl_int), count * sizeof(cl_int), d.data()),
           "clEnqueueWriteBuffer(descriptor sort keys)");
}

void DescriptorSet::write(ClRuntime& rt, const std::vector<HostDescriptor>& v, std::size_t at, int depth) const {
  write_raw(rt, reinterpret_cast<const unsigned char*>(v.data()), v.size(), at, depth);
}

std::vector<HostDescriptor> DescriptorSet::read(ClRuntime& rt, std::size_t count, std::size_t at) const {
  std::vector<HostDescriptor> v(count);
  if (count)
    cl_check(rt.queue().enqueueReadBuffer(records, CL_TRUE, at * kBytes, count * kBytes, v.data()),
             "clEnqueueReadBuffer(descriptors)");
  return v;
}

namespace {

// A kernel's work-group size: what it allows, at most `cap`, a power of two.
std::size_t queried_group_size(ClRuntime& rt, cl::Kernel& k, std::size_t cap) {
  std::size_t allowed = 0;
  cl_check(k.getWorkGroupInfo(rt.device().device, CL_KERNEL_WORK_GROUP_SIZE, &allowed),
           "clGetKernelWorkGroupInfo(CL_KERNEL_WORK_GROUP_SIZE)");
  std::size_t local = 1;
  while (local * 2 <= std::min(allowed, cap)) local *= 2;
  return local;
}

}  // namespace

ScatterPass::ScatterPass(ClRuntime& rt, int num_pes) : rt_(rt), num_pes_(num_pes) {
  count_ = decltype(count_)(rt, "scatter_count");
  scan_ = decltype(scan_)(rt, "scatter_scan");
  plan_ = decltype(plan_)(rt, "scatter_plan");
  move_entries_ = decltype(move_entries_)(rt, "scatter_move_entries");
  move_blocks_ = decltype(move_blocks_)(rt, "scatter_move_blocks");
  by_block_ = !rt.device().is_gpu;
  // scatter.cl's work-group arrays hold OPSILA_SCATTER_GROUP_MAX entries.
  const std::size_t cap = std::min<std::size_t>(rt.group_size(), OPSILA_SCATTER_GROUP_MAX);
  wg_scan_ = queried_group_size(rt, scan_.kernel(), cap);
  wg_plan_ = queried_group_size(rt, plan_.kernel(), cap);
  for (const Table& t : own_tables()) *t.buffer = device_buffer(rt, t.ints * sizeof(cl_int), t.name);
  // scatter_plan writes the key totals by atomics, which read them first
  // (Oclgrind's check counts that read).
  zero_buffer(rt, key_total, 2 * std::size_t(num_pes) * sizeof(cl_int), "scatter key totals");
  no_outputs_.records.buffer = no_outputs_.dests.buffer = no_counts_.buffer = dummy_;
}

std::vector<ScatterPass::Table> ScatterPass::grown_tables(const Needs& n) {
  return {{"scatter ranks", n.ranks, &ranks.buffer.buffer, &ranks.capacity},
          {"scatter block counts", n.block_counts, &block_counts.buffer.buffer, &block_counts.capacity},
          {"SPMD work-group PEs", n.groups, &group_pe.buffer.buffer, &group_pe.capacity},
          {"SPMD work-group slots", n.groups, &group_first.buffer.buffer, &group_first.capacity}};
}

std::vector<ScatterPass::Table> ScatterPass::own_tables() {
  const std::size_t P = std::size_t(num_pes_), K = 2 * P;  // two sort keys a PE (OPSILA_STREAM_KEY)
  return {{"bank offsets", P, &bank_ranges.begin.buffer, nullptr},
          {"bank counts", P, &bank_ranges.count.buffer, nullptr},
          {"scatter totals", P, &pe_total.buffer, nullptr},
          {"scatter key totals", K, &key_total.buffer, nullptr},
          {"scatter key offsets", K, &key_ranges.begin.buffer, nullptr},
          {"scatter key counts", K, &key_ranges.count.buffer, nullptr},
          {"scatter overflow bases", K, &key_ranges.base.buffer, nullptr},
          {"scatter counts", 3, &counts.buffer, nullptr},
          {"scatter plan ticket", 1, &ticket.buffer, nullptr},
          {"no SPMD outputs", 1, &dummy_, nullptr}};
}

ScatterPass::Needs ScatterPass::needs(std::size_t sources, std::size_t blocks, std::size_t slots,
                                      std::size_t group_size, int num_pes) {
  Needs n;
  n.ranks = sources;
  n.block_counts = (blocks + 1) * 2 * std::size_t(num_pes);  // two sort keys a PE
  n.groups = slots / group_size + std::size_t(num_pes) + 1;
  return n;
}

void ScatterPass::grow(const Table& need, std::size_t size) {
  if (*need.capacity >= need.ints) return;
  *need.capacity = size;
  *need.buffer = device_buffer(rt_, size * sizeof(cl_int), need.name);
}

ScatterPass::Args ScatterPass::pool_only(const DescriptorSet& pool, std::size_t pool_len, const DescriptorSet& banks,
                                         const DescriptorSet& next, int slots, int group_size) {
  Args a;
  a.pool_len = static_cast<int>(pool_len);
  a.pool = &pool;
  a.slots = slots;
  a.group_size = group_size;
  a.banks = &banks;
  a.next_pool = &next;
  return a;
}

int ScatterPass::blocks(const Args& a) const {
  return static_cast<int>(blocks_of(std::size_t(a.pool_len))) + a.out_groups;
}

scatter_kernels::Sources ScatterPass::sources_of(const Args& a) const {
  scatter_kernels::Sources s;
  s.pool_len = a.pool_len;
  s.pool_blocks = static_cast<int>(blocks_of(std::size_t(a.pool_len)));
  s.num_blocks = blocks(a);
  s.items_per_group = a.group_size;
  s.spawn_slots = a.spawn_slots;
  s.num_keys = 2 * num_pes_;  // two sort keys a PE (OPSILA_STREAM_KEY)
  s.pool = *a.pool;
  s.outputs = a.outputs ? *a.outputs : no_outputs_;
  s.out_count = a.out_item_count ? *a.out_item_count : no_counts_;
  return s;
}

scatter_kernels::Placement ScatterPass::placement(const Args& a) const {
  scatter_kernels::Placement to;
  to.keys = key_ranges;
  to.banks = *a.banks;
  to.next = *a.next_pool;
  return to;
}

void ScatterPass::plan(Launcher& launch, const Args& a, int round) {
  const int P = num_pes_;
  const std::size_t nblocks = std::size_t(blocks(a));
  const std::size_t sources = std::size_t(a.pool_len) + std::size_t(a.out_groups) * a.group_size * a.spawn_slots;
  // Grown by half again, so that a frame's slowly rising needs do not
  // reallocate every round.
  const std::size_t slots = std::size_t(a.slots), wg = std::size_t(a.group_size);
  const std::vector<Table> need = grown_tables(needs(sources, nblocks, slots, wg, P));
  const std::vector<Table> roomy = grown_tables(needs(sources + sources / 2, nblocks + nblocks / 2, slots, wg, P));
  for (std::size_t i = 0; i < need.size(); ++i) grow(need[i], roomy[i].ints);
  scatter_kernels::CountArgs c;
  c.sources = sources_of(a);
  c.hist = block_counts.buffer;
  c.ranks = ranks.buffer;
  c.write_rank = by_block_ ? 0 : 1;
  c.ticket = ticket;
  count_.bind(c);
  launch.run(count_.kernel(), "scatter_count", std::max<std::size_t>(nblocks, 1), 0, round);
  scatter_kernels::PlanArgs p;
  p.num_blocks = static_cast<int>(nblocks);
  p.num_keys = c.sources.num_keys;
  p.hist = block_counts.buffer;
  p.key_total = key_total;
  p.ticket = ticket;
  p.num_pes = P;
  p.group_begin = a.group_begin;
  p.group_end = a.group_end < 0 ? P : a.group_end;
  p.slots = a.slots;
  p.cap = a.cap > 0 ? a.cap : a.slots;
  p.group_size = a.group_size;
  p.throttle = a.throttle ? 1 : 0;
  p.pe_total = pe_total;
  p.banks = bank_ranges;
  p.keys = key_ranges;
  p.groups = group_table();
  p.counts = counts;
  plan_.bind(p);
  // The scan: one work-group per key on a GPU, one in all on a CPU (see
  // scan_keys); the last to finish plans.
  const std::size_t scan_groups = by_block_ ? 1 : std::size_t(p.num_keys);
  launch.run(plan_.kernel(), "scatter_plan", scan_groups * wg_plan_, wg_plan_, round);
}

void ScatterPass::scan(Launcher& launch, const char* name, const cl::Buffer& values, int n, const cl::Buffer& total,
                       int round) {
  scatter_kernels::ScanArgs s;
  s.num_blocks = n;
  s.values = values;
  s.total = total;
  scan_.bind(s);
  launch.run(scan_.kernel(), name, wg_scan_, wg_scan_, round);
}

void ScatterPass::move(Launcher& launch, const Args& a, int round) {
  const scatter_kernels::Sources sources = sources_of(a);
  if (by_block_) {
    scatter_kernels::MoveBlocksArgs m;
    m.sources = sources;
    m.hist = block_counts.buffer;
    m.to = placement(a);
    move_blocks_.bind(m);
    if (sources.num_blocks > 0)
      launch.run(move_blocks_.kernel(), "scatter_move", std::size_t(sources.num_blocks), 0, round);
    return;
  }
  // One work-item per pool entry, then one per SPMD work-item.
  const std::size_t entries = std::size_t(a.pool_len) + std::size_t(a.out_groups) * a.group_size;
  scatter_kernels::MoveEntriesArgs m;
  m.sources = sources;
  m.ranks = ranks.buffer;
  m.hist = block_counts.buffer;
  m.to = placement(a);
  move_entries_.bind(m);
  if (entries > 0) launch.run(move_entries_.kernel(), "scatter_move", entries, 0, round);
}

}  // namespace opsila
