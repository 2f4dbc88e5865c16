#include "machine/descriptors.h"

#include "machine/renderer.h"

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
  org = device_buffer(rt, n * sizeof(cl_float4), what);
  dir = device_buffer(rt, n * sizeof(cl_float4), what);
  wgt = device_buffer(rt, n * sizeof(cl_float4), what);
  ids = device_buffer(rt, n * sizeof(cl_int4), what);
  dest = device_buffer(rt, n * sizeof(cl_int), what);
  capacity = n;
}

int DescriptorSet::set_args(cl::Kernel& k, int at) const {
  cl_check(k.setArg(at++, org), "clSetKernelArg(org)");
  cl_check(k.setArg(at++, dir), "clSetKernelArg(dir)");
  cl_check(k.setArg(at++, wgt), "clSetKernelArg(wgt)");
  cl_check(k.setArg(at++, ids), "clSetKernelArg(ids)");
  cl_check(k.setArg(at++, dest), "clSetKernelArg(dest)");
  return at;
}

void DescriptorSet::copy_prefix_to(ClRuntime& rt, DescriptorSet& to, std::size_t count) const {
  if (count == 0) return;
  auto& q = rt.queue();
  cl_check(q.enqueueCopyBuffer(org, to.org, 0, 0, count * sizeof(cl_float4)), "clEnqueueCopyBuffer(queue org)");
  cl_check(q.enqueueCopyBuffer(dir, to.dir, 0, 0, count * sizeof(cl_float4)), "clEnqueueCopyBuffer(queue dir)");
  cl_check(q.enqueueCopyBuffer(wgt, to.wgt, 0, 0, count * sizeof(cl_float4)), "clEnqueueCopyBuffer(queue wgt)");
  cl_check(q.enqueueCopyBuffer(ids, to.ids, 0, 0, count * sizeof(cl_int4)), "clEnqueueCopyBuffer(queue ids)");
  cl_check(q.enqueueCopyBuffer(dest, to.dest, 0, 0, count * sizeof(cl_int)), "clEnqueueCopyBuffer(queue dest)");
}

void Launcher::run(cl::Kernel& k, const char* name, std::size_t global, std::size_t local, int round,
                   const std::vector<cl::Event>* wait) {
  if (local == 0) {
    // A fixed work-group size per kernel, from what the kernel allows: drivers
    // that compile per work-group size (PoCL) then compile each kernel once.
    std::size_t allowed = 0;
    cl_check(k.getWorkGroupInfo(rt_.device().device, CL_KERNEL_WORK_GROUP_SIZE, &allowed),
             "clGetKernelWorkGroupInfo(CL_KERNEL_WORK_GROUP_SIZE)");
    local = 64;
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
  for (auto& p : pending_) {
    cl_ulong t0 = 0, t1 = 0;
    if (p.ev.getProfilingInfo(CL_PROFILING_COMMAND_START, &t0) == CL_SUCCESS &&
        p.ev.getProfilingInfo(CL_PROFILING_COMMAND_END, &t1) == CL_SUCCESS)
      sink_.push_back({p.name, p.round, (t1 - t0) * 1e-9});
  }
  pending_.clear();
  checked_ = 0;
}

ScatterPass::ScatterPass(ClRuntime& rt, int num_pes) : rt_(rt), num_pes_(num_pes) {
  count_ = rt.kernel("scatter_count");
  scan_ = rt.kernel("scatter_scan");
  plan_ = rt.kernel("scatter_plan");
  move_ = rt.kernel("scatter_move");
  bank_count = device_buffer(rt, num_pes * sizeof(cl_int), "bank counts");
  pe_total = device_buffer(rt, num_pes * sizeof(cl_int), "scatter totals");
  overflow_base = device_buffer(rt, num_pes * sizeof(cl_int), "scatter overflow bases");
  counts = device_buffer(rt, 2 * sizeof(cl_int), "scatter counts");
}

void ScatterPass::enqueue(Launcher& launch, const Args& a, int round) {
  const std::size_t total = std::size_t(a.out_len) + a.queue_len;
  const int P = num_pes_;
  if (rank_cap_ < total) {
    rank_cap_ = total + total / 2;
    rank_ = device_buffer(rt_, rank_cap_ * sizeof(cl_int), "scatter ranks");
    hist_ = device_buffer(rt_, ((rank_cap_ + kBlock - 1) / kBlock) * P * sizeof(cl_int), "scatter block counts");
  }
  const std::size_t blocks = (total + kBlock - 1) / kBlock;
  const cl::Buffer& traffic = a.traffic ? *a.traffic : counts;
  int i = 0;
  count_.setArg(i++, a.out_len);
  count_.setArg(i++, a.queue_len);
  count_.setArg(i++, a.n);
  count_.setArg(i++, a.spawn_slots);
  count_.setArg(i++, P);
  count_.setArg(i++, *a.processed);
  count_.setArg(i++, a.outputs->dest);
  count_.setArg(i++, a.queue->dest);
  count_.setArg(i++, hist_);
  count_.setArg(i++, rank_);
  launch.run(count_, "scatter_count", round_up(std::max<std::size_t>(blocks, 1), 16), 0, round);
  i = 0;
  scan_.setArg(i++, static_cast<int>(blocks));
  scan_.setArg(i++, P);
  scan_.setArg(i++, hist_);
  scan_.setArg(i++, pe_total);
  launch.run(scan_, "scatter_scan", round_up(P, 16), 0, round);
  i = 0;
  plan_.setArg(i++, P);
  plan_.setArg(i++, a.n);
  plan_.setArg(i++, pe_total);
  plan_.setArg(i++, bank_count);
  plan_.setArg(i++, overflow_base);
  plan_.setArg(i++, counts);
  launch.run(plan_, "scatter_plan", 1, 1, round);
  i = 0;
  // One move launch per source segment: outputs (entries 0..out_len), then
  // the queue (entries out_len..total).
  const DescriptorSet* segment[2] = {a.outputs, a.queue};
  const int length[2] = {a.out_len, a.queue_len}, offset[2] = {0, a.out_len};
  for (int s = 0; s < 2; ++s) {
    if (length[s] == 0) continue;
    i = 0;
    move_.setArg(i++, length[s]);
    move_.setArg(i++, offset[s]);
    move_.setArg(i++, a.n);
    move_.setArg(i++, a.spawn_slots);
    move_.setArg(i++, P);
    move_.setArg(i++, s == 0 ? 1 : 0);
    i = segment[s]->set_args(move_, i);
    move_.setArg(i++, rank_);
    move_.setArg(i++, hist_);
    move_.setArg(i++, overflow_base);
    i = a.banks->set_args(move_, i);
    i = a.next_queue->set_args(move_, i);
    move_.setArg(i++, traffic);
    move_.setArg(i++, a.traffic ? a.traffic_levels : 0);
    launch.run(move_, "scatter_move", std::size_t(length[s]), 0, round);
  }
}

}  // namespace opsila
