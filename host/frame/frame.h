// The frame machine's private header: the state the renderer keeps between
// frames (Renderer::Machine) and the stages of a frame, one file each, each
// named after the kernel file it drives:
//   frame_kernels.h        the kernels' argument structs and buffer roles
//   frame_prepare.cpp      the machine for one scene and view (bank size n,
//                          work-group sizes, the program's kernels)
//   frame_buffers.cpp      the buffer table: scene uploads, frame buffers, clearing
//   frame_item_buffer.cpp  kernels/item_buffer.cl
//   frame_primary.cpp      kernels/primary.cl
//   frame_scatter.cpp      kernels/scatter.cl (the exchange, and the ranks' part of it)
//   frame_spmd_phase.cpp   kernels/spmd_phase.cl
//   frame_readback.cpp     image, counters, progress, rank report
// renderer.cpp holds the loop that runs them. Only these files include it.
#pragma once

#include <memory>
#include <vector>

#include "partition/banks.h"
#include "device/descriptors.h"
#include "device/memory_plan.h"
#include "frame/frame_kernels.h"
#include "partition/pe_group.h"
#include "frame/rank_exchange.h"
#include "mpi/ranks.h"
#include "frame/renderer.h"
#include "opsila_shared.h"

namespace opsila {

// Everything the machine keeps between frames, and the stages of a frame.
// The item buffer's bins: squares of `side` pixels (a multiple of the
// tile's, so a tile lies in one), bins_x to a row, bin b listing in
// list[first[b] .. first[b + 1]) the clusters whose rectangle (rects, in
// the item buffer's order) overlaps it, in that order. A tile tests only
// its bin's clusters instead of every cluster of the scene (10^5 instances
// made the listing nine tenths of the frame). The side doubles from one
// tile until the lists hold at most kMaxItemBinEntries.
struct ItemBins {
  int side = 1, bins_x = 1;
  std::vector<int> first{0, 0}, list{-1};
};
constexpr std::size_t kMaxItemBinEntries = std::size_t(1) << 24;
ItemBins item_bins(const std::vector<cl_int4>& rects, int width, int height, int tile_w);

struct Renderer::Machine {
  ClRuntime& rt;
  // P PEs in all; with several MPI ranks this device holds the G PEs of its
  // group (pe_group.h) and only their banks.
  OneProcess solo;    // one process, when the settings name no ranks
  Ranks& ranks;  // settings.ranks, else solo
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
  bool item_output = true;        // RenderSettings::item_buffer_output
  // The pixel sums read into pinned host memory (RenderSettings::pinned_readback)
  // rather than mapped; accum_host holds them.
  bool pinned_readback = false;
  // Launches without events but the long ones (RenderSettings::launch_records).
  bool sparse_launches = false;
  // The image resolved on the device (kernels/resolve.cl) and read back as
  // floats: one device alone that does not share host memory and has
  // doubles, or OPSILA_DEVICE_RESOLVE=1; accum_host then holds the floats.
  bool device_resolve = false;
  PinnedHostBuffer accum_host;
  std::vector<float> offsets;     // (i + 0.5) / k, i = 0..k-1
  Progress* progress = nullptr;
  // OPSILA_FAULT_ROUND=K: a device fault reported at round K of every frame
  // (what a GPU reset or CL_OUT_OF_RESOURCES mid-frame looks like), so the
  // tests can show how a failure among running ranks ends them all.
  int fault_round = -1;
  FlightPlan flight{1, 1, 1, 1};
  // The SPMD launch builds the next round's primary descriptors
  // (RenderSettings::primary_ahead; frame_primary.cpp, primary_ahead).
  bool build_ahead = true;
  // Descriptors that may wait before the exchange takes only the rays that
  // end their tree (kernels/scatter.cl): OPSILA_WAITING_LIMIT, else the
  // planned pool once a level (depth first, about what the trees hold).
  std::size_t waiting_limit = 0;
  FrameParams fp{};
  RenderStats prepared;  // what the prepare step knows: banks, n, work-group size
  bool first_frame = true;  // its kernels' first launches may wait for their compile
  ShareFigures share;    // a scene read in shares: what the collective partition did here

  // The frame's kernels: from the program that counts the work (--stats,
  // the bench's counted frame, the pilots' measure program), and from the
  // one that counts only rays (a plain render, the bench's timed frames).
  // `counting` picks this frame's set; a machine prepared with
  // RenderSettings::switch_counting holds both.
  // `clocking` (Renderer::count_stage_cycles) runs the stage-clock set instead.
  frame_kernels::Set work_kernels, ray_kernels, stage_kernels;
  bool counting = true, clocking = false;
  int counted_traffic_levels = 0;  // traffic_levels of a counting frame (the buffer's size)
  frame_kernels::Set& kernels() { return clocking ? stage_kernels : counting ? work_kernels : ray_kernels; }
  std::unique_ptr<ScatterPass> scatter;
  // The device buffers, typed by role (frame_kernels.h), as the buffer
  // table declares them.
  BankGeometry geometry;
  ShadingTables shading;  // materials, lights, and the banks' vertex attributes and textures
  RoutingTables routing_tables;
  ItemClusterList item_list;  // its `listed`: the projected boxes' union, a tile outside it lists no cluster
  ItemArrays item;
  HitList b_hit_pixels;  // the hit list (kernels/primary.cl)
  HitBlocks b_hit_blocks;
  HitListLength b_hit_total;
  PixelSums b_accum;
  ResolvedImage b_image;  // device_resolve only (one pixel's room elsewhere)
  StatCounters b_stats;
  TrafficCounters b_traffic;
  OutputCounts b_out_count;
  PrimaryHitCount b_hits;
  // Pilot frames (measure_cost): each cluster's tests per level, and what
  // maps them back to the scene's facets (every cluster's, on every rank).
  // A stage-clock frame counts its stages' cycles in work.cost instead.
  bool measure = false;
  ClusterWork work;
  std::size_t ncost = 1;
  DescriptorSet banks, outputs, pool, next_pool;

