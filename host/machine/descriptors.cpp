#include "machine/descriptors.h"

#include <algorithm>
#include <cstring>
#include <vector>

#include "machine/render_types.h"

namespace opsila {

cl::Buffer device_buffer(ClRuntime& rt, std::size_t bytes, const char* what) {
  if (bytes > rt.max_alloc())
    throw ClError(std::string("buffer '") + what + "' needs " + std::to_string(bytes) +
                  " bytes, more than the device's CL_DEVICE_MAX_MEM_ALLOC_SIZE (" + std::to_string(rt.max_alloc()) +
                  " bytes" + (rt.memory_limit() ? ", as lowered by OPSILA_DEVICE_MEMORY_LIMIT" : "") +
                  "): use a smaller --size, --depth or --bank-capacity");
  cl_int err = CL_SUCCESS;
  cl::Buffer b(rt.context(), CL_MEM_READ_WRITE, std::max<std::size_t>(bytes, 16), nullptr, &err);
  cl_check(err, (std::string("clCreateBuffer(") + what + ", " + std::to_string(bytes) + " bytes)").c_str());
  rt.count_allocation(bytes);
  return b;
}

void zero_buffer(ClRuntime& rt, const cl::Buffer& b, std::size_t bytes, const char* what) {
  // Static and never written: non-blocking writes may read it at any time.
  static const unsigned char zeros[1 << 16] = {};
  for (std::size_t at = 0; at < bytes; at += sizeof zeros) {
    const std::size_t chunk = std::min(sizeof zeros, bytes - at);
    cl_check(rt.queue().enqueueWriteBuffer(b, CL_FALSE, at, chunk, zeros),
             (std::string("clEnqueueWriteBuffer(") + what + ", zeros)").c_str());
  }
}

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

void DescriptorSet::write_raw(ClRuntime& rt, const unsigned char* bytes, std::size_t count, std::size_t at) const {
  if (count == 0) return;
  std::vector<cl_int> d(count);
  for (std::size_t i = 0; i < count; ++i) {
    HostDescriptor h;
    std::memcpy(&h, bytes + i * kBytes, kBytes);
    d[i] = desc_dest(h);
  }
  cl_check(rt.queue().enqueueWriteBuffer(records, CL_TRUE, at * kBytes, count * kBytes, bytes),
           "clEnqueueWriteBuffer(descriptors)");
  cl_check(rt.queue().enqueueWriteBuffer(dests, CL_TRUE, at * sizeof(cl_int), count * sizeof(cl_int), d.data()),
           "clEnqueueWriteBuffer(descriptor destinations)");
}

void DescriptorSet::write(ClRuntime& rt, const std::vector<HostDescriptor>& v, std::size_t at) const {
  write_raw(rt, reinterpret_cast<const unsigned char*>(v.data()), v.size(), at);
}

std::vector<HostDescriptor> DescriptorSet::read(ClRuntime& rt, std::size_t count, std::size_t at) const {
  std::vector<HostDescriptor> v(count);
  if (count)
    cl_check(rt.queue().enqueueReadBuffer(records, CL_TRUE, at * kBytes, count * kBytes, v.data()),
             "clEnqueueReadBuffer(descriptors)");
  return v;
}

void Launcher::run(cl::Kernel& k, const char* name, std::size_t global, std::size_t local, int round,
                   const std::vector<cl::Event>* wait) {
  if (local == 0) {
    // A fixed work-group size per kernel, from what the kernel allows: drivers
    // that compile per work-group size (PoCL) then compile each kernel once.
    std::size_t allowed = 0;
    cl_check(k.getWorkGroupInfo(rt_.device().device, CL_KERNEL_WORK_GROUP_SIZE, &allowed),
             "clGetKernelWorkGroupInfo(CL_KERNEL_WORK_GROUP_SIZE)");
    local = rt_.group_size();
    while (local > 1 && local > allowed) local /= 2;
  }
  global = round_up(std::max<std::size_t>(global, 1), local);
  cl::Event ev;
  cl_int err = rt_.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(global), cl::NDRange(local), wait,
                                                &ev);
  cl_check(err, (std::string("clEnqueueNDRangeKernel(") + name + ")").c_str());
  pending_.push_back({name, round, ev});
}

