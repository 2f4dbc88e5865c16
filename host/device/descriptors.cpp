#include "device/descriptors.h"

#include <algorithm>
#include <cstring>
#include <vector>

namespace opsila {

void DescriptorSet::allocate(ClRuntime& rt, std::size_t n, const char* what) {
  n = std::max<std::size_t>(n, 1);
  records = device_buffer(rt, n * kBytes, what);
  dests = device_buffer(rt, n * sizeof(cl_int), what);
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
  move_pool_ = decltype(move_pool_)(rt, "scatter_move_pool");
  move_out_ = decltype(move_out_)(rt, "scatter_move_outputs");
  move_blocks_ = decltype(move_blocks_)(rt, "scatter_move_blocks");
  by_block_ = !rt.device().is_gpu;
  // scatter.cl's work-group arrays hold OPSILA_SCATTER_GROUP_MAX entries.
  const std::size_t cap = std::min<std::size_t>(rt.group_size(), OPSILA_SCATTER_GROUP_MAX);
  wg_scan_ = queried_group_size(rt, scan_.kernel(), cap);
  wg_plan_ = queried_group_size(rt, plan_.kernel(), cap);
  bank_begin = device_buffer(rt, num_pes * sizeof(cl_int), "bank offsets");
  bank_count = device_buffer(rt, num_pes * sizeof(cl_int), "bank counts");
  pe_total = device_buffer(rt, num_pes * sizeof(cl_int), "scatter totals");
  key_total = device_buffer(rt, 2 * num_pes * sizeof(cl_int), "scatter key totals");
  key_begin = device_buffer(rt, 2 * num_pes * sizeof(cl_int), "scatter key offsets");
  key_count = device_buffer(rt, 2 * num_pes * sizeof(cl_int), "scatter key counts");
  key_base = device_buffer(rt, 2 * num_pes * sizeof(cl_int), "scatter overflow bases");
  counts = device_buffer(rt, 3 * sizeof(cl_int), "scatter counts");
  dummy_ = device_buffer(rt, sizeof(cl_int), "no SPMD outputs");
}

void ScatterPass::grow(Grown& g, std::size_t need, std::size_t size, const char* what) {
  if (g.capacity >= need) return;
  g.capacity = size;
  g.buffer = device_buffer(rt_, size * sizeof(cl_int), what);
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
  return (a.pool_len + kBlock - 1) / kBlock + a.out_groups;
}

void ScatterPass::plan(Launcher& launch, const Args& a, int round) {
  const int P = num_pes_, K = 2 * P;  // two sort keys a PE (OPSILA_STREAM_KEY)
  const int pool_blocks = (a.pool_len + kBlock - 1) / kBlock, nblocks = blocks(a);
  const std::size_t sources = std::size_t(a.pool_len) + std::size_t(a.out_groups) * a.group_size * a.spawn_slots;
  // Grown by half again, so that a frame's slowly rising needs do not
  // reallocate every round.
  grow(ranks, sources, sources + sources / 2, "scatter ranks");
  grow(block_counts, (std::size_t(nblocks) + 1) * K, (std::size_t(nblocks) + nblocks / 2 + 1) * K,
       "scatter block counts");
  const std::size_t groups = std::size_t(a.slots) / a.group_size + P + 1;
  grow(group_pe, groups, groups, "SPMD work-group PEs");
  grow(group_first, groups, groups, "SPMD work-group slots");
  const cl::Buffer& out = a.outputs ? a.outputs->records : dummy_;
  const cl::Buffer& out_dest = a.outputs ? a.outputs->dests : dummy_;
  const cl::Buffer& out_count = a.out_item_count ? *a.out_item_count : dummy_;
  count_.bind(a.pool_len, pool_blocks, nblocks, a.group_size, a.spawn_slots, K, *a.pool, out, out_dest, out_count, block_counts.buffer,
              ranks.buffer, by_block_ ? 0 : 1);
  launch.run(count_.kernel(), "scatter_count", std::max(nblocks, 1), 0, round);
  scan_.bind(nblocks, K, block_counts.buffer, key_total);
  // One work-group per key on a GPU, one in all on a CPU (see scatter_scan).
  const std::size_t scan_groups = by_block_ ? 1 : std::size_t(K);
  launch.run(scan_.kernel(), "scatter_scan", scan_groups * wg_scan_, wg_scan_, round);
  const int cap = a.cap > 0 ? a.cap : a.slots;
  const int group_end = a.group_end < 0 ? P : a.group_end;
  plan_.bind(P, a.group_begin, group_end, a.slots, cap, a.group_size, a.throttle ? 1 : 0, key_total, pe_total,
             bank_begin, bank_count, key_begin, key_count, key_base, group_pe.buffer, group_first.buffer, counts);
  launch.run(plan_.kernel(), "scatter_plan", wg_plan_, wg_plan_, round);
}

void ScatterPass::scan(Launcher& launch, const char* name, const cl::Buffer& values, int n, const cl::Buffer& total,
                       int round) {
  scan_.bind(n, 1, values, total);
  launch.run(scan_.kernel(), name, wg_scan_, wg_scan_, round);
}

void ScatterPass::move(Launcher& launch, const Args& a, int round) {
  const int K = 2 * num_pes_;
  const int pool_blocks = (a.pool_len + kBlock - 1) / kBlock;
  if (by_block_) {
    const cl::Buffer& out = a.outputs ? a.outputs->records : dummy_;
    const cl::Buffer& out_dest = a.outputs ? a.outputs->dests : dummy_;
    const cl::Buffer& out_count = a.out_item_count ? *a.out_item_count : dummy_;
    move_blocks_.bind(a.pool_len, pool_blocks, blocks(a), a.group_size, a.spawn_slots, K, *a.pool, out, out_dest,
                      out_count, block_counts.buffer, key_begin, key_count, key_base, *a.banks, *a.next_pool);
    if (blocks(a) > 0) launch.run(move_blocks_.kernel(), "scatter_move", std::size_t(blocks(a)), 0, round);
    return;
  }
  if (a.pool_len > 0) {
    move_pool_.bind(a.pool_len, a.out_groups, K, *a.pool, ranks.buffer, block_counts.buffer, key_begin, key_count,
                    key_base, *a.banks, *a.next_pool);
    launch.run(move_pool_.kernel(), "scatter_move", std::size_t(a.pool_len), 0, round);
  }
  if (a.out_groups > 0) {
    const int items = a.out_groups * a.group_size;
    move_out_.bind(items, a.group_size, a.spawn_slots, a.pool_len, K, *a.outputs, *a.out_item_count, ranks.buffer,
                   block_counts.buffer, key_begin, key_count, key_base, *a.banks, *a.next_pool);
    launch.run(move_out_.kernel(), "scatter_move", std::size_t(items), 0, round);
  }
}

}  // namespace opsila
