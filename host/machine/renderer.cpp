// The OPSILA host loop: item buffer (SIMD), primary descriptors, then rounds
// of exchange (SIMD scatter) + SPMD phase until no descriptor is left.
// Longer than 500 lines on purpose: every stage of the machine is here, each
// a short function, in the order render() runs them, so that the host loop
// reads in one place; the memory plan lives in machine/memory_plan.
#include "machine/renderer.h"

#include <algorithm>
#include <cstdlib>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>

#include "core/camera.h"
#include "core/texture.h"
#include "core/fixed_point.h"
#include "core/util.h"
#include "machine/banks.h"
#include "machine/descriptors.h"
#include "machine/memory_plan.h"
#include "machine/pe_group.h"
#include "machine/rank_exchange.h"
#include "machine/stats.h"
#include "opsila_shared.h"
#include "machine/partition.h"
#include "machine/prepare_banks.h"
#include "core/progress.h"
#include "core/stage_clock.h"

namespace opsila {
namespace {

// "Projected object boxes": each cluster box as a conservative pixel
// rectangle (x0, y0, x1, y1), the whole screen when a corner is behind the eye.
std::vector<cl_int4> cluster_rects(const Scene& scene, const BankedScene& bs) {
  const CameraFrame frame = camera_frame(scene.camera, scene.width, scene.height);
  int W = scene.width, H = scene.height;
  std::vector<cl_int4> rects(bs.clusters.size());
  for (std::size_t c = 0; c < bs.clusters.size(); ++c) {
    const Cluster& cl = bs.clusters[c];
    double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
    bool behind = false;
    for (int k = 0; k < 8 && !behind; ++k) {
      Vec3 corner{(k & 1) ? cl.bmax[0] : cl.bmin[0], (k & 2) ? cl.bmax[1] : cl.bmin[1],
                  (k & 4) ? cl.bmax[2] : cl.bmin[2]};
      double px, py;
      behind = !project_to_pixels(frame, W, H, corner, px, py);
      if (behind) break;
      x0 = std::min(x0, px), x1 = std::max(x1, px), y0 = std::min(y0, py), y1 = std::max(y1, py);
    }
    cl_int4 rc;
    if (behind || !std::isfinite(x0 + x1 + y0 + y1)) {
      rc.s[0] = 0, rc.s[1] = 0, rc.s[2] = W - 1, rc.s[3] = H - 1;
    } else {
      // One pixel of margin: the rectangle only culls, the ray test decides.
      rc.s[0] = static_cast<int>(std::max(-1.0, std::floor(x0) - 1));
      rc.s[1] = static_cast<int>(std::max(-1.0, std::floor(y0) - 1));
      rc.s[2] = static_cast<int>(std::min(double(W), std::ceil(x1) + 1));
      rc.s[3] = static_cast<int>(std::min(double(H), std::ceil(y1) + 1));
    }
    rects[c] = rc;
  }
  return rects;
}

std::uint64_t fixed_pair(const std::vector<cl_uint>& v, std::size_t i) {
  return join_words(v[2 * i], v[2 * i + 1]);
}

}  // namespace

int SurfaceBuffers::set_args(cl::Kernel& k, int at) const {
  k.setArg(at++, attributes);
  k.setArg(at++, textures);
  k.setArg(at++, texels);
  k.setArg(at++, srgb);
  return at;
}

SurfaceBuffers upload_surface(ClRuntime& rt, const BankedScene& bs) {
  SurfaceBuffers b;
  b.attributes = upload(rt, bs.attributes, "vertex attributes");
  b.textures = upload(rt, bs.textures, "texture copies");
  b.texels = upload(rt, bs.texels, "texels");
  const std::array<float, 256>& table = srgb_decode_table();
  b.srgb = upload(rt, std::vector<float>(table.begin(), table.end()), "sRGB decode table");
  return b;
}

const char* balance_name(Balance b) {
  switch (b) {
    case Balance::work: return "work";
    case Balance::measured: return "measured";
    default: return "facets";
  }
}

// Everything the machine keeps between frames, and the stages of a frame.
struct Renderer::Machine {
  ClRuntime& rt;
  // P PEs in all; with several MPI ranks this device holds the G PEs of its
  // group (pe_group.h) and only their banks.
  Ranks& ranks = Ranks::world();
  PeGroup group;
  int G = 0;
  DevicePlan plan;
  std::unique_ptr<RankExchange> rank_exchange;  // several ranks only
  int P = 0, n = 0, S = 0, depth = 0, width = 0, height = 0, traffic_levels = 0, cap = 0;
  int routing = OPSILA_ROUTING_BOXES;
  std::size_t npix = 0, nstats = 0, ntraffic = 0;
  std::size_t spmd_wg = 1;
  int tile_w = 1, item_launch_pixels = 1;
  int spp = 1, spp_k = 1;         // samples per pixel, N = k*k
  std::vector<float> offsets;     // (i + 0.5) / k, i = 0..k-1
  Progress* progress = nullptr;
  // OPSILA_FAULT_ROUND=K: a device fault reported at round K of every frame
  // (what a GPU reset or CL_OUT_OF_RESOURCES mid-frame looks like), so the
  // tests can show how a failure among running ranks ends them all.
  int fault_round = -1;
  FlightPlan flight{1, 1, 1, 1};
  FrameParams fp{};
  RenderStats prepared;  // what the prepare step knows: banks, n, work-group size
  ShareFigures share;    // a scene read in shares: what the collective partition did here

