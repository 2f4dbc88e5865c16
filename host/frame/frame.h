// The frame machine's private header: the state the renderer keeps between
// frames (Renderer::Machine) and the stages of a frame, one file each, each
// named after the kernel file it drives:
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
#include "device/kernel_args.h"
#include "device/memory_plan.h"
#include "partition/pe_group.h"
#include "frame/rank_exchange.h"
#include "mpi/ranks.h"
#include "frame/renderer.h"
#include "opsila_shared.h"

namespace opsila {

namespace frame_kernels {
using Buf = cl::Buffer;
// The kernels of the frame, their parameters as the host passes them.
// kernels/item_buffer.cl: frame, clusters (nearest first), their distances
// from the eye, projected boxes and their union, bank nodes and facets, tile
// side, the traced tiles' first column and row, tiles per row, first tile,
// sample offsets, mode, and the item buffer with its hits, distances and
// hit order keys.
using ItemBufferKernel = KernelBinding<FrameParams, Buf, Buf, Buf, cl_int4, Buf, Buf, int, cl_int2, int, int, float,
                                       float, int, Buf, Buf, Buf, Buf>;
// kernels/primary.cl: the hit list's two passes (frame, item buffer hits,
// pixels, traced rectangle, first pass, per-block hits, pixel sums; item
// buffer hits, pixels, traced rectangle, per-block prefixes, hit list);
// then frame, PE table, hit list, item hits and
// distances, hits in the list, sample offsets, pool offset, the pool,
// primary hit count.
using CountHitsKernel = KernelBinding<FrameParams, Buf, int, cl_int4, int, Buf, Buf>;
using ListHitsKernel = KernelBinding<Buf, int, int, cl_int4, Buf, Buf>;
using PrimaryKernel = KernelBinding<FrameParams, Buf, Buf, Buf, Buf, int, int, float, float, int, DescriptorSet, Buf>;
// kernels/spmd_phase.cl: frame, PE table, clusters, routing boxes, routing,
// bank nodes, facets, materials, lights, surface, banks, the exchange's
// work-group table and bank ranges, outputs and their counts, pixel sums,
// statistics, traffic and its levels, and the pilots' cluster work.
using SpmdKernel = KernelBinding<FrameParams, Buf, Buf, Buf, int, Buf, Buf, Buf, Buf, SurfaceBuffers, DescriptorSet,
                                 Buf, Buf, Buf, Buf, DescriptorSet, Buf, Buf, Buf, Buf, int, Buf, Buf, Buf>;
// All of them, from one program (frame_prepare.cpp).
struct Set {
  ItemBufferKernel item;
  CountHitsKernel count_hits;
  ListHitsKernel list_hits;
  PrimaryKernel primary;
  SpmdKernel spmd;
  bool built = false;
  Set() = default;
  Set(ClRuntime& rt, KernelProgram program);
};
}  // namespace frame_kernels

// Everything the machine keeps between frames, and the stages of a frame.
struct Renderer::Machine {
  ClRuntime& rt;
  // P PEs in all; with several MPI ranks this device holds the G PEs of its
  // group (pe_group.h) and only their banks.
  Ranks solo;    // one process, when the settings name no ranks
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
  PinnedHostBuffer accum_host;
  std::vector<float> offsets;     // (i + 0.5) / k, i = 0..k-1
  Progress* progress = nullptr;
  // OPSILA_FAULT_ROUND=K: a device fault reported at round K of every frame
  // (what a GPU reset or CL_OUT_OF_RESOURCES mid-frame looks like), so the
  // tests can show how a failure among running ranks ends them all.
  int fault_round = -1;
  FlightPlan flight{1, 1, 1, 1};
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
  frame_kernels::Set work_kernels, ray_kernels;
  bool counting = true;
  int counted_traffic_levels = 0;  // traffic_levels of a counting frame (the buffer's size)
  frame_kernels::Set& kernels() { return counting ? work_kernels : ray_kernels; }
  std::unique_ptr<ScatterPass> scatter;
  cl::Buffer b_tris, b_nodes, b_clusters, b_route, b_pes, b_mats, b_lights, b_rects, b_item_clusters, b_item_near;
  SurfaceBuffers surface;  // vertex attributes and texture copies of the banks
  cl::Buffer b_items, b_item_tri, b_item_t, b_item_key, b_accum, b_stats, b_traffic, b_out_count, b_hits;
  cl::Buffer b_hit_pixels, b_hit_blocks, b_hit_total;  // the hit list (kernels/primary.cl)
  // Pilot frames (measure_cost): each cluster's tests per level, and what
  // maps them back to the scene's facets (every cluster's, on every rank).
  bool measure = false;
  cl::Buffer b_node_cluster, b_tri_cluster, b_cost;
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
  cl_int4 listed_rect{};         // their union: a tile outside it lists no cluster
  // The pixels the item buffer traces (x0, y0, x1, y1, inclusive): on one
  // device, when the frame gives no item buffer, the union above within the
  // image (empty when no cluster is listed); else the whole image. A pixel
  // outside it is a miss that no kernel touches: read_image gives it the
  // background's sum.
  cl_int4 traced_rect{};
  std::vector<float> srgb;       // sRGB decode table
  std::vector<int> no_cluster{-1};
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
  };

  Machine(const Scene& scene, PreparedBanks banks, const RenderSettings& settings, ClRuntime& runtime);
  int choose_bank_capacity(const BankedScene& bs, const RenderSettings& settings);
  void choose_work_groups();
  void host_tables(const Scene& scene, BankedScene& bs);
  void describe_prepared(const PreparedBanks& banks);
  std::vector<BufferSpec> buffer_table(const BankedScene& bs, const FlightPlan& f);
  void allocate();

  void clear_frame();
  void item_buffer(Launcher& launch, int sample);
  std::size_t list_hits(Launcher& launch, int sample);
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

// "Projected object boxes" of the item buffer (frame_buffers.cpp).
std::vector<cl_int4> cluster_rects(const Scene& scene, const BankedScene& bs);
cl_int4 rects_union(const std::vector<cl_int4>& rects);
// Cluster indices by the distance from the eye to their boxes, nearest first
// (ties by index): the item buffer meets near hits first and culls behind
// them; any order gives the same items (kernels/hit_order.h).
std::vector<int> item_depth_order(const Scene& scene, const BankedScene& bs, std::vector<double>* distance = nullptr);

}  // namespace opsila
