// The replicated-scene megakernel baseline (host side of
// kernels/baselines/megakernel.cl), and the traversal alone over its rays
// (kernels/baselines/traversal.cl).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <tuple>

#include "bench/bench.h"
#include "scene/camera.h"
#include "core/fixed_point.h"
#include "core/parallel.h"
#include "opsila_shared.h"
#include "partition/bank_bvh.h"
#include "partition/bank_qnode.h"
#include "partition/partition.h"
#include "bench/bench_kernels.h"
#include "bench/ray_file.h"
#include "device/counters.h"
#include "device/kernel_args.h"
#include "frame/renderer.h"

namespace opsila {

namespace {

using Buf = cl::Buffer;
using MegaKernel = KernelBinding<MegaArgs>;
using MegaRaysKernel = KernelBinding<MegaRaysArgs>;

// The whole scene on one PE: bank 0 under one BVH (clusters on top).
struct MegaScene {
  BankedScene bs;
  FrameParams fp{};
  SceneRoot root;
  double build_seconds = 0;
};

MegaScene mega_scene(const Scene& scene) {
  auto t_build = std::chrono::steady_clock::now();
  MegaScene m;
  m.bs = partition_scene(scene, 1);
  m.fp = frame_params(scene, m.bs, 0);
  m.root.node = m.bs.pes[0].node_begin;
  m.root.instances = m.bs.pes[0].instance_root;
  Box box;
  if (children_box(m.bs.nodes[std::size_t(m.root.node)], box))
    for (int a = 0; a < 3; ++a) m.root.lo.s[a] = box.lo[a], m.root.hi.s[a] = box.hi[a];
  m.build_seconds = seconds_since(t_build);
  return m;
}

// The megakernel's inputs and outputs on the device.
struct MegaBuffers {
  BankGeometry geometry;
  ShadingTables shading;
  SampleOffsets offsets;
  MegaPixelSums accum;
  MegaRayCounts counts;
  MegaItems items;
};

MegaBuffers mega_buffers(ClRuntime& rt, const Scene& scene, const BankedScene& bs) {
  const std::size_t npix = std::size_t(scene.width) * scene.height;
  MegaBuffers b;
  b.geometry.tris.buffer = upload(rt, bs.triangles, "facets");
  b.geometry.nodes.buffer =
      rt.quantised_nodes() ? upload(rt, quantise_nodes(bs.nodes), "BVH nodes") : upload(rt, bs.nodes, "BVH nodes");
  b.geometry.insts.buffer = upload(rt, bs.instances.empty() ? std::vector<Instance>(1) : bs.instances, "instances");
  b.shading.materials.buffer = upload(rt, bs.materials, "materials");
  std::vector<Light> lights = bs.lights;
  if (lights.empty()) lights.push_back(Light{});
  b.shading.lights.buffer = upload(rt, lights, "lights");
  b.shading.surface = upload_surface(rt, bs);
  b.accum.buffer = device_buffer(rt, npix * 3 * sizeof(cl_long), "pixel sums");
  b.counts.buffer = device_buffer(rt, npix * sizeof(cl_uint4), "ray counts");
  b.items.buffer = device_buffer(rt, npix * sizeof(cl_int2), "item buffer");
  b.offsets.buffer = upload(rt, sample_offsets(scene.spp), "sample offsets");
  return b;
}

// A megakernel launch's arguments, all but its pixels.
MegaArgs mega_args(const MegaScene& ms, const MegaBuffers& b, int spp_k, bool items) {
  MegaArgs a;
  a.fp = ms.fp;
  a.geometry = b.geometry;
  a.shading = b.shading;
  a.root = ms.root;
  a.spp_k = spp_k;
  a.offsets = b.offsets;
  a.accum = b.accum;
  a.counts = b.counts;
  a.write_items = items ? 1 : 0;
  a.items = b.items;
  return a;
}

// One fixed work-group size, so a driver that specialises kernels per size
// (PoCL) compiles each kernel once: a power of two up to 64, dividing the
// rounded global size.
std::size_t fixed_local(ClRuntime& rt, cl::Kernel& k) {
  std::size_t local = k.getWorkGroupInfo<CL_KERNEL_WORK_GROUP_SIZE>(rt.device().device);
  local = std::min<std::size_t>(local, 64);
  while (local & (local - 1)) local &= local - 1;
  return std::max<std::size_t>(local, 1);
}

// Launches `k` over the pixels in tiles of `tile`; bind(begin, count) sets its arguments.
template <typename Bind>
void launch_tiles(ClRuntime& rt, Launcher& launch, cl::Kernel& k, const char* name, std::size_t npix, int tile,
                  Bind&& bind) {
  const std::size_t local = fixed_local(rt, k);
  tile = std::max(1, tile);
  for (std::size_t begin = 0; begin < npix; begin += std::size_t(tile)) {
    const int count = static_cast<int>(std::min<std::size_t>(std::size_t(tile), npix - begin));
    bind(static_cast<int>(begin), count);
    launch.run(k, name, round_up(count, 64), local, -1);
  }
}

}  // namespace

// The scene is read, not copied: it outlives the megakernel.
struct Megakernel::State {
  const Scene& scene;
  ClRuntime& rt;
  int tile;
  bool items;  // the item buffer too (tests); the bench's frames leave it out, as OPSILA's do
  MegaScene ms;
  MegaKernel mega;
  std::unique_ptr<MegaKernel> uncounted;  // count_work(false): the program without the test counters
  bool count = true;
  MegaBuffers b;
  std::vector<cl_long> accum;    // host copies of the pixel sums and ray counts,
  std::vector<cl_uint4> counts;  // kept between frames as the output image is
  // Where the device does not share host memory, the copies go to pinned
  // memory instead, as OPSILA's image does (RenderSettings::pinned_readback).
  bool pinned;
  PinnedHostBuffer accum_host, counts_host;
  State(const Scene& s, ClRuntime& runtime, int t, bool with_items)
      : scene(s), rt(runtime), tile(t), items(with_items), ms(mega_scene(s)),
        mega(runtime, "megakernel", KernelProgram::baselines),  // the program is built here, before any timing
        b(mega_buffers(runtime, s, ms.bs)), pinned(!host_sharing(runtime).in_place) {}
};

Megakernel::Megakernel(const Scene& scene, ClRuntime& rt, int tile, bool item_buffer) {
  check_kernel_limits(scene);
  rt.walk_instances(!scene.instances.empty());
  s_ = std::make_unique<State>(scene, rt, tile, item_buffer);
}

Megakernel::~Megakernel() = default;

void Megakernel::count_work(bool count) {
  if (!count && !s_->uncounted)
    s_->uncounted = std::make_unique<MegaKernel>(s_->rt, "megakernel", KernelProgram::baselines_uncounted);
  s_->count = count;
}

BaselineImage Megakernel::frame() {
  BaselineImage out;
  frame(out);
  return out;
}

// Timed as OPSILA's frame is (Renderer::render): the kernels, the read-back
// and the decode of the pixel sums into the float image, into storage that
// a repeated frame reuses.
void Megakernel::frame(BaselineImage& out) {
  const Scene& scene = s_->scene;
  ClRuntime& rt = s_->rt;
  const MegaScene& ms = s_->ms;
  const MegaBuffers& b = s_->b;
  const std::size_t npix = std::size_t(scene.width) * scene.height;
  out.width = scene.width;
  out.height = scene.height;
  out.build_seconds = ms.build_seconds;
  cl::CommandQueue& q = rt.queue();

  auto t0 = std::chrono::steady_clock::now();
  std::vector<LaunchRecord> launches;
  Launcher launch(rt, launches);
  MegaKernel& mega = s_->count ? s_->mega : *s_->uncounted;
  MegaArgs args = mega_args(ms, b, spp_side(scene.spp), s_->items);
  launch_tiles(rt, launch, mega.kernel(), "megakernel", npix, s_->tile, [&](int begin, int count) {
    args.pixel_begin = begin;
    args.pixel_count = count;
    mega.bind(args);
  });
  cl_long* accum = nullptr;
  cl_uint4* counts = nullptr;
  if (s_->pinned) {
    s_->accum_host.reserve(rt, npix * 3 * sizeof(cl_long), "megakernel pixel sums, host copy");
    s_->counts_host.reserve(rt, npix * sizeof(cl_uint4), "megakernel ray counts, host copy");
    accum = static_cast<cl_long*>(s_->accum_host.data());
    counts = static_cast<cl_uint4*>(s_->counts_host.data());
  } else {
    s_->accum.resize(npix * 3);
    s_->counts.resize(npix);
    accum = s_->accum.data();
    counts = s_->counts.data();
  }
  launch.check(q.enqueueReadBuffer(b.accum, CL_TRUE, 0, npix * 3 * sizeof(cl_long), accum),
               "clEnqueueReadBuffer(megakernel pixel sums)");
  launch.check(q.enqueueReadBuffer(b.counts, CL_TRUE, 0, npix * sizeof(cl_uint4), counts),
               "clEnqueueReadBuffer(megakernel ray counts)");
  if (s_->items) {
    out.item_buffer.resize(npix * 2);
    launch.check(q.enqueueReadBuffer(b.items, CL_TRUE, 0, npix * sizeof(cl_int2), out.item_buffer.data()),
                 "clEnqueueReadBuffer(megakernel item buffer)");
  } else {
    out.item_buffer.clear();
  }
  launch.check(q.finish(), "clFinish");
  // Pixel sums -> floats exactly as the renderer converts its fixed point.
  out.rgb.resize(npix * 3);
  const MeanDecoder mean(scene.spp);
  parallel_ranges(npix * 3, std::size_t(1) << 16, [&](std::size_t i0, std::size_t i1) {
    for (std::size_t i = i0; i < i1; ++i) out.rgb[i] = mean(static_cast<std::uint64_t>(accum[i]));  // >= 0: add_sat
  });
  out.seconds = seconds_since(t0);
  launch.harvest();
  out.kernel_seconds = 0;
  for (const LaunchRecord& r : launches) out.kernel_seconds += r.seconds;
  out.rays = RayCounts();
  out.rays.primary = npix * static_cast<std::size_t>(scene.spp);
  out.triangle_tests = out.box_tests = 0;  // stay 0 without the counters (count_work)
  for (std::size_t i = 0; i < npix; ++i) {
    const cl_uint4& c = counts[i];
    out.rays.secondary += c.s[0];
    out.rays.shadow += c.s[1];
    out.triangle_tests += c.s[2];
    out.box_tests += c.s[3];
  }
}

std::vector<std::uint64_t> Megakernel::stage_cycles(double& kernel_seconds) {
  ClRuntime& rt = s_->rt;
  KernelBinding<MegaStagesArgs> mega(rt, "megakernel_stages", KernelProgram::baselines_stages);
  std::vector<cl_uint> raw(OPSILA_STAGE_COUNTERS * OPSILA_COUNTER_WORDS, 0u);
  MegaStagesArgs args;
  args.frame = mega_args(s_->ms, s_->b, spp_side(s_->scene.spp), false);
  args.cycles.buffer = upload(rt, raw, "stage cycles");
  std::vector<LaunchRecord> launches;
  Launcher launch(rt, launches);
  const std::size_t npix = std::size_t(s_->scene.width) * s_->scene.height;
  launch_tiles(rt, launch, mega.kernel(), "megakernel_stages", npix, s_->tile, [&](int begin, int count) {
    args.frame.pixel_begin = begin;
    args.frame.pixel_count = count;
    mega.bind(args);
  });
  std::vector<std::uint64_t> cycles = read_counters(rt, args.cycles, OPSILA_STAGE_COUNTERS, "megakernel stage cycles");
  launch.harvest();  // the read waited for the launches
  kernel_seconds = 0;
  for (const LaunchRecord& r : launches) kernel_seconds += r.seconds;
  return cycles;
}

BaselineImage render_megakernel(const Scene& scene, ClRuntime& rt, int tile) {
  return Megakernel(scene, rt, tile).frame();
}

namespace {

// The rays one megakernel frame traces, in its order: a first run counts
// each pixel's rays, a second (megakernel_rays) writes them from each
// pixel's prefix sum on. Split into nearest-hit and any-hit rays. Returns
// false, with the reason, when the device cannot hold them.
struct RayLog {
  std::vector<cl_float4> nearest, any;  // two float4 per ray
};

bool log_megakernel_rays(const Scene& scene, ClRuntime& rt, const MegaScene& ms, const MegaBuffers& b, int tile,
                         RayLog& log, std::string& why) {
  const std::size_t npix = std::size_t(scene.width) * scene.height;
  MegaKernel mega(rt, "megakernel", KernelProgram::baselines);
  MegaRaysKernel rays(rt, "megakernel_rays", KernelProgram::baselines);
  const int side = spp_side(scene.spp);
  std::vector<LaunchRecord> launches;
  Launcher launch(rt, launches);
  MegaRaysArgs args;
  args.frame = mega_args(ms, b, side, false);
  launch_tiles(rt, launch, mega.kernel(), "megakernel", npix, tile, [&](int begin, int count) {
    args.frame.pixel_begin = begin;
    args.frame.pixel_count = count;
    mega.bind(args.frame);
  });
  std::vector<cl_uint4> counts(npix);
  launch.check(rt.queue().enqueueReadBuffer(b.counts, CL_TRUE, 0, npix * sizeof(cl_uint4), counts.data()),
               "clEnqueueReadBuffer(megakernel ray counts)");
  std::vector<cl_uint> first(npix);
  std::uint64_t total = 0;
  for (std::size_t p = 0; p < npix; ++p) {
    first[p] = static_cast<cl_uint>(std::min<std::uint64_t>(total, 0xffffffffu));
    total += std::uint64_t(scene.spp) + counts[p].s[0] + counts[p].s[1];
  }
  const std::uint64_t bytes = total * 2 * sizeof(cl_float4);
  if (total >= 0x7fffffffu || bytes > rt.max_alloc()) {
    why = std::to_string(total) + " rays need a log of " + format_size(bytes) + ", the device allows " +
          format_size(rt.max_alloc());
    return false;
  }
  args.log_first.buffer = upload(rt, first, "ray log offsets");
  args.log.buffer = device_buffer(rt, std::max<std::uint64_t>(bytes, 1), "ray log");
  launch_tiles(rt, launch, rays.kernel(), "megakernel_rays", npix, tile, [&](int begin, int count) {
    args.frame.pixel_begin = begin;
    args.frame.pixel_count = count;
    rays.bind(args);
  });
  std::vector<cl_float4> all(total * 2);
  if (total > 0)
    launch.check(rt.queue().enqueueReadBuffer(args.log, CL_TRUE, 0, bytes, all.data()),
                 "clEnqueueReadBuffer(ray log)");
  launch.harvest();
  for (std::size_t i = 0; i < all.size(); i += 2) {
    std::vector<cl_float4>& to = all[i + 1].s[3] < 0 ? log.nearest : log.any;
    to.push_back(all[i]);
    to.push_back(all[i + 1]);
  }
  return true;
}

}  // namespace

using BatchKernel = KernelBinding<TraversalArgs>;

struct TraversalBatch::State {
  State(ClRuntime& rt, const Scene& scene)
      : rt(rt),
        ms(mega_scene(scene)),
        nearest(rt, "traversal_nearest", KernelProgram::baselines),
        any(rt, "traversal_any", KernelProgram::baselines) {}
  ClRuntime& rt;
  MegaScene ms;
  MegaBuffers b;
  BatchKernel nearest, any;
  TraversalArgs args;  // the rays and their count are each kernel's
  Buf b_nearest, b_any;
  std::size_t nearest_rays = 0, any_rays = 0;
  RayLog kept;  // --rays-out only