  cl::Kernel k_item, k_primary, k_spmd;
  std::unique_ptr<ScatterPass> scatter;
  cl::Buffer b_tris, b_nodes, b_clusters, b_route, b_pes, b_mats, b_lights, b_rects;
  SurfaceBuffers surface;  // vertex attributes and texture copies of the banks
  cl::Buffer b_items, b_item_tri, b_item_t, b_item_facet, b_accum, b_stats, b_traffic, b_out_count, b_hits;
  // Pilot frames (measure_cost): each cluster's tests per level, and what
  // maps them back to the scene's facets (every cluster's, on every rank).
  bool measure = false;
  cl::Buffer b_node_cluster, b_tri_cluster, b_cost;
  std::size_t ncost = 1;
  DescriptorSet banks, outputs, pool, next_pool;

  // Where a frame stands between rounds.
  struct Frame {
    int sample = 0;              // the sample pass whose hits the item buffer holds
    std::size_t next_pixel = 0;  // first pixel without a primary descriptor yet, in this pass
    std::size_t pool_len = 0;    // descriptors waiting in `pool`
    int out_groups = 0;          // SPMD work-groups whose outputs the next exchange reads
    int groups = 0;              // SPMD work-groups of this round (from the exchange's plan)
    std::size_t pool_len_max = 0;  // several ranks: the longest pool of any rank (they inject alike)
  };

  Machine(const Scene& scene, PreparedBanks banks, const RenderSettings& settings, ClRuntime& runtime);
  int choose_bank_capacity(const BankedScene& bs, const RenderSettings& settings) const;
  void choose_work_groups();
  void upload_scene(const Scene& scene, const BankedScene& bs);
  void allocate_frame_buffers();

