// What a frame reads back: the image, the counters, the progress line
// and, with several ranks, this rank's report.
#include "frame/frame.h"

#include <algorithm>
#include <optional>

#include "core/fixed_point.h"
#include "core/parallel.h"
#include "core/progress.h"
#include "device/counters.h"
#include "frame/stats.h"

namespace opsila {

// A device buffer mapped for reading. On a CPU device (PoCL) the mapping is
// the buffer's own memory: the image is decoded straight from it, with no
// staging copy whose fresh pages cost more than the copy itself
// (docs/BENCHMARKS.md, "Levers"); elsewhere the driver makes one transfer,
// as a read would. Unmapped when done (checked) or, on an error, when dropped.
class MappedRead {
 public:
  MappedRead(Launcher& launch, cl::CommandQueue& q, const cl::Buffer& b, std::size_t bytes, const char* what)
      : q_(q), b_(b) {
    cl_int err = CL_SUCCESS;
    p_ = q.enqueueMapBuffer(b, CL_TRUE, CL_MAP_READ, 0, bytes, nullptr, nullptr, &err);
    launch.check(err, what);
  }
  ~MappedRead() {
    if (p_) q_.enqueueUnmapMemObject(b_, p_);
  }
  MappedRead(const MappedRead&) = delete;
  MappedRead& operator=(const MappedRead&) = delete;
  template <class T>
  const T* data() const {
    return static_cast<const T*>(p_);
  }
  void unmap(Launcher& launch, const char* what) {
    void* p = p_;
    p_ = nullptr;
    launch.check(q_.enqueueUnmapMemObject(b_, p), what);
  }

