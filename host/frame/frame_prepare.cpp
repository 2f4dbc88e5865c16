// The machine for one scene and view, on prepared banks: bank size n and
// the memory plan, work-group sizes, the program's kernels, then the
// uploads and buffers (frame_buffers.cpp).
#include "frame/frame.h"

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstdlib>
#include <stdexcept>
#include <string>

#include "scene/camera.h"
#include "core/env_hooks.h"
#include "core/stage_clock.h"
#include "core/util.h"
#include "mpi/ranks.h"

namespace opsila {

Renderer::Machine::Machine(const Scene& scene, PreparedBanks banks, const RenderSettings& settings,
                           ClRuntime& runtime)
    : rt(runtime), ranks(settings.ranks ? *settings.ranks : solo) {
  P = settings.num_pes;
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
  item_output = settings.item_buffer_output;
  take_switches(settings, banks.group);

  measure = settings.measure_cost;
  // --stats and the bench's counted frame count the work; a plain render
  // and the bench's timed frames count only rays. Compiled before anything
  // is timed.
  counting = measure || settings.count_work;
  rt.walk_instances(!banks.scene.instances.empty());
  if (counting || settings.switch_counting)
    work_kernels = frame_kernels::Set(rt, measure ? KernelProgram::measure : KernelProgram::render);
  if (!counting || settings.switch_counting) ray_kernels = frame_kernels::Set(rt, KernelProgram::render_uncounted);
  if (settings.stage_cycles) stage_kernels = frame_kernels::Set(rt, KernelProgram::render_stages);
  scatter = std::make_unique<ScatterPass>(rt, P);
  choose_work_groups();
  cap = settings.work_groups_per_pe > 0 ? settings.work_groups_per_pe * static_cast<int>(spmd_wg) : 0;

  // This device's PEs and their banks, prepared before (partition/banks.h).
  group = banks.group;
  G = group.size();
  BankedScene& bs = banks.scene;
  // The upload stage: the frame's tables, the bank arrays handed to the
  // device (an aligned copy where it reads them in place) and the buffers.
  const PrepareTimes before_upload = prepare_times();
  auto upload = std::make_unique<StageClock>(PrepareStage::upload);
  if (measure) ncost = std::size_t(depth) * bs.clusters.size();
  if (settings.stage_cycles) ncost = std::max<std::size_t>(ncost, OPSILA_STAGE_COUNTERS * OPSILA_COUNTER_WORDS);
  S = OPSILA_SPAWN_SLOTS(static_cast<int>(bs.lights.size()));
  counted_traffic_levels =
      (settings.count_work || settings.switch_counting) && P <= OPSILA_TRAFFIC_MAX_PES ? depth : 0;
  traffic_levels = counting ? counted_traffic_levels : 0;
  nstats = std::size_t(OPSILA_MAX_DEPTH) * P * OPSILA_STAT_COUNT;
  ntraffic = std::max<std::size_t>(1, std::size_t(counted_traffic_levels) * P * P);
  fp = frame_params(scene, bs, 0);
  fp.group_begin = group.begin;
  fp.group_end = group.end;
  fp.tri_base = banks.tri_base;
  host_tables(scene, bs);  // takes the bank arrays: bs keeps the global tables
  n = choose_bank_capacity(bs, settings);
  fp.bank_capacity = n;
  flight = FlightPlan(G, n, spmd_wg, S);
  if (item_launch_pixels <= 0)  // RenderSettings::item_buffer_tile
    item_launch_pixels = static_cast<int>(std::clamp<std::size_t>(flight.slots, std::size_t(1) << 16, 1 << 24));
  // Depth first, what waits is about the planned pool once a level of the
  // ray trees; beyond that the exchange throttles (frame_scatter.cpp).
  if (waiting_limit == 0) waiting_limit = flight.pool * std::size_t(std::max(depth, 1));
  buffers = buffer_table(bs, flight);
  plan = plan_of(buffers);

  describe_prepared(banks);
  share = banks.share;
  allocate();
  upload.reset();
  prepared.prepare = banks.prepare;
  prepared.prepare[PrepareStage::upload] = stages_since(before_upload)[PrepareStage::upload];
  prepared.prepare.peak_host_bytes = host_peak_bytes();
  if (!group.all()) rank_exchange = std::make_unique<RankExchange>(rt, ranks, group, P, depth);
}

// The frame's switches: from the settings, unless a hook overrides them
// (core/env_hooks.h).
void Renderer::Machine::take_switches(const RenderSettings& settings, const PeGroup& on) {
  build_ahead = settings.primary_ahead;
  if (const auto a = env_hook_number(EnvHook::primary_ahead, 0, 1, "0 or 1")) build_ahead = build_ahead && *a == 1;
  const bool discrete = !host_sharing(rt).in_place;  // a GPU's memory, not the host's
  pinned_readback = settings.pinned_readback || discrete;
  // Several ranks' reports read every launch's time (rank_report).
  sparse_launches = !settings.launch_records && discrete && on.all();
  if (const auto e = env_hook_number(EnvHook::launch_events, 0, 1, "0 or 1")) sparse_launches = *e == 0;
  // One device alone: several ranks add their sums on the host first.
  device_resolve = discrete;
  if (const auto r = env_hook_number(EnvHook::device_resolve, 0, 1, "0 or 1")) device_resolve = *r == 1;
  device_resolve = device_resolve && rt.doubles() && on.all();
  progress = settings.progress;
  if (const auto k = env_hook_number(EnvHook::fault_round, 0, 999999999, "a round number"))
    fault_round = static_cast<int>(*k);
  if (const auto w = env_hook_number(EnvHook::waiting_limit, 1, std::uint64_t(1) << 40, "a descriptor count"))
    waiting_limit = static_cast<std::size_t>(*w);
}

// What the stats report of the machine's preparation (RenderStats).
void Renderer::Machine::describe_prepared(const PreparedBanks& banks) {
  const BankedScene& bs = banks.scene;
  prepared.num_pes = P;
  prepared.bank_capacity = n;
  prepared.num_clusters = static_cast<int>(bs.clusters.size());
  prepared.routing = routing;
  prepared.balance = banks.balance;
  prepared.pilot_frames = banks.pilot_frames;
  prepared.pilot_seconds = banks.pilot_seconds;
  prepared.pilot_warm_up_seconds = banks.pilot_warm_up_seconds;
  prepared.bank_bytes = bs.bank_bytes;
  if (rt.quantised_nodes())  // the walks read BankQNode, half a BankNode
    for (std::size_t p = 0; p < prepared.bank_bytes.size() && p < bs.bank_nodes.size(); ++p)
      prepared.bank_bytes[p] -= bs.bank_nodes[p] * (sizeof(BankNode) - sizeof(BankQNode));
  prepared.global_bytes = bs.global_bytes;
  prepared.replicated_bytes = bs.replicated_bytes;
  prepared.texture_bytes = bs.texture_bytes;
  prepared.texture_replicated_bytes = bs.texture_replicated_bytes;
  prepared.device_bytes = plan.total();
}

// n, the paper's bank size: P * n descriptors in flight fill the device
// (2^18 on a GPU, 2^16 on a CPU), bounded by memory. Everything allocated
// before the first launch must fit the device's global memory (device_buffer
// checks each buffer against the largest single allocation). An automatic n
// halves until it fits; an explicit --bank-capacity, or an image that does
// not fit even with n = 1, is refused.
int Renderer::Machine::choose_bank_capacity(const BankedScene& bs, const RenderSettings& settings) {
  int bank = settings.bank_capacity;
  if (bank <= 0) {
    std::size_t target = rt.device().is_gpu ? (1u << 18) : (1u << 16);
    target = std::min<std::size_t>(target, std::max<std::size_t>(npix, 1024));
    bank = static_cast<int>(std::max<std::size_t>(1, target / G));
  }
  if (std::size_t(G) * bank * S > (1u << 30))
    throw InputError("--bank-capacity " + std::to_string(bank) + " is too large for " + std::to_string(P) +
                     " PEs and " + std::to_string(S - 2) + " lights");
  auto plan = [&](int b) { return plan_of(buffer_table(bs, FlightPlan(G, b, spmd_wg, S))); };
  if (settings.bank_capacity <= 0)
    while (bank > 1 && plan(bank).total() > rt.memory_now()) bank /= 2;
  if (const DevicePlan need = plan(bank); need.total() > rt.memory_now())
    throw ClError("the render needs " + format_size(need.total()) + " of device memory (image " + format_size(need.image) +
                  ", descriptors " + format_size(need.descriptors) + ", scene " + format_size(need.scene) + ", other " +
                  format_size(need.other) + "), more than the device's global memory (" + format_size(rt.memory_now()) +
                  ", " + rt.memory_now_source() +
                  "): use a smaller --size, fewer --pes, a smaller --bank-capacity" +
                  (ranks.built_with_mpi() ? " or more MPI ranks (mpirun -np R)" : ""));
  return bank;
}

// Work-group sizes: queried, never assumed. The SPMD phase's (one
// descriptor per work-item), and the item buffer's square tile of pixels (as
// large as the kernel allows up to 8x8).
// A machine holding both sets takes sizes that both allow, so that its
// frames differ only in what they count.
void Renderer::Machine::choose_work_groups() {
  const cl::Device& dev = rt.device().device;
  std::size_t spmd_allowed = SIZE_MAX, item_allowed = SIZE_MAX, multiple = 0;
  for (frame_kernels::Set* k : {&work_kernels, &ray_kernels}) {
    if (!k->built) continue;
    std::size_t allowed = 0;
    cl_check(k->spmd.kernel().getWorkGroupInfo(dev, CL_KERNEL_WORK_GROUP_SIZE, &allowed),
             "clGetKernelWorkGroupInfo(spmd_phase)");
    spmd_allowed = std::min(spmd_allowed, allowed);
    cl_check(k->spmd.kernel().getWorkGroupInfo(dev, CL_KERNEL_PREFERRED_WORK_GROUP_SIZE_MULTIPLE, &multiple),
             "clGetKernelWorkGroupInfo(spmd_phase)");
    cl_check(k->item.kernel().getWorkGroupInfo(dev, CL_KERNEL_WORK_GROUP_SIZE, &allowed),
             "clGetKernelWorkGroupInfo(item_buffer)");
    item_allowed = std::min(item_allowed, allowed);
  }
  spmd_wg = std::min<std::size_t>(spmd_allowed, rt.group_size());  // 64 unless asked (ClRuntime::group_size)
  if (multiple > 0 && spmd_wg >= multiple) spmd_wg = spmd_wg / multiple * multiple;
  spmd_wg = std::max<std::size_t>(1, spmd_wg);
  prepared.work_group_size = spmd_wg;
  prepared.quantised_nodes = rt.quantised_nodes();

  tile_w = OPSILA_ITEM_TILE_SIDE;
  while (tile_w > 1 && std::size_t(tile_w) * tile_w > item_allowed) tile_w /= 2;
}

frame_kernels::Set::Set(ClRuntime& rt, KernelProgram program)
    : item(rt, "item_buffer", program),
      count_hits(rt, "count_hits", program),
      list_hits(rt, "list_hits", program),
      primary(rt, "build_primary", program),
      spmd(rt, "spmd_phase", program),
      built(true) {
  if (rt.doubles()) resolve = ResolveKernel(rt, "resolve_image", program);
}

}  // namespace opsila
