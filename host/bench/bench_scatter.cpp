// The scatter benchmark (the paper's figure 6): host scatter against the
// scatter kernels, beside the device's copy bandwidth for the same bytes.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>

#include "bench/bench.h"
#include "bench/bench_kernels.h"
#include "core/util.h"
#include "frame/host_scatter.h"
#include "device/kernel_args.h"
#include "scene/render_types.h"

namespace opsila {

namespace {

template <typename T>
void write_buffer(ClRuntime& rt, const cl::Buffer& b, const std::vector<T>& v, const char* what) {
  if (!v.empty())
    cl_check(rt.queue().enqueueWriteBuffer(b, CL_TRUE, 0, v.size() * sizeof(T), v.data()), what);
}

double event_seconds(const cl::Event& ev) {
  cl_ulong t0 = 0, t1 = 0;
  cl_check(ev.getProfilingInfo(CL_PROFILING_COMMAND_START, &t0), "clGetEventProfilingInfo(START)");
  cl_check(ev.getProfilingInfo(CL_PROFILING_COMMAND_END, &t1), "clGetEventProfilingInfo(END)");
  return (t1 - t0) * 1e-9;
}

// The timed runs' median and spread.
void settle(const std::vector<double>& times, double& seconds, Spread& spread) {
  seconds = median(times);
  spread = spread_of(times);
}

// A kernel's work-group size: what it allows, at most 64, a power of two.
std::size_t group_size_for(ClRuntime& rt, cl::Kernel& k) {
  std::size_t local = k.getWorkGroupInfo<CL_KERNEL_WORK_GROUP_SIZE>(rt.device().device);
  local = std::min<std::size_t>(local, 64);
  while (local & (local - 1)) local &= local - 1;
  return std::max<std::size_t>(local, 1);
}

// The scatter bench's descriptors are radiance rays of a frame this deep
// (random_descriptors: level 1, none ends its ray tree), so each PE's
// entries have one sort key and keep their source order.
constexpr int kBenchDepth = 5;

// I' as the exchange computes it, from the host scatter's plan: each
// source entry's place in [banks | next pool], or -1 for a hole.
std::vector<cl_int> placement_index(const HostDescriptors& src, const HostScatterResult& plan, int pes,
                                    std::size_t bank_slots) {
  std::vector<std::size_t> rank(pes, 0), base(pes, 0), demand(pes, 0);
  for (const HostDescriptor& d : src)
    if (desc_dest(d) >= 0 && desc_dest(d) < pes) ++demand[desc_dest(d)];
  for (int q = 1; q < pes; ++q) base[q] = base[q - 1] + (demand[q - 1] - plan.bank_count[q - 1]);
  std::vector<cl_int> index(src.size(), -1);
  for (std::size_t i = 0; i < src.size(); ++i) {
    const int q = desc_dest(src[i]);
    if (q < 0 || q >= pes) continue;
    const std::size_t r = rank[q]++, fits = plan.bank_count[q];
    index[i] = static_cast<cl_int>(r < fits ? plan.bank_begin[q] + r : bank_slots + base[q] + (r - fits));
  }
  return index;
}

// The paper's primitive alone, Vd(I'(i)) = Vs(i) with I' given, on its six
// vectors and on one 64-byte record: the layouts compared on the same bytes.
void measure_paper_scatter(ClRuntime& rt, const HostDescriptors& src, const std::vector<cl_int>& index,
                           std::size_t dest_len, int warmup, ScatterPoint& pt) {
  const std::size_t n = src.size();
  SixVectorsArgs six_args;
  six_args.count = static_cast<int>(n);
  six_args.index.buffer = upload(rt, index, "paper scatter index");
  const std::size_t field_bytes[6] = {sizeof(cl_int2), sizeof(cl_int), sizeof(cl_float4),
                                      sizeof(cl_float4), sizeof(cl_float4), sizeof(cl_int)};
  for (std::size_t f = 0; f < 6; ++f) {
    const std::size_t bytes = field_bytes[f];
    six_args.from.v[f] = device_buffer(rt, std::max<std::size_t>(n, 1) * bytes, "paper scatter source");
    six_args.to.v[f] = device_buffer(rt, std::max<std::size_t>(dest_len, 1) * bytes, "paper scatter destination");
    zero_buffer(rt, six_args.from.v[f], std::max<std::size_t>(n, 1) * bytes, "paper scatter source");
  }
  DescriptorSet rec_from, rec_to;
  rec_from.allocate(rt, n, "paper scatter records");
  rec_to.allocate(rt, dest_len, "paper scatter records");
  rec_from.write(rt, src, 0, kBenchDepth);
  OneRecordArgs one_args;
  one_args.count = six_args.count;
  one_args.index = six_args.index;
  one_args.from = rec_from.records;
  one_args.to = rec_to.records;
  KernelBinding<SixVectorsArgs> six_vectors(rt, "scatter_six_vectors", KernelProgram::baselines);
  KernelBinding<OneRecordArgs> one_record(rt, "scatter_one_record", KernelProgram::baselines);
  cl::Kernel& six = six_vectors.bind(six_args);
  cl::Kernel& one = one_record.bind(one_args);
  std::vector<double> t6, t1;
  for (int r = 0; r < warmup + pt.repeats; ++r) {
    cl::Event e6, e1;
    const std::size_t l6 = group_size_for(rt, six), l1 = group_size_for(rt, one);
    const std::size_t g = std::max<std::size_t>(n, 1);
    cl_check(rt.queue().enqueueNDRangeKernel(six, cl::NullRange, cl::NDRange(round_up(g, l6)), cl::NDRange(l6), nullptr,
                                             &e6),
             "clEnqueueNDRangeKernel(scatter_six_vectors)");
    cl_check(rt.queue().enqueueNDRangeKernel(one, cl::NullRange, cl::NDRange(round_up(g, l1)), cl::NDRange(l1), nullptr,
                                             &e1),
             "clEnqueueNDRangeKernel(scatter_one_record)");
    cl_check(rt.queue().finish(), "clFinish(paper scatter)");
    if (r >= warmup) t6.push_back(event_seconds(e6)), t1.push_back(event_seconds(e1));
  }
  settle(t6, pt.six_vectors_seconds, pt.six_vectors_spread);
  settle(t1, pt.one_record_seconds, pt.one_record_spread);
}

// Host: the same counting sort, plainly (one thread, steady_clock).
HostScatterResult measure_host_scatter(const HostDescriptors& src, int pes, int slots, int group_size,
                                       std::size_t bank_slots, int warmup, ScatterPoint& pt) {
  HostScatterResult host_result;
  HostDescriptors banks(bank_slots), next(src.size());
  std::vector<std::size_t> scratch;
  std::vector<double> times;
  for (int r = 0; r < warmup + pt.repeats; ++r) {
    auto t0 = std::chrono::steady_clock::now();
    host_result = host_scatter(src, pes, slots, 0, group_size, kBenchDepth, false, banks, next, scratch);
    double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (r >= warmup) times.push_back(s);
  }
  pt.host_seconds = median(times);
  pt.host_spread = spread_of(times);
  pt.moved = host_result.placed + host_result.waiting;
  pt.waiting = host_result.waiting;
  return host_result;
}

// Device: the renderer's ScatterPass on the same input (pool only), checked
// against the host's counts.
void measure_device_scatter(ClRuntime& rt, const HostDescriptors& src, int pes, int slots, int group_size,
                            std::size_t bank_slots, int warmup, const HostScatterResult& host_result,
                            ScatterPoint& pt) {
  const std::size_t length = src.size();
  cl::CommandQueue& q = rt.queue();
  DescriptorSet pool, banks, next;
  pool.allocate(rt, length, "scatter bench source");
  banks.allocate(rt, bank_slots, "scatter bench banks");
  next.allocate(rt, length, "scatter bench next pool");
  pool.write(rt, src, 0, kBenchDepth);
  ScatterPass scatter(rt, pes);
  const ScatterPass::Args a = ScatterPass::pool_only(pool, length, banks, next, slots, group_size);
  std::vector<double> totals;
  std::vector<std::vector<LaunchRecord>> runs;
  for (int r = 0; r < warmup + pt.repeats; ++r) {
    std::vector<LaunchRecord> records;
    Launcher launch(rt, records);
    scatter.plan(launch, a, 0);
    scatter.move(launch, a, 0);
    launch.check(q.finish(), "clFinish(scatter bench)");
    launch.harvest();
    if (r < warmup) continue;
    double sum = 0;
    for (const LaunchRecord& rec : records) sum += rec.seconds;
    totals.push_back(sum);
    runs.push_back(std::move(records));
  }
  pt.kernel_seconds = median(totals);
  pt.kernel_spread = spread_of(totals);
  // Per-kernel split of the run closest to the median.
  std::size_t best = 0;
  for (std::size_t i = 1; i < totals.size(); ++i)
    if (std::abs(totals[i] - pt.kernel_seconds) < std::abs(totals[best] - pt.kernel_seconds)) best = i;
  for (const LaunchRecord& rec : runs[best]) {
    if (rec.name == "scatter_count") pt.count_seconds += rec.seconds;
    if (rec.name == "scatter_plan") pt.plan_seconds += rec.seconds;
    if (rec.name == "scatter_move") pt.move_seconds += rec.seconds;
  }
  cl_int counts[3] = {0, 0, 0};
  std::vector<cl_int> bank_count(pes);
  cl_check(q.enqueueReadBuffer(scatter.counts, CL_TRUE, 0, sizeof(counts), counts), "clEnqueueReadBuffer(counts)");
  cl_check(q.enqueueReadBuffer(scatter.bank_ranges.count, CL_TRUE, 0, pes * sizeof(cl_int), bank_count.data()),
           "clEnqueueReadBuffer(bank counts)");
  pt.verified = bank_count == host_result.bank_count && std::size_t(counts[0]) == host_result.waiting &&
                std::size_t(counts[1]) == host_result.placed && counts[2] == host_result.groups;
}

// The physical ceiling: a plain copy of the same bytes, as a kernel and
// as clEnqueueCopyBuffer.
void measure_copy_ceiling(ClRuntime& rt, int warmup, ScatterPoint& pt) {
  cl::CommandQueue& q = rt.queue();
  const std::size_t bytes = std::max<std::size_t>(pt.moved, 1) * DescriptorSet::kBytes;
  const std::size_t n4 = (bytes + sizeof(cl_float4) - 1) / sizeof(cl_float4);
  CopyArgs a;
  a.from = device_buffer(rt, n4 * sizeof(cl_float4), "copy bench source");
  a.to = device_buffer(rt, n4 * sizeof(cl_float4), "copy bench destination");
  a.count = static_cast<int>(n4);
  zero_buffer(rt, a.from, n4 * sizeof(cl_float4), "copy bench source");
  zero_buffer(rt, a.to, n4 * sizeof(cl_float4), "copy bench destination");
  KernelBinding<CopyArgs> copy_float4(rt, "copy_float4", KernelProgram::baselines);
  cl::Kernel& copy = copy_float4.bind(a);
  const std::size_t local = group_size_for(rt, copy);
  std::vector<double> kt, bt;
  for (int r = 0; r < warmup + pt.repeats; ++r) {
    cl::Event ek, eb;
    cl_check(
        q.enqueueNDRangeKernel(copy, cl::NullRange, cl::NDRange(round_up(n4, 64)), cl::NDRange(local), nullptr, &ek),
        "clEnqueueNDRangeKernel(copy_float4)");
    cl_check(q.enqueueCopyBuffer(a.from, a.to, 0, 0, n4 * sizeof(cl_float4), nullptr, &eb), "clEnqueueCopyBuffer");
    cl_check(q.finish(), "clFinish(copy bench)");
    if (r >= warmup) kt.push_back(event_seconds(ek)), bt.push_back(event_seconds(eb));
  }
  settle(kt, pt.copy_kernel_seconds, pt.copy_kernel_spread);
  settle(bt, pt.copy_buffer_seconds, pt.copy_buffer_spread);
}

}  // namespace

namespace {

// Bank slots roomy enough that uniform destinations almost never overflow.
constexpr int kBenchGroupSize = 16;  // the SPMD work-group size on a CPU
int bank_share(std::size_t length, int pes) {
  const std::size_t per_pe = (length + pes - 1) / pes;
  return static_cast<int>(per_pe + per_pe / 10 + 16);
}
std::size_t bank_slots_of(std::size_t length, int pes) {
  return std::size_t(pes) * bank_share(length, pes) + std::size_t(pes) * kBenchGroupSize;
}

}  // namespace

ScatterFootprint scatter_footprint(std::size_t length, int pes) {
  const std::size_t dest = bank_slots_of(length, pes) + length;
  ScatterFootprint f;
  f.largest = dest * DescriptorSet::kBytes;
  // Records and destination streams (68 bytes) and the six vectors (56) of
  // source and destination, and the index.
  f.total = (length + dest) * (DescriptorSet::kBytes + sizeof(cl_int) + 56) + length * sizeof(cl_int);
  return f;
}

ScatterPoint measure_scatter(ClRuntime& rt, std::size_t length, int pes, int warmup, int repeats,
                             double hole_rate) {
  ScatterPoint pt;
  pt.length = length;
  pt.pes = pes;
  pt.repeats = std::max(1, repeats);
  pt.n = bank_share(length, pes);
  const int slots = pes * pt.n, group_size = kBenchGroupSize;
  const std::size_t bank_slots = bank_slots_of(length, pes);

  const HostDescriptors src = random_descriptors(length, pes, hole_rate, 1987u + static_cast<unsigned>(length));
  const HostScatterResult host_result =
      measure_host_scatter(src, pes, slots, group_size, bank_slots, warmup, pt);
  measure_device_scatter(rt, src, pes, slots, group_size, bank_slots, warmup, host_result, pt);
  measure_paper_scatter(rt, src, placement_index(src, host_result, pes, bank_slots), bank_slots + length, warmup,
                        pt);
  measure_copy_ceiling(rt, warmup, pt);
  return pt;
}

}  // namespace opsila