  void clear_frame();
  void item_buffer(Launcher& launch, int sample);
  void primary_descriptors(Launcher& launch, Frame& f, int round);
  ScatterPass::Args exchange_args(const Frame& f) const;
  void exchange(Launcher& launch, Frame& f, int round, RenderStats& st);
  void spmd_phase(Launcher& launch, Frame& f, int round);
  void report_progress(const Frame& f);
  void read_image(Launcher& launch, RenderResult& result);
  void read_stats(RenderResult& result);
  bool end_rank_round(Launcher& launch, Frame& f);
  RankReport rank_report(const RenderStats& st, double seconds, double mpi_seconds) const;
};

Renderer::Machine::Machine(const Scene& scene, PreparedBanks banks, const RenderSettings& settings,
                           ClRuntime& runtime)
    : rt(runtime) {
  P = settings.num_pes;
  check_machine_request(scene, P);
  if (banks.scene.num_pes != P || banks.group.begin < 0 || banks.group.end > P)
    throw std::invalid_argument("Renderer: the banks were prepared for another machine");
  width = scene.width;
  height = scene.height;
  depth = scene.max_depth;
  npix = std::size_t(width) * height;
  item_launch_pixels = settings.item_buffer_tile;
  routing = settings.routing;
  spp = scene.spp;
  spp_k = spp_side(spp);
  offsets = sample_offsets(spp);
  progress = settings.progress;
  if (const char* k = std::getenv("OPSILA_FAULT_ROUND"); k && *k) {
    const std::string text = k;
    if (!std::all_of(text.begin(), text.end(), [](unsigned char c) { return std::isdigit(c); }) || text.size() > 9)
      throw InputError("OPSILA_FAULT_ROUND=" + text + ": expected a round number");
    fault_round = std::stoi(text);
  }

  measure = settings.measure_cost;
  const KernelProgram program = measure ? KernelProgram::measure : KernelProgram::render;
  rt.program(program);  // compile before anything is timed
  k_item = rt.kernel("item_buffer", program);
  k_primary = rt.kernel("build_primary", program);
  k_spmd = rt.kernel("spmd_phase", program);
  scatter = std::make_unique<ScatterPass>(rt, P);
  choose_work_groups();
  cap = settings.work_groups_per_pe > 0 ? settings.work_groups_per_pe * static_cast<int>(spmd_wg) : 0;

  // This device's PEs and their banks, prepared before (machine/banks.h).
  group = banks.group;
  G = group.size();
  const BankedScene& bs = banks.scene;
  if (measure) ncost = std::size_t(depth) * bs.clusters.size();
  S = OPSILA_SPAWN_SLOTS(static_cast<int>(bs.lights.size()));
  n = choose_bank_capacity(bs, settings);
  flight = FlightPlan(G, n, spmd_wg, S);
  plan = plan_device_memory(bs, npix, P, flight, depth);
  fp = frame_params(scene, bs, n);
  fp.group_begin = group.begin;
  fp.group_end = group.end;
  fp.tri_base = banks.tri_base;
  traffic_levels = P <= OPSILA_TRAFFIC_MAX_PES ? depth : 0;

  prepared.num_pes = P;
  prepared.bank_capacity = n;
  prepared.num_clusters = static_cast<int>(bs.clusters.size());
  prepared.routing = routing;
  prepared.balance = banks.balance;
  prepared.pilot_frames = banks.pilot_frames;
  prepared.pilot_seconds = banks.pilot_seconds;
  share = banks.share;
  prepared.bank_bytes = bs.bank_bytes;
  prepared.global_bytes = bs.global_bytes;
  prepared.replicated_bytes = bs.replicated_bytes;
  prepared.texture_bytes = bs.texture_bytes;
  prepared.texture_replicated_bytes = bs.texture_replicated_bytes;
  const PrepareTimes before_upload = prepare_times();
  {
    StageClock clock(PrepareStage::upload);
    upload_scene(scene, bs);
    clock.progress(0.9);
    allocate_frame_buffers();
  }
  prepared.prepare = banks.prepare;
  prepared.prepare[PrepareStage::upload] = stages_since(before_upload)[PrepareStage::upload];
  prepared.prepare.peak_host_bytes = host_peak_bytes();
  if (!group.all()) rank_exchange = std::make_unique<RankExchange>(rt, ranks, group, P);
}

// n, the paper's bank size: P * n descriptors in flight fill the device
// (2^18 on a GPU, 2^16 on a CPU), bounded by memory. Everything allocated
// before the first launch must fit the device's global memory (device_buffer
// checks each buffer against the largest single allocation). An automatic n
// halves until it fits; an explicit --bank-capacity, or an image that does
// not fit even with n = 1, is refused.
int Renderer::Machine::choose_bank_capacity(const BankedScene& bs, const RenderSettings& settings) const {
  int bank = settings.bank_capacity;
  if (bank <= 0) {
    std::size_t target = rt.device().is_gpu ? (1u << 18) : (1u << 16);
    target = std::min<std::size_t>(target, std::max<std::size_t>(npix, 1024));
    bank = static_cast<int>(std::max<std::size_t>(1, target / G));
  }
  if (std::size_t(G) * bank * S > (1u << 30))
    throw InputError("--bank-capacity " + std::to_string(bank) + " is too large for " + std::to_string(P) +
                     " PEs and " + std::to_string(S - 2) + " lights");
  auto plan = [&](int b) { return plan_device_memory(bs, npix, P, FlightPlan(G, b, spmd_wg, S), depth); };
  if (settings.bank_capacity <= 0)
    while (bank > 1 && plan(bank).total() > rt.global_mem()) bank /= 2;
  if (const DevicePlan need = plan(bank); need.total() > rt.global_mem())
    throw ClError("the render needs " + format_size(need.total()) + " of device memory (image " + format_size(need.image) +
                  ", descriptors " + format_size(need.descriptors) + ", scene " + format_size(need.scene) + ", other " +
                  format_size(need.other) + "), more than the device's global memory (" + format_size(rt.global_mem()) +
                  (rt.memory_limit() ? ", as lowered by OPSILA_DEVICE_MEMORY_LIMIT" : ", CL_DEVICE_GLOBAL_MEM_SIZE") +
                  "): use a smaller --size, fewer --pes, a smaller --bank-capacity" +
                  (ranks.built_with_mpi() ? " or more MPI ranks (mpirun -np R)" : ""));
  return bank;
}

// Work-group sizes: queried, never assumed. The SPMD phase's (one
// descriptor per work-item), and the item buffer's square tile of pixels (as
// large as the kernel allows up to 8x8).
void Renderer::Machine::choose_work_groups() {
  const cl::Device& dev = rt.device().device;
  std::size_t allowed = 0, multiple = 0;
  cl_check(k_spmd.getWorkGroupInfo(dev, CL_KERNEL_WORK_GROUP_SIZE, &allowed),
           "clGetKernelWorkGroupInfo(spmd_phase)");
  cl_check(k_spmd.getWorkGroupInfo(dev, CL_KERNEL_PREFERRED_WORK_GROUP_SIZE_MULTIPLE, &multiple),
           "clGetKernelWorkGroupInfo(spmd_phase)");
  spmd_wg = std::min<std::size_t>(allowed, rt.group_size());  // 64 unless asked (ClRuntime::group_size)
  if (multiple > 0 && spmd_wg >= multiple) spmd_wg = spmd_wg / multiple * multiple;
  spmd_wg = std::max<std::size_t>(1, spmd_wg);
  prepared.work_group_size = spmd_wg;

  cl_check(k_item.getWorkGroupInfo(dev, CL_KERNEL_WORK_GROUP_SIZE, &allowed),
           "clGetKernelWorkGroupInfo(item_buffer)");
  tile_w = OPSILA_ITEM_TILE_SIDE;
  while (tile_w > 1 && std::size_t(tile_w) * tile_w > allowed) tile_w /= 2;
}

// Scene: banks and the global (every-PE) tables, uploaded once.
void Renderer::Machine::upload_scene(const Scene& scene, const BankedScene& bs) {
  b_tris = upload(rt, bs.triangles, "bank facets");
  b_nodes = upload(rt, bs.nodes, "bank BVH nodes");
  b_clusters = upload(rt, bs.clusters, "cluster spheres");
  b_route = upload(rt, bs.route_nodes, "routing boxes");
  b_pes = upload(rt, bs.pes, "PE table");
  b_mats = upload(rt, bs.materials, "materials");
  std::vector<Light> lights = bs.lights;
  if (lights.empty()) lights.push_back(Light{});
  b_lights = upload(rt, lights, "lights");
  surface = upload_surface(rt, bs);
  std::vector<cl_int4> rects = cluster_rects(scene, bs);
  for (std::size_t c = 0; c < rects.size(); ++c)  // another rank's cluster: never listed here
    if (bs.clusters[c].root < 0) rects[c] = cl_int4{{1 << 30, 1 << 30, -(1 << 30), -(1 << 30)}};
  b_rects = upload(rt, rects, "projected cluster boxes");
  // Only the pilot's program reads these; others get one-entry stand-ins.
  b_node_cluster = upload(rt, measure ? bs.node_cluster : std::vector<int>{-1}, "node clusters");
  b_tri_cluster = upload(rt, measure ? bs.tri_cluster : std::vector<int>{-1}, "facet clusters");
}

// Item buffer, pixel sums, statistics and descriptor vectors: banks (the
// slots in flight, each bank padded to whole work-groups), SPMD output
// places, and the waiting pool (ping-pong).
void Renderer::Machine::allocate_frame_buffers() {
  b_items = device_buffer(rt, npix * sizeof(cl_int2), "item buffer");
  b_item_tri = device_buffer(rt, npix * sizeof(cl_int), "item buffer hits");
  b_item_t = device_buffer(rt, npix * sizeof(cl_float), "item buffer distances");
  b_item_facet = device_buffer(rt, npix * sizeof(cl_int), "item buffer facets");
  b_accum = device_buffer(rt, npix * OPSILA_ACCUM_WORDS * sizeof(cl_uint), "pixel sums");
  nstats = std::size_t(OPSILA_MAX_DEPTH) * P * OPSILA_STAT_COUNT * 2;
  b_stats = device_buffer(rt, nstats * sizeof(cl_uint), "stats");
  ntraffic = std::max<std::size_t>(1, std::size_t(traffic_levels) * P * P);
  b_traffic = device_buffer(rt, ntraffic * sizeof(cl_uint), "traffic");
  b_hits = device_buffer(rt, 2 * sizeof(cl_uint), "primary hit count");
  b_cost = device_buffer(rt, ncost * sizeof(cl_uint), "cluster work");
  b_out_count = device_buffer(rt, flight.groups * flight.group_size * sizeof(cl_int), "SPMD output counts");
  banks.allocate(rt, flight.slots + std::size_t(P) * flight.group_size, "descriptor banks");
  outputs.allocate(rt, flight.outputs, "SPMD output places");
  pool.allocate(rt, flight.pool, "descriptor pool");
  next_pool.allocate(rt, flight.pool, "descriptor pool");
}

// Every frame starts from zero pixel sums, statistics and traffic.
void Renderer::Machine::clear_frame() {
  if (rank_exchange) rank_exchange->reset();
  zero_buffer(rt, b_accum, npix * OPSILA_ACCUM_WORDS * sizeof(cl_uint), "pixel sums");
  zero_buffer(rt, b_stats, nstats * sizeof(cl_uint), "stats");
  zero_buffer(rt, b_traffic, ntraffic * sizeof(cl_uint), "traffic");
  zero_buffer(rt, b_hits, 2 * sizeof(cl_uint), "primary hit count");
  zero_buffer(rt, b_cost, ncost * sizeof(cl_uint), "cluster work");
}

// SIMD phase 1, the item buffer: one work-group per square tile of pixels;
// launches are bounded to about `item_buffer_tile` pixels each so that no
// launch runs unbounded.
//
// One pass per sample (0 .. N-1, i rightwards, j downwards) keeps the
// nearest hits for that sample's primary descriptors; the (object, facet)
// output is the centre ray's: the centre sample's pass writes it for odd k,
// a pass of its own (sample -1, no hits kept) for even k. With several
// ranks, each launch covers whole rows of tiles, which the ranks relay in
// turn (rank_exchange.h), and every pass keeps its hits (the relayed state).
void Renderer::Machine::item_buffer(Launcher& launch, int sample) {
  const bool centre_only = sample < 0;
  const int i = centre_only ? 0 : sample % spp_k, j = centre_only ? 0 : sample / spp_k;
  const bool centre = centre_only || (2 * i + 1 == spp_k && 2 * j + 1 == spp_k);
  const int mode = (centre ? OPSILA_ITEM_WRITE_ITEMS : 0) |
                   (centre_only && group.all() ? 0 : OPSILA_ITEM_WRITE_HITS);
  const float ox = centre_only ? 0.5f : offsets[std::size_t(i)], oy = centre_only ? 0.5f : offsets[std::size_t(j)];
  const int tiles_x = (width + tile_w - 1) / tile_w, tiles_y = (height + tile_w - 1) / tile_w;
  const int tiles = tiles_x * tiles_y;
  int per_launch = std::max(1, item_launch_pixels / (tile_w * tile_w));
  if (!group.all()) per_launch = std::max(1, per_launch / tiles_x) * tiles_x;
  const ItemBuffers relay{&b_items, &b_item_tri, &b_item_t, &b_item_facet, centre};
  for (int begin = 0; begin < tiles; begin += per_launch) {
    const int count = std::min(per_launch, tiles - begin);
    const std::size_t px0 = std::size_t(begin / tiles_x) * tile_w * width;
    const std::size_t px1 = std::min(npix, std::size_t((begin + count) / tiles_x) * tile_w * width);
    if (!group.all()) relay_receive(ranks, rt, relay, px0, px1 - px0);
    int a = 0;
    k_item.setArg(a++, fp);
    k_item.setArg(a++, b_clusters);
    k_item.setArg(a++, b_rects);
    k_item.setArg(a++, b_nodes);
    k_item.setArg(a++, b_tris);
    k_item.setArg(a++, tile_w);
    k_item.setArg(a++, tiles_x);
    k_item.setArg(a++, begin);
    k_item.setArg(a++, ox);
    k_item.setArg(a++, oy);
    k_item.setArg(a++, mode);
    k_item.setArg(a++, b_items);
    k_item.setArg(a++, b_item_tri);
    k_item.setArg(a++, b_item_t);
    k_item.setArg(a++, b_item_facet);
    launch.run(k_item, "item_buffer", std::size_t(count) * tile_w * tile_w, std::size_t(tile_w) * tile_w, -1);
    if (!group.all()) relay_send(ranks, rt, relay, px0, px1 - px0);
  }
  if (!group.all()) relay_share(ranks, rt, relay, npix);
}

// Primary descriptors (SIMD), built from the item buffer into the waiting
// pool when it runs short, bound for the PEs that own the items. When a
// sample pass is used up, the next sample's item buffer pass runs first (the
// in-order queue runs it after the builds that read the previous one), so
// the descriptors in flight stay bounded by the injection whatever N is.
void Renderer::Machine::primary_descriptors(Launcher& launch, Frame& f, int round) {
  // Several ranks decide alike (on the longest pool of any): each builds the
  // descriptors of its own PEs from the same pixels, and the item buffer
  // passes, relayed between ranks, start on every rank in the same round.
  if ((group.all() ? f.pool_len : f.pool_len_max) >= flight.inject) return;
  if (f.next_pixel >= npix && f.sample + 1 < spp) {
    item_buffer(launch, ++f.sample);
    f.next_pixel = 0;
  }
  if (f.next_pixel >= npix) return;
  std::size_t count = std::min(flight.inject, npix - f.next_pixel);
  if (!group.all() && f.pool_len + count > pool.capacity) {
    DescriptorSet bigger;
    bigger.allocate(rt, (f.pool_len + count) * 3 / 2, "descriptor pool");
    pool.copy_prefix_to(rt, bigger, f.pool_len);
    pool = bigger;
  }
  if (f.pool_len + count > pool.capacity) count = pool.capacity - f.pool_len;
  int a = 0;
  k_primary.setArg(a++, fp);
  k_primary.setArg(a++, b_pes);
  k_primary.setArg(a++, b_item_tri);
  k_primary.setArg(a++, b_item_t);
  k_primary.setArg(a++, static_cast<int>(f.next_pixel));
  k_primary.setArg(a++, static_cast<int>(count));
  k_primary.setArg(a++, offsets[std::size_t(f.sample % spp_k)]);
  k_primary.setArg(a++, offsets[std::size_t(f.sample / spp_k)]);
  k_primary.setArg(a++, static_cast<int>(f.pool_len));
  a = pool.set_args(k_primary, a);
  k_primary.setArg(a++, b_accum);
  k_primary.setArg(a++, b_hits);
  launch.run(k_primary, "build_primary", round_up(count, 64), 0, round);
  f.next_pixel += count;
  f.pool_len += count;
}

ScatterPass::Args Renderer::Machine::exchange_args(const Frame& f) const {
  ScatterPass::Args sa;
  sa.pool_len = static_cast<int>(f.pool_len);
  sa.pool = &pool;
  sa.out_groups = f.out_groups;
  sa.group_size = static_cast<int>(spmd_wg);
  sa.spawn_slots = S;
  sa.outputs = &outputs;
  sa.out_item_count = &b_out_count;
  sa.slots = static_cast<int>(flight.slots);
  sa.cap = cap;
  sa.banks = &banks;
  sa.next_pool = &next_pool;
  sa.group_begin = group.begin;
  sa.group_end = group.end;
  return sa;
}

// SIMD exchange: scatter [pool | SPMD outputs] into the banks of the next
// SPMD phase, each bank as large as its PE's demand allows; what finds no
// slot waits in the next pool. The control unit reads three counts (how many
// wait, how many were placed, how many work-groups serve them) while the
// records move.
void Renderer::Machine::exchange(Launcher& launch, Frame& f, int round, RenderStats& st) {
  const std::size_t bound = f.pool_len + std::size_t(f.out_groups) * spmd_wg * S + flight.inject;
  if (next_pool.capacity < bound) next_pool.allocate(rt, bound + bound / 2, "descriptor pool");
  const ScatterPass::Args sa = exchange_args(f);
  scatter->plan(launch, sa, round);
  cl_int counts[3] = {0, 0, 0};
  cl::Event read;
  launch.check(rt.queue().enqueueReadBuffer(scatter->counts, CL_FALSE, 0, sizeof(counts), counts, nullptr, &read),
               "clEnqueueReadBuffer(scatter counts)");
  scatter->move(launch, sa, round);
  launch.check(read.wait(), "clWaitForEvents(scatter counts)");
  if (rank_exchange) rank_exchange->start(scatter->pe_total, next_pool, static_cast<std::size_t>(counts[0]));
  std::swap(pool, next_pool);
  f.pool_len = static_cast<std::size_t>(counts[0]);
  f.groups = counts[2];
  st.overflow_deferrals += rank_exchange ? rank_exchange->waiting() : static_cast<std::uint64_t>(counts[0]);
}

// Several ranks, after the SPMD launch: the records bound for other ranks
// travel while the SPMD phase runs; the next pool is this rank's waiting
// records followed by what the others sent. The ranks go on while any has
// work, and take the next injection decision together. Returns false at the end.
bool Renderer::Machine::end_rank_round(Launcher& launch, Frame& f) {
  launch.check(rt.queue().flush(), "clFlush");
  rank_exchange->exchange();
  f.pool_len = rank_exchange->finish(pool, next_pool, flight.inject);
  std::swap(pool, next_pool);
  const bool left = f.pool_len > 0 || f.out_groups > 0 || f.next_pixel < npix || f.sample + 1 < spp;
  std::vector<std::uint64_t> all = {left ? 1u : 0u, f.pool_len};
  ranks.max(all);
  f.pool_len_max = all[1];
  return all[0] > 0;
}

// SPMD phase: the plan's work-groups, each on one PE's bank.
void Renderer::Machine::spmd_phase(Launcher& launch, Frame& f, int round) {
  int a = 0;
  k_spmd.setArg(a++, fp);
  k_spmd.setArg(a++, b_pes);
  k_spmd.setArg(a++, b_clusters);
  k_spmd.setArg(a++, b_route);
  k_spmd.setArg(a++, routing);
  k_spmd.setArg(a++, b_nodes);
  k_spmd.setArg(a++, b_tris);
  k_spmd.setArg(a++, b_mats);
  k_spmd.setArg(a++, b_lights);
  a = surface.set_args(k_spmd, a);
  a = banks.set_args(k_spmd, a);
  k_spmd.setArg(a++, scatter->group_pe);
  k_spmd.setArg(a++, scatter->group_first);
  k_spmd.setArg(a++, scatter->bank_begin);
  k_spmd.setArg(a++, scatter->bank_count);
  a = outputs.set_args(k_spmd, a);
  k_spmd.setArg(a++, b_out_count);
  k_spmd.setArg(a++, b_accum);
  k_spmd.setArg(a++, b_stats);
  k_spmd.setArg(a++, b_traffic);
  k_spmd.setArg(a++, traffic_levels);
  k_spmd.setArg(a++, b_node_cluster);
  k_spmd.setArg(a++, b_tri_cluster);
  k_spmd.setArg(a++, b_cost);
  launch.run(k_spmd, "spmd_phase", std::size_t(f.groups) * spmd_wg, spmd_wg, round);
  f.out_groups = f.groups;
  if (round % 16 == 15) launch.harvest();
}

// Read back the pixel sums (fixed point: the sum of the N samples, decoded
// here into their mean) and the item buffer.
void Renderer::Machine::read_image(Launcher& launch, RenderResult& result) {
  cl::CommandQueue& q = rt.queue();
  std::vector<cl_uint> accum(npix * OPSILA_ACCUM_WORDS);
  launch.check(q.enqueueReadBuffer(b_accum, CL_TRUE, 0, accum.size() * sizeof(cl_uint), accum.data()),
               "clEnqueueReadBuffer(pixel sums)");
  result.item_buffer.resize(npix * 2);
  launch.check(q.enqueueReadBuffer(b_items, CL_TRUE, 0, npix * sizeof(cl_int2), result.item_buffer.data()),
               "clEnqueueReadBuffer(item buffer)");
  launch.check(q.finish(), "clFinish");
  // 64-bit integer sums: with several ranks, summed over them on rank 0.
  std::vector<std::uint64_t> sums(npix * 3);
  for (std::size_t i = 0; i < npix * 3; ++i) sums[i] = fixed_pair(accum, i);
  if (!group.all()) reduce_to_root(ranks, sums);
  result.rgb.resize(npix * 3);
  for (std::size_t i = 0; i < npix * 3; ++i) result.rgb[i] = from_fixed(sums[i], spp);
}

// Per-level, per-PE counters and traffic, then the frame's totals. Every
// primary ray is cast by the item buffer; descriptors are spawned as primary
// hits, children and shadow rays, and finish as shaded hits, misses,
// occluded or lit shadow rays.
void Renderer::Machine::read_stats(RenderResult& result) {
  RenderStats& st = result.stats;
  cl::CommandQueue& q = rt.queue();
  std::vector<cl_uint> raw(nstats);
  cl_check(q.enqueueReadBuffer(b_stats, CL_TRUE, 0, nstats * sizeof(cl_uint), raw.data()), "clEnqueueReadBuffer(stats)");
  std::vector<cl_uint> tr(traffic_levels > 0 ? ntraffic : 0), hits(2);
  if (traffic_levels > 0)
    cl_check(q.enqueueReadBuffer(b_traffic, CL_TRUE, 0, ntraffic * sizeof(cl_uint), tr.data()),
             "clEnqueueReadBuffer(traffic)");
  cl_check(q.enqueueReadBuffer(b_hits, CL_TRUE, 0, 2 * sizeof(cl_uint), hits.data()),
           "clEnqueueReadBuffer(primary hit count)");
  // Each rank counted its own PEs and primaries: summed on rank 0.
  std::vector<std::uint64_t> counters(std::size_t(depth) * P * OPSILA_STAT_COUNT), traffic(tr.begin(), tr.end());
  for (std::size_t k = 0; k < counters.size(); ++k) counters[k] = fixed_pair(raw, k);
  counters.push_back(fixed_pair(hits, 0));
  if (!group.all()) {
    reduce_to_root(ranks, counters);
    reduce_to_root(ranks, traffic);
  }
  st.counters.assign(depth, std::vector<std::vector<std::uint64_t>>(P, std::vector<std::uint64_t>(OPSILA_STAT_COUNT, 0)));
  for (int l = 0; l < depth; ++l)
    for (int p = 0; p < P; ++p)
      for (int s = 0; s < OPSILA_STAT_COUNT; ++s)
        st.counters[l][p][s] = counters[(std::size_t(l) * P + p) * OPSILA_STAT_COUNT + s];
  if (traffic_levels > 0) {
    st.traffic.assign(traffic_levels, std::vector<std::uint64_t>(std::size_t(P) * P));
    for (int l = 0; l < traffic_levels; ++l)
      for (std::size_t k = 0; k < std::size_t(P) * P; ++k) st.traffic[l][k] = traffic[std::size_t(l) * P * P + k];
  }
  result.rays.primary = npix * std::size_t(spp);
  result.rays.primary_hits = counters.back();
  std::uint64_t children = 0, shadow = 0, finished = 0, forwards = 0;
  for (int l = 0; l < depth; ++l)
    for (int p = 0; p < P; ++p) {
      const auto& c = st.counters[l][p];
      children += c[OPSILA_STAT_SPAWN_RADIANCE];
      shadow += c[OPSILA_STAT_SPAWN_SHADOW];
      finished += c[OPSILA_STAT_RESOLVED] + c[OPSILA_STAT_MISS] + c[OPSILA_STAT_OCCLUDED] + c[OPSILA_STAT_LIT];
      forwards += c[OPSILA_STAT_FORWARD];
    }
  result.rays.secondary = children;
  result.rays.shadow = shadow;
  st.descriptors_spawned = result.rays.primary_hits + children + shadow;
  st.descriptors_finished = finished;
  st.forwards = forwards;
}

// Progress (only when a line is due): a lower bound of the samples whose ray
// trees are finished, out of all samples: samples injected, less one per
// descriptor still in flight (spawned - finished, from the counters).
void Renderer::Machine::report_progress(const Frame& f) {
  std::vector<cl_uint> raw(nstats), hits(2);
  cl::CommandQueue& q = rt.queue();
  cl_check(q.enqueueReadBuffer(b_stats, CL_TRUE, 0, nstats * sizeof(cl_uint), raw.data()), "clEnqueueReadBuffer(stats)");
  cl_check(q.enqueueReadBuffer(b_hits, CL_TRUE, 0, 2 * sizeof(cl_uint), hits.data()),
           "clEnqueueReadBuffer(primary hit count)");
  std::uint64_t spawned = fixed_pair(hits, 0), finished = 0;
  for (int l = 0; l < depth; ++l)
    for (int p = 0; p < P; ++p) {
      const std::size_t at = (std::size_t(l) * P + p) * OPSILA_STAT_COUNT;
      spawned += fixed_pair(raw, at + OPSILA_STAT_SPAWN_RADIANCE) + fixed_pair(raw, at + OPSILA_STAT_SPAWN_SHADOW);
      finished += fixed_pair(raw, at + OPSILA_STAT_RESOLVED) + fixed_pair(raw, at + OPSILA_STAT_MISS) +
                  fixed_pair(raw, at + OPSILA_STAT_OCCLUDED) + fixed_pair(raw, at + OPSILA_STAT_LIT);
    }
  const std::uint64_t injected = std::uint64_t(f.sample) * npix + f.next_pixel;
  const std::uint64_t in_flight = spawned > finished ? spawned - finished : 0;
  const double done = injected > in_flight ? double(injected - in_flight) : 0.0;
  const std::uint64_t rays = injected + (spawned - fixed_pair(hits, 0));
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
    if (l.name == "spmd_phase" && l.round >= 0 && std::size_t(l.round) < spmd.size()) spmd[l.round] += l.seconds;
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

Renderer::Renderer(const Scene& scene, PreparedBanks banks, const RenderSettings& settings, ClRuntime& runtime)
    : m_(std::make_unique<Machine>(scene, std::move(banks), settings, runtime)) {}

Renderer::~Renderer() = default;

// One frame, as the paper runs it.
RenderResult Renderer::render() {
  Machine& m = *m_;
  RenderResult result;
  result.width = m.width;
  result.height = m.height;
  result.stats = m.prepared;
  RenderStats& st = result.stats;
  Launcher launch(m.rt, st.launches);
  // Several ranks: from here on they wait on each other (a rank that failed
  // while preparing has said so, and every rank stops here).
  const bool ranks = !m.group.all();
  if (ranks) m.ranks.begin_collective();
  const auto t_start = std::chrono::steady_clock::now();
  const double mpi_start = m.ranks.mpi_seconds();

  if (m.progress) m.progress->start();
  m.clear_frame();
  if (m.spp_k % 2 == 0) m.item_buffer(launch, -1);  // even k: the centre ray is no sample
  m.item_buffer(launch, 0);
  Machine::Frame f;
  for (int round = 0;; ++round) {
    if (round == m.fault_round)
      throw ClError("device fault at round " + std::to_string(round) + " (injected by OPSILA_FAULT_ROUND)");
    m.primary_descriptors(launch, f, round);
    if (!ranks && f.pool_len == 0 && f.out_groups == 0) break;
    m.exchange(launch, f, round, st);
    if (f.groups == 0) {  // only NIL holes were left: nothing placed, nothing waits
      f.out_groups = 0;
      if (ranks && !m.end_rank_round(launch, f)) break;
      continue;
    }
    m.spmd_phase(launch, f, round);
    ++st.rounds;
    if (ranks && !m.end_rank_round(launch, f)) break;
    if (m.progress && m.progress->due()) m.report_progress(f);
  }
  m.read_image(launch, result);

  st.render_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  launch.harvest();
  if (ranks) {
    const RankReport mine = m.rank_report(st, st.render_seconds, m.ranks.mpi_seconds() - mpi_start);
    for (const std::string& text : m.ranks.gather(rank_report_json(mine), 0))
      st.ranks.push_back(rank_report_from_json(text));
  }
  m.read_stats(result);
  if (ranks) m.ranks.end_collective();
  if (m.progress && m.progress->due()) m.progress->report(1.0, result.rays.total());
  return result;
}

std::vector<std::uint64_t> Renderer::cluster_work() {
  Machine& m = *m_;
  if (!m.measure) return {};
  std::vector<cl_uint> raw(m.ncost);
  cl_check(m.rt.queue().enqueueReadBuffer(m.b_cost, CL_TRUE, 0, raw.size() * sizeof(cl_uint), raw.data()),
           "clEnqueueReadBuffer(cluster work)");
  // A cluster is counted by the rank that holds it alone (the others count
  // 0 for it), so the largest count over the ranks is its count.
  std::vector<std::uint64_t> cost(raw.begin(), raw.end());
  if (!m.group.all()) m.ranks.max(cost);
  return cost;
}

RenderResult render(const Scene& scene, const RenderSettings& settings, ClRuntime& runtime) {
  PreparedBanks banks = prepare_banks(scene, settings, runtime);
  return Renderer(scene, std::move(banks), settings, runtime).render();
}

}  // namespace opsila