void Launcher::check(cl_int err, const char* what) {
  auto describe = [](const Pending& p) {
    return std::string(p.name) + (p.round >= 0 ? " (round " + std::to_string(p.round) + ")" : std::string());
  };
  for (std::size_t i = checked_; i < pending_.size(); ++i) {
    cl_int status = CL_COMPLETE;
    if (pending_[i].ev.getInfo(CL_EVENT_COMMAND_EXECUTION_STATUS, &status) != CL_SUCCESS) break;
    if (status < 0)
      throw ClError("kernel " + describe(pending_[i]) + " failed on the device: " + cl_error_name(status) + " (" +
                    std::to_string(status) + "), seen at " + what);
    if (status != CL_COMPLETE) break;  // in-order queue: nothing later has finished either
    checked_ = i + 1;
  }
  if (err != CL_SUCCESS)
    throw ClError(std::string(what) + ": " + cl_error_name(err) + " (" + std::to_string(err) + ")" +
                  (pending_.empty() ? std::string() : " after kernel " + describe(pending_.back())));
}

void Launcher::harvest() {
  check(CL_SUCCESS, "collecting kernel timings");
  // Launches still running (and, in an in-order queue, all after them) stay
  // pending for a later harvest.
  std::size_t done = 0;
  for (; done < pending_.size(); ++done) {
    const Pending& p = pending_[done];
    cl_int status = CL_COMPLETE;
    cl_check(p.ev.getInfo(CL_EVENT_COMMAND_EXECUTION_STATUS, &status), "clGetEventInfo(execution status)");
    if (status != CL_COMPLETE) break;
    cl_ulong t0 = 0, t1 = 0;
    if (p.ev.getProfilingInfo(CL_PROFILING_COMMAND_START, &t0) == CL_SUCCESS &&
        p.ev.getProfilingInfo(CL_PROFILING_COMMAND_END, &t1) == CL_SUCCESS)
      sink_.push_back({p.name, p.round, (t1 - t0) * 1e-9});
  }
  std::vector<Pending> running(pending_.begin() + done, pending_.end());
  pending_ = std::move(running);
  checked_ = 0;
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
  // At most 256: scatter.cl's work-group arrays hold 256 entries.
  wg_scan_ = queried_group_size(rt, scan_.kernel(), std::min<std::size_t>(rt.group_size(), 256));
  wg_plan_ = queried_group_size(rt, plan_.kernel(), std::min<std::size_t>(rt.group_size(), 256));
  bank_begin = device_buffer(rt, num_pes * sizeof(cl_int), "bank offsets");
  bank_count = device_buffer(rt, num_pes * sizeof(cl_int), "bank counts");
  pe_total = device_buffer(rt, num_pes * sizeof(cl_int), "scatter totals");
  overflow_base = device_buffer(rt, num_pes * sizeof(cl_int), "scatter overflow bases");
  counts = device_buffer(rt, 3 * sizeof(cl_int), "scatter counts");
  dummy_ = device_buffer(rt, sizeof(cl_int), "no SPMD outputs");
}

int ScatterPass::blocks(const Args& a) const {
  return (a.pool_len + kBlock - 1) / kBlock + a.out_groups;
}