  // Enqueues kernel k over `count` rays of `rays` (count > 0).
  void trace(Launcher& launch, BatchKernel& k, const Buf& rays, std::size_t count) {
    args.rays.buffer = rays;
    args.count = static_cast<int>(count);
    cl::Kernel& kk = k.bind(args);
    launch.run(kk, k.name().c_str(), round_up(static_cast<int>(count), 64), fixed_local(rt, kk), -1);
  }
};

TraversalBatch::TraversalBatch(const Scene& scene, ClRuntime& rt, TraversalAlone& record, int tile) {
  check_kernel_limits(scene);
  rt.walk_instances(!scene.instances.empty());
  rt.program(KernelProgram::baselines);
  auto s = std::make_unique<State>(rt, scene);
  s->b = mega_buffers(rt, scene, s->ms.bs);
  RayLog log;
  if (!log_megakernel_rays(scene, rt, s->ms, s->b, tile, log, record.skipped)) return;
  record.present = true;
  s->nearest_rays = record.nearest_rays = log.nearest.size() / 2;
  s->any_rays = record.any_rays = log.any.size() / 2;
  s->b_nearest = upload(rt, log.nearest, "nearest-hit rays");
  s->b_any = upload(rt, log.any, "any-hit rays");
  s->args.geometry = s->b.geometry;
  s->args.root = s->ms.root;
  s->args.slack = s->ms.fp.box_slack;
  s->args.hits.buffer = device_buffer(rt, std::max<std::size_t>(s->nearest_rays, s->any_rays) * sizeof(cl_int) + 4,
                                      "traversal answers");
  if (record.keep_rays) s->kept = std::move(log);
  s_ = std::move(s);
}

TraversalBatch::~TraversalBatch() = default;

std::pair<double, double> TraversalBatch::run() {
  State& s = *s_;
  std::vector<LaunchRecord> launches;
  Launcher launch(s.rt, launches);
  for (auto [k, rays, count] : {std::tuple{&s.nearest, &s.b_nearest, s.nearest_rays},
                                std::tuple{&s.any, &s.b_any, s.any_rays}}) {
    if (count > 0) s.trace(launch, *k, *rays, count);
  }
  launch.check(s.rt.queue().finish(), "clFinish");
  launch.harvest();
  double n = 0, a = 0;
  for (const LaunchRecord& l : launches) (l.name == "traversal_nearest" ? n : a) += l.seconds;
  return {n, a};
}

namespace {

// The logged rays as the file's 8 floats each: tmax +inf for a nearest-hit
// ray (the log marks those with a negative one).
std::vector<float> file_rays(const std::vector<cl_float4>& log, bool nearest) {
  std::vector<float> out;
  out.reserve(log.size() * 4);
  for (std::size_t i = 0; i < log.size(); i += 2) {
    for (int k = 0; k < 4; ++k) out.push_back(log[i].s[k]);
    for (int k = 0; k < 3; ++k) out.push_back(log[i + 1].s[k]);
    out.push_back(nearest ? INFINITY : log[i + 1].s[3]);
  }
  return out;
}

}  // namespace

void TraversalBatch::write_rays_file(TraversalAlone& record) {
  State& s = *s_;
  RayFile f;
  for (const BankTriangle& t : s.ms.bs.triangles)
    for (const float* v : {t.v0, t.v1, t.v2}) f.triangles.insert(f.triangles.end(), v, v + 3);
  f.nearest = file_rays(s.kept.nearest, true);
  f.any = file_rays(s.kept.any, false);
  std::vector<LaunchRecord> launches;
  Launcher launch(s.rt, launches);
  for (auto [k, rays, count, answers] : {std::tuple{&s.nearest, &s.b_nearest, s.nearest_rays, &f.nearest_hit},
                                         std::tuple{&s.any, &s.b_any, s.any_rays, &f.any_blocked}}) {
    answers->resize(count);
    if (count == 0) continue;
    s.trace(launch, *k, *rays, count);
    launch.check(s.rt.queue().enqueueReadBuffer(s.args.hits.buffer, CL_TRUE, 0, count * sizeof(cl_int),
                                                answers->data()),
                 "clEnqueueReadBuffer(traversal answers)");
  }
  launch.harvest();
  record.rays_file = ray_file_bytes(f);
}

void record_traversal_run(TraversalAlone& t, std::pair<double, double> seconds) {
  t.nearest_seconds_all.push_back(seconds.first);
  t.any_seconds_all.push_back(seconds.second);
  t.seconds_all.push_back(seconds.first + seconds.second);
}

void finish_traversal(TraversalAlone& t) {
  if (t.seconds_all.empty()) return;
  const std::size_t m = median_index(t.seconds_all);
  t.seconds = t.seconds_all[m];
  t.nearest_seconds = t.nearest_seconds_all[m];
  t.any_seconds = t.any_seconds_all[m];
}

TraversalAlone measure_traversal_alone(const Scene& scene, ClRuntime& rt, int warmup, int repeats, int tile) {
  TraversalAlone out;
  TraversalBatch batch(scene, rt, out, tile);
  if (!out.present) return out;
  for (int r = 0; r < warmup + repeats; ++r) {
    const auto seconds = batch.run();
    if (r >= warmup) record_traversal_run(out, seconds);
  }
  finish_traversal(out);
  return out;
}

}  // namespace opsila