 private:
  cl::CommandQueue& q_;
  cl::Buffer b_;
  void* p_ = nullptr;
};

static_assert(OPSILA_ACCUM_WORDS == 3 * OPSILA_COUNTER_WORDS, "pixel sums: three (low, high) word pairs a pixel");

// Read back the pixel sums (fixed point: the sum of the N samples, decoded
// here into their mean) and, when the frame gives it, the item buffer.
void Renderer::Machine::read_image(Launcher& launch, RenderResult& result) {
  if (device_resolve) return read_resolved(launch, result);
  cl::CommandQueue& q = rt.queue();
  const std::size_t values = npix * 3;
  const std::size_t pixel_bytes = OPSILA_ACCUM_WORDS * sizeof(cl_uint);
  // One device alone reads only the rows of the traced rectangle: the
  // decode below reads no other sum.
  const bool rect_only = group.all();
  const bool traced = traced_rect.s[0] <= traced_rect.s[2] && traced_rect.s[1] <= traced_rect.s[3];
  const std::size_t row0 = rect_only ? (traced ? std::size_t(traced_rect.s[1]) : 0) : 0;
  const std::size_t rows = rect_only ? (traced ? std::size_t(traced_rect.s[3]) + 1 - row0 : 0) : std::size_t(height);
  std::optional<MappedRead> accum;
  const cl_uint* words = nullptr;  // the sums of pixel (row0, 0) onward
  if (pinned_readback) {
    accum_host.reserve(rt, npix * pixel_bytes, "pixel sums, host copy");
    if (rows > 0)
      launch.check(q.enqueueReadBuffer(b_accum, CL_TRUE, row0 * width * pixel_bytes, rows * width * pixel_bytes,
                                       accum_host.data()),
                   "clEnqueueReadBuffer(pixel sums)");
    words = static_cast<const cl_uint*>(accum_host.data());
  } else {
    accum.emplace(launch, q, b_accum, npix * pixel_bytes, "clEnqueueMapBuffer(pixel sums)");
    words = accum->data<cl_uint>() + row0 * width * OPSILA_ACCUM_WORDS;
  }
  read_items(launch, result);
  const std::size_t first = row0 * width * 3;  // the first value `words` holds
  auto sum = [words, first](std::size_t i) { return join_words(words[2 * (i - first)], words[2 * (i - first) + 1]); };
  const MeanDecoder mean(spp);
  result.rgb.resize(values);
  // Rows on the host's threads, each writing only its own pixels: on one
  // core the decode of a 1920x1080 image takes about as long as a GPU's
  // whole frame (docs/BENCHMARKS.md, "On a GPU").
  constexpr std::size_t kDecodeGrain = std::size_t(1) << 16;  // values a thread, at least
  if (group.all()) {
    // Outside the traced rectangle every pass missed and nothing wrote the
    // sums: the background's, as count_hits would have left them.
    float background[3];
    for (int c = 0; c < 3; ++c) background[c] = mean(owned_sum(to_fixed(fp.background[c]), spp));
    const int x0 = traced_rect.s[0], x1 = traced_rect.s[2], y0 = traced_rect.s[1], y1 = traced_rect.s[3];
    parallel_ranges(std::size_t(height), kDecodeGrain / (3 * std::size_t(width)) + 1, [&](std::size_t r0,
                                                                                           std::size_t r1) {
      for (std::size_t y = r0; y < r1; ++y) {
        const bool row = int(y) >= y0 && int(y) <= y1 && x0 <= x1;
        const std::size_t begin = y * width;
        const std::size_t in0 = begin + (row ? x0 : width), in1 = begin + (row ? x1 + 1 : width);
        for (std::size_t p = begin; p < in0; ++p)
          for (int c = 0; c < 3; ++c) result.rgb[3 * p + c] = background[c];
        for (std::size_t i = 3 * in0; i < 3 * in1; ++i) result.rgb[i] = mean(sum(i));
        for (std::size_t p = in1; p < begin + width; ++p)
          for (int c = 0; c < 3; ++c) result.rgb[3 * p + c] = background[c];
      }
    });
    if (accum) accum->unmap(launch, "clEnqueueUnmapMemObject(pixel sums)");
  } else {
    // 64-bit integer sums, summed over the ranks on rank 0.
    std::vector<std::uint64_t> sums(values);
    for (std::size_t i = 0; i < values; ++i) sums[i] = sum(i);
    if (accum) accum->unmap(launch, "clEnqueueUnmapMemObject(pixel sums)");
    reduce_to_root(ranks, sums);
    parallel_ranges(values, kDecodeGrain, [&](std::size_t i0, std::size_t i1) {
      for (std::size_t i = i0; i < i1; ++i) result.rgb[i] = mean(sums[i]);
    });
  }
  launch.check(q.finish(), "clFinish");
}

// The item buffer, when the frame gives it (--item-buffer).
void Renderer::Machine::read_items(Launcher& launch, RenderResult& result) {
  if (!item_output) {
    result.item_buffer.clear();
    return;
  }
  MappedRead items(launch, rt.queue(), item.items, npix * sizeof(cl_int2), "clEnqueueMapBuffer(item buffer)");
  const cl_int* item = items.data<cl_int>();
  result.item_buffer.assign(item, item + npix * 2);
  items.unmap(launch, "clEnqueueUnmapMemObject(item buffer)");
}

// The image resolved on the device (kernels/resolve.cl): the floats
// read_image's decode would give, read into pinned memory, then copied
// into the result on the host's threads.
void Renderer::Machine::read_resolved(Launcher& launch, RenderResult& result) {
  const std::size_t values = npix * 3;
  frame_kernels::ResolveArgs a;
  a.accum = b_accum;
  a.npix = static_cast<int>(npix);
  a.width = width;
  a.traced = traced_rect;
  for (int c = 0; c < 3; ++c) a.background.s[c] = owned_sum(to_fixed(fp.background[c]), spp);
  const MeanDecoder mean(spp);
  mean.kernel_constants(a.divisor, a.inverse, a.exact);
  a.rgb = b_image;
  // A few work-groups a compute unit, each work-item over many pixels
  // (kernels/resolve.cl).
  cl_int err = CL_SUCCESS;
  const cl_uint units = rt.device().device.getInfo<CL_DEVICE_MAX_COMPUTE_UNITS>(&err);
  launch.check(err, "clGetDeviceInfo(CL_DEVICE_MAX_COMPUTE_UNITS)");
  const std::size_t grid = std::size_t(std::max<cl_uint>(units, 1)) * 8 * rt.group_size();
  launch.run(kernels().resolve.bind(a), "resolve_image", std::min(grid, npix), 0, -1);
  accum_host.reserve(rt, values * sizeof(float), "image, host copy");
  launch.check(rt.queue().enqueueReadBuffer(b_image, CL_TRUE, 0, values * sizeof(float), accum_host.data()),
               "clEnqueueReadBuffer(image)");
  read_items(launch, result);
  const float* rgb = static_cast<const float*>(accum_host.data());
  result.rgb.resize(values);
  parallel_ranges(values, std::size_t(1) << 18, [&](std::size_t i0, std::size_t i1) {
    std::copy(rgb + i0, rgb + i1, result.rgb.begin() + std::ptrdiff_t(i0));
  });
  launch.check(rt.queue().finish(), "clFinish");
}

// Per-level, per-PE counters and traffic, then the frame's totals. Every
// primary ray is cast by the item buffer; descriptors are spawned as primary
// hits, children and shadow rays, and finish as shaded hits, misses,
// occluded or lit shadow rays.
void Renderer::Machine::read_stats(RenderResult& result) {
  RenderStats& st = result.stats;
  const std::size_t ncounters = std::size_t(depth) * P * OPSILA_STAT_COUNT;
  std::vector<std::uint64_t> counters = read_counters(rt, b_stats, ncounters, "stats");
  std::vector<std::uint64_t> traffic;
  if (traffic_levels > 0) traffic = read_counters(rt, b_traffic, ntraffic, "traffic");
  counters.push_back(read_counters(rt, b_hits, 1, "primary hit count")[0]);
  // Each rank counted its own PEs and primaries: summed on rank 0.
  if (!group.all()) {
    reduce_to_root(ranks, counters);
    reduce_to_root(ranks, traffic);
  }
  const std::uint64_t primary_hits = counters.back();
  counters.pop_back();
  st.counters.assign(depth, std::vector<std::vector<std::uint64_t>>(P));
  for (int l = 0; l < depth; ++l)
    for (int p = 0; p < P; ++p) {
      const auto at = counters.begin() + std::ptrdiff_t((std::size_t(l) * P + p) * OPSILA_STAT_COUNT);
      st.counters[l][p].assign(at, at + OPSILA_STAT_COUNT);
    }
  if (traffic_levels > 0) {
    st.traffic.assign(traffic_levels, std::vector<std::uint64_t>(std::size_t(P) * P));
    for (int l = 0; l < traffic_levels; ++l)
      for (std::size_t k = 0; k < std::size_t(P) * P; ++k) st.traffic[l][k] = traffic[std::size_t(l) * P * P + k];
  }
  result.rays.primary = npix * std::size_t(spp);
  result.rays.primary_hits = primary_hits;
  std::uint64_t children = 0, shadow = 0, forwards = 0;
  for (std::size_t at = 0; at < counters.size(); at += OPSILA_STAT_COUNT) {
    children += counters[at + OPSILA_STAT_SPAWN_RADIANCE];
    shadow += counters[at + OPSILA_STAT_SPAWN_SHADOW];
    forwards += counters[at + OPSILA_STAT_FORWARD];
  }
  const CounterSums sums = counter_sums(counters);
  result.rays.secondary = children;
  result.rays.shadow = shadow;
  st.descriptors_spawned = primary_hits + sums.spawned;
  st.descriptors_finished = sums.finished;
  st.forwards = forwards;
}

// Progress (only when a line is due): a lower bound of the samples whose ray
// trees are finished, out of all samples: samples injected, less one per
// descriptor still in flight (spawned - finished, from the counters).
void Renderer::Machine::report_progress(const Frame& f) {
  const std::vector<std::uint64_t> counters =
      read_counters(rt, b_stats, std::size_t(depth) * P * OPSILA_STAT_COUNT, "stats");
  const std::uint64_t primary_hits = read_counters(rt, b_hits, 1, "primary hit count")[0];
  const CounterSums sums = counter_sums(counters);
  const std::uint64_t spawned = primary_hits + sums.spawned, finished = sums.finished;
  // A miss is done when its pass's hit list is made.
  const std::uint64_t injected = std::uint64_t(f.sample) * npix + (npix - f.listed) + f.next_hit;
  const std::uint64_t in_flight = spawned > finished ? spawned - finished : 0;
  const double done = injected > in_flight ? double(injected - in_flight) : 0.0;
  const std::uint64_t rays = injected + sums.spawned;
  progress->report(done / (double(npix) * spp), rays);
}

// This rank's share of the frame, for rank 0's --stats and the bench.
RankReport Renderer::Machine::rank_report(const RenderStats& st, double seconds, double mpi_seconds) const {
  RankReport r;
  r.rank = group.rank;
  r.pe_begin = group.begin;
  r.pe_end = group.end;
  r.host = ranks.host();
  r.device = rt.description();
  r.device_bytes = plan.total();
  r.scene_bytes = plan.scene;
  r.host_peak_bytes = host_peak_bytes();
  r.render_seconds = seconds;
  r.mpi_seconds = mpi_seconds;
  const RankExchange& x = *rank_exchange;
  std::vector<double> spmd(x.mpi_seconds.size(), 0.0);
  for (const LaunchRecord& l : st.launches) {
    auto it = std::find_if(r.kernel_seconds.begin(), r.kernel_seconds.end(),
                           [&](const auto& e) { return e.first == l.name; });
    if (it == r.kernel_seconds.end()) it = r.kernel_seconds.insert(it, {l.name, 0.0});
    it->second += l.seconds;
    // Rounds past the exchange's cap share its last row (keep_round).
    if (l.name == "spmd_phase" && l.round >= 0 && !spmd.empty())
      spmd[std::min(std::size_t(l.round), spmd.size() - 1)] += l.seconds;
  }
  // The MPI part runs while the device runs the SPMD phase; the staging
  // (reading back, writing the received records) overlaps nothing.
  for (std::size_t k = 0; k < spmd.size(); ++k) {
    r.exchange_seconds += x.staging_seconds[k] + x.mpi_seconds[k];
    r.exposed_seconds += x.staging_seconds[k] + std::max(0.0, x.mpi_seconds[k] - spmd[k]);
  }
  r.sent = x.sent;
  r.received = x.received;
  r.share = share;
  return r;
}

}  // namespace opsila