  // Host arrays the uploads read. The bank arrays stay as long as the
  // machine where the device reads them in place (device/device_buffers.h,
  // HostArray), and are freed once copied elsewhere; the small tables are
  // made for the upload and freed with the machine.
  HostArray host_tris, host_nodes, host_attributes, host_texels;
  std::vector<Light> lights;     // at least one (a stand-in never lit)
  // The item buffer's clusters, nearest the eye first (item_depth_order),
  // and their projected boxes in that order.
  std::vector<Cluster> item_clusters;
  std::vector<float> item_near;  // each one's distance from the eye, rounded down
  std::vector<cl_int4> rects;
  ItemBins bins;  // the clusters each square of the screen lists (item_bins)
  // The pixels the item buffer traces (x0, y0, x1, y1, inclusive): on one
  // device, when the frame gives no item buffer, their union (item_list.listed)
  // within the image (empty when no cluster is listed); else the whole image. A pixel
  // outside it is a miss that no kernel touches: read_image gives it the
  // background's sum.
  cl_int4 traced_rect{};
  std::vector<float> srgb;       // sRGB decode table
  std::vector<int> no_cluster{-1};
  std::vector<Instance> no_instance{Instance{}};  // the table's stand-in for a scene without instances
  std::vector<BufferSpec> buffers;  // the buffer table, as allocated (frame_buffers.cpp)
  std::uint64_t in_place_bytes = 0;  // of the uploads, read by the device in place

  // Where a frame stands between rounds.
  struct Frame {
    int sample = 0;              // the sample pass whose hits the item buffer holds
    std::size_t listed = 0;      // its hit list's length (the pixels that need a primary descriptor)
    std::size_t next_hit = 0;    // first hit of the list without a primary descriptor yet
    std::size_t pool_len = 0;    // descriptors waiting in `pool`
    int out_groups = 0;          // SPMD work-groups whose outputs the next exchange reads
    int groups = 0;              // SPMD work-groups of this round (from the exchange's plan)
    std::size_t pool_len_max = 0;  // several ranks: the longest pool of any rank (they inject alike)
    bool built_ahead = false;    // the last SPMD launch built this round's primary descriptors
  };

  Machine(const Scene& scene, PreparedBanks banks, const RenderSettings& settings, ClRuntime& runtime);
  // Waits for the device before anything is freed: a frame that ended in
  // an error (another rank's failure, a fault) may leave launches running,
  // which read the host arrays below in place.
  ~Machine();
  int choose_bank_capacity(const BankedScene& bs, const RenderSettings& settings);
  void choose_work_groups();
  void host_tables(const Scene& scene, BankedScene& bs);
  void take_switches(const RenderSettings& settings, const PeGroup& on);
  void describe_prepared(const PreparedBanks& banks);
  std::vector<BufferSpec> buffer_table(const BankedScene& bs, const FlightPlan& f);
  void allocate();

  void clear_frame();
  void item_buffer(Launcher& launch, int sample);
  std::size_t list_hits(Launcher& launch, int sample);
  frame_kernels::PrimaryBuildArgs primary_build(Frame& f, std::size_t count);
  void primary_descriptors(Launcher& launch, Frame& f, int round);
  int primary_ahead(Frame& f, frame_kernels::PrimaryBuildArgs& b);
  ScatterPass::Args exchange_args(const Frame& f) const;
  void exchange(Launcher& launch, Frame& f, int round, RenderStats& st);
  void spmd_phase(Launcher& launch, Frame& f, int round);
  void report_progress(const Frame& f);
  void read_image(Launcher& launch, RenderResult& result);
  void read_resolved(Launcher& launch, RenderResult& result);
  void read_items(Launcher& launch, RenderResult& result);
  void read_stats(RenderResult& result);
  bool end_rank_round(Launcher& launch, Frame& f);
  RankReport rank_report(const RenderStats& st, double seconds, double mpi_seconds) const;
};


// "Projected object boxes" of the item buffer (frame_buffers.cpp).
std::vector<cl_int4> cluster_rects(const Scene& scene, const std::vector<Cluster>& clusters);
// The clusters the item buffer lists: every cluster of the scene's own
// facets, and for each bank of this device that holds instances one entry
// for them all, its root their BVH's (PeInfo.instance_root), its box theirs:
// one walk that meets the nearest instances first, instead of a list entry
// (a rectangle test and a walk of its own) per instance.
std::vector<Cluster> item_buffer_clusters(const BankedScene& bs);
cl_int4 rects_union(const std::vector<cl_int4>& rects);
// Cluster indices by the distance from the eye to their boxes, nearest first
// (ties by index): the item buffer meets near hits first and culls behind
// them; any order gives the same items (kernels/hit_order.h).
std::vector<int> item_depth_order(const Scene& scene, const std::vector<Cluster>& clusters,
                                  std::vector<double>* distance = nullptr);

}  // namespace opsila