void ScatterPass::plan(Launcher& launch, const Args& a, int round) {
  const int P = num_pes_;
  const int pool_blocks = (a.pool_len + kBlock - 1) / kBlock, nblocks = blocks(a);
  const std::size_t sources = std::size_t(a.pool_len) + std::size_t(a.out_groups) * a.group_size * a.spawn_slots;
  if (rank_cap_ < sources) {
    rank_cap_ = sources + sources / 2;
    rank_ = device_buffer(rt_, rank_cap_ * sizeof(cl_int), "scatter ranks");
  }
  if (hist_cap_ < std::size_t(nblocks) + 1) {
    hist_cap_ = nblocks + nblocks / 2 + 1;
    hist_ = device_buffer(rt_, hist_cap_ * P * sizeof(cl_int), "scatter block counts");
  }
  const std::size_t groups = std::size_t(a.slots) / a.group_size + P + 1;
  if (group_cap_ < groups) {
    group_cap_ = groups;
    group_pe = device_buffer(rt_, groups * sizeof(cl_int), "SPMD work-group PEs");
    group_first = device_buffer(rt_, groups * sizeof(cl_int), "SPMD work-group slots");
  }
  const cl::Buffer& out = a.outputs ? a.outputs->records : dummy_;
  const cl::Buffer& out_dest = a.outputs ? a.outputs->dests : dummy_;
  const cl::Buffer& out_count = a.out_item_count ? *a.out_item_count : dummy_;
  count_.bind(a.pool_len, pool_blocks, nblocks, a.group_size, a.spawn_slots, P, *a.pool, out, out_dest, out_count, hist_,
              rank_, by_block_ ? 0 : 1);
  launch.run(count_.kernel(), "scatter_count", std::max(nblocks, 1), 0, round);
  scan_.bind(nblocks, P, hist_, pe_total);
  // One work-group per PE on a GPU, one in all on a CPU (see scatter_scan).
  const std::size_t scan_groups = by_block_ ? 1 : std::size_t(P);
  launch.run(scan_.kernel(), "scatter_scan", scan_groups * wg_scan_, wg_scan_, round);
  const int cap = a.cap > 0 ? a.cap : a.slots;
  const int group_end = a.group_end < 0 ? P : a.group_end;
  plan_.bind(P, a.group_begin, group_end, a.slots, cap, a.group_size, pe_total, bank_begin, bank_count, overflow_base,
             group_pe, group_first, counts);
  launch.run(plan_.kernel(), "scatter_plan", wg_plan_, wg_plan_, round);
}

void ScatterPass::move(Launcher& launch, const Args& a, int round) {
  const int P = num_pes_;
  const int pool_blocks = (a.pool_len + kBlock - 1) / kBlock;
  if (by_block_) {
    const cl::Buffer& out = a.outputs ? a.outputs->records : dummy_;
    const cl::Buffer& out_dest = a.outputs ? a.outputs->dests : dummy_;
    const cl::Buffer& out_count = a.out_item_count ? *a.out_item_count : dummy_;
    move_blocks_.bind(a.pool_len, pool_blocks, blocks(a), a.group_size, a.spawn_slots, P, *a.pool, out, out_dest,
                      out_count, hist_, bank_begin, bank_count, overflow_base, *a.banks, *a.next_pool);
    if (blocks(a) > 0) launch.run(move_blocks_.kernel(), "scatter_move", std::size_t(blocks(a)), 0, round);
    return;
  }
  if (a.pool_len > 0) {
    move_pool_.bind(a.pool_len, P, *a.pool, rank_, hist_, bank_begin, bank_count, overflow_base, *a.banks,
                    *a.next_pool);
    launch.run(move_pool_.kernel(), "scatter_move", std::size_t(a.pool_len), 0, round);
  }
  if (a.out_groups > 0) {
    const int items = a.out_groups * a.group_size;
    move_out_.bind(items, a.group_size, a.spawn_slots, a.pool_len, pool_blocks, P, *a.outputs, *a.out_item_count, rank_,
                   hist_, bank_begin, bank_count, overflow_base, *a.banks, *a.next_pool);
    launch.run(move_out_.kernel(), "scatter_move", std::size_t(items), 0, round);
  }
}

}  // namespace opsila
