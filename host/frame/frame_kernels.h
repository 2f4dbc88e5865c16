// The frame's kernels and their argument structs (device/kernel_args.h):
// each struct's kernel_args() follows its kernel's signature, and each of
// its buffers is a handle of its own role, declared here once (the
// exchange's in device/descriptors.h, the scene's in frame/scene_buffers.h).
#pragma once

#include <tuple>

#include "device/descriptors.h"
#include "device/kernel_args.h"
#include "frame/scene_buffers.h"
#include "opsila_shared.h"

namespace opsila {

// The global tables the routing reads: PE table, cluster spheres, routing
// boxes (kernels/lib/routing.cl, Routing).
using PeTable = DeviceArray<struct PeTableRole>;
using ClusterSpheres = DeviceArray<struct ClusterSpheresRole>;
using RouteBoxes = DeviceArray<struct RouteBoxesRole>;
struct RoutingTables {
  PeTable pes;
  ClusterSpheres clusters;
  RouteBoxes route;
  auto kernel_args() const { return std::tie(pes, clusters, route); }
};

// The item buffer's clusters, nearest the eye first, their distances from
// the eye and projected boxes, the boxes' union, and the bins that list
// them (frame.h, ItemBins).
struct ItemClusterList {
  DeviceArray<struct ItemClustersRole> clusters;
  DeviceArray<struct ItemClusterNearRole> near;
  DeviceArray<struct ClusterRectsRole> rects;
  cl_int4 listed{};
  DeviceArray<struct ItemBinFirstRole> bin_first;
  DeviceArray<struct ItemBinListRole> bin_list;
  int bin_side = 1, bins_x = 1;
  auto kernel_args() const { return std::tie(clusters, near, rects, listed, bin_first, bin_list, bin_side, bins_x); }
};

// The item buffer: (object, facet) pairs, and the nearest hit so far: its
// facet, distance and hit order key.
using ItemHits = DeviceArray<struct ItemHitsRole>;
using ItemDistances = DeviceArray<struct ItemDistancesRole>;
using ItemKeys = DeviceArray<struct ItemKeysRole>;
struct ItemArrays {
  DeviceArray<struct ItemPairsRole> items;
  ItemHits tri;
  ItemDistances t;
  ItemKeys key;
  auto kernel_args() const { return std::tie(items, tri, t, key); }
};

// The hit list of a sample pass (kernels/primary.cl): its pixels, the hits
// per block of pixels (then their prefixes), and its length.
using HitList = DeviceArray<struct HitListRole>;
using HitBlocks = DeviceArray<struct HitBlocksRole>;
using HitListLength = DeviceArray<struct HitListLengthRole>;

// Sums and counters of the frame.
using PixelSums = DeviceArray<struct PixelSumsRole>;
using StatCounters = DeviceArray<struct StatCountersRole>;
using TrafficCounters = DeviceArray<struct TrafficCountersRole>;
using PrimaryHitCount = DeviceArray<struct PrimaryHitCountRole>;
using ResolvedImage = DeviceArray<struct ResolvedImageRole>;  // three floats a pixel

// The pilots' cluster work: what maps nodes and facets to their clusters,
// and each cluster's tests per level (one-entry stand-ins elsewhere).
struct ClusterWork {
  DeviceArray<struct NodeClustersRole> node_cluster;
  DeviceArray<struct FacetClustersRole> tri_cluster;
  DeviceArray<struct ClusterCostRole> cost;
  auto kernel_args() const { return std::tie(node_cluster, tri_cluster, cost); }
};

namespace frame_kernels {

// kernels/item_buffer.cl: a launch over tiles tile_begin.. of the traced
// rectangle (tile_origin in tiles, tiles_x a row), for the sample at
// (ox, oy) in the pixel; mode: what it writes (OPSILA_ITEM_WRITE_*).
struct ItemBufferArgs {
  FrameParams fp{};
  ItemClusterList clusters;
  BankGeometry geometry;
  int tile_w = 1;
  cl_int2 tile_origin{};
  int tiles_x = 0, tile_begin = 0;
  float ox = 0.5f, oy = 0.5f;
  int mode = 0;
  ItemArrays item;
  auto kernel_args() const {
    return std::tie(fp, clusters, geometry, tile_w, tile_origin, tiles_x, tile_begin, ox, oy, mode, item);
  }
};

// kernels/primary.cl, the hit list's two passes: hits per block (and, in
// the first pass, every pixel's sums), then the list from their prefixes.
struct CountHitsArgs {
  FrameParams fp{};
  ItemHits hits;
  int npix = 0;
  cl_int4 traced{};
  int first_pass = 0;
  HitBlocks block_hits;
  PixelSums accum;
  auto kernel_args() const { return std::tie(fp, hits, npix, traced, first_pass, block_hits, accum); }
};
struct ListHitsArgs {
  ItemHits hits;
  int npix = 0, width = 0;
  cl_int4 traced{};
  HitBlocks block_first;
  HitList list;
  auto kernel_args() const { return std::tie(hits, npix, width, traced, block_first, list); }
};
// kernels/primary.cl, PrimaryBuild: hits first.. first + count - 1 of the
// list, written into the pool from slot `offset` on, by build_primary or
// by the SPMD launch's first work-groups, before its phase's (spmd_groups).
struct PrimaryBuildArgs {
  HitList list;
  ItemHits hits;
  ItemDistances distances;
  ItemKeys keys;
  int first = 0, count = 0;
  float ox = 0.5f, oy = 0.5f;
  int offset = 0;
  DescriptorSet pool;
  PrimaryHitCount hit_count;
  auto kernel_args() const { return std::tie(list, hits, distances, keys, first, count, ox, oy, offset, pool, hit_count); }
};
struct PrimaryArgs {
  FrameParams fp{};
  PeTable pes;
  InstanceTable insts;
  PrimaryBuildArgs build;
  auto kernel_args() const { return std::tie(fp, pes, insts, build); }
};

// kernels/resolve.cl: the pixel sums to the image, as MeanDecoder decodes
// them; background: the sums of a pixel outside the traced rectangle.
struct ResolveArgs {
  PixelSums accum;
  int npix = 0, width = 0;
  cl_int4 traced{};
  cl_ulong4 background{};
  double divisor = 1, inverse = 1;
  int exact = 0;
  ResolvedImage rgb;
  auto kernel_args() const { return std::tie(accum, npix, width, traced, background, divisor, inverse, exact, rgb); }
};

// kernels/spmd_phase.cl: the plan's work-groups, each on one PE's bank.
struct SpmdArgs {
  FrameParams fp{};
  RoutingTables routing;
  int routing_mode = OPSILA_ROUTING_BOXES;
  BankGeometry geometry;
  ShadingTables shading;
  DescriptorSet banks;
  WorkGroupTable groups;
  BankRanges bank_ranges;
  DescriptorSet outputs;
  OutputCounts out_count;
  PixelSums accum;
  StatCounters stats;
  TrafficCounters traffic;
  int traffic_levels = 0;
  ClusterWork work;
  int spmd_groups = 0;       // the phase's work-groups; any before them build
  PrimaryBuildArgs primary;  // the next round's primary descriptors (count 0: none)
  auto kernel_args() const {
    return std::tie(fp, routing, routing_mode, geometry, shading, banks, groups, bank_ranges, outputs, out_count, accum,
                    stats, traffic, traffic_levels, work, spmd_groups, primary);
  }
};

using ItemBufferKernel = KernelBinding<ItemBufferArgs>;
using CountHitsKernel = KernelBinding<CountHitsArgs>;
using ListHitsKernel = KernelBinding<ListHitsArgs>;
using PrimaryKernel = KernelBinding<PrimaryArgs>;
using SpmdKernel = KernelBinding<SpmdArgs>;
using ResolveKernel = KernelBinding<ResolveArgs>;

// All of them, from one program (frame_prepare.cpp).
struct Set {
  ItemBufferKernel item;
  CountHitsKernel count_hits;
  ListHitsKernel list_hits;
  PrimaryKernel primary;
  SpmdKernel spmd;
  ResolveKernel resolve;  // only where the device has doubles (ClRuntime::doubles)
  bool built = false;
  Set() = default;
  Set(ClRuntime& rt, KernelProgram program);
};

}  // namespace frame_kernels
}  // namespace opsila
