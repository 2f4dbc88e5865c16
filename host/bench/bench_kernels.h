// The baselines' kernels (kernels/baselines/*.cl) and their argument
// structs (device/kernel_args.h): each struct's kernel_args() follows its
// kernel's signature, and each buffer is a handle of its own role.
#pragma once

#include <array>
#include <tuple>

#include "device/descriptors.h"
#include "device/kernel_args.h"
#include "frame/scene_buffers.h"
#include "opsila_shared.h"

namespace opsila {

// The root of the one BVH over the whole scene's own facets, its
// children's box (kernels/lib/bvh.cl, scene_nearest), and the root of the
// BVH over its instances (-1: none).
struct SceneRoot {
  int node = 0;
  cl_float4 lo{}, hi{};
  int instances = -1;
  auto kernel_args() const { return std::tie(node, lo, hi, instances); }
};

// kernels/baselines/megakernel.cl: one launch over pixels pixel_begin..
// of the image, spp_k x spp_k samples each at `offsets`; its pixel sums
// (64-bit), ray counts per pixel, and the item buffer when write_items.
using SampleOffsets = DeviceArray<struct SampleOffsetsRole>;
using MegaPixelSums = DeviceArray<struct MegaPixelSumsRole>;
using MegaRayCounts = DeviceArray<struct MegaRayCountsRole>;
using MegaItems = DeviceArray<struct MegaItemsRole>;
struct MegaArgs {
  FrameParams fp{};
  BankGeometry geometry;
  ShadingTables shading;
  SceneRoot root;
  int spp_k = 1;
  SampleOffsets offsets;
  int pixel_begin = 0, pixel_count = 0;
  MegaPixelSums accum;
  MegaRayCounts counts;
  int write_items = 0;
  MegaItems items;
  auto kernel_args() const {
    return std::tie(fp, geometry, shading, root, spp_k, offsets, pixel_begin, pixel_count, accum, counts,
                    write_items, items);
  }
};
// megakernel_rays: the same, and every ray written to the log from
// 2 * log_first[pixel] on.
struct MegaRaysArgs {
  MegaArgs frame;
  DeviceArray<struct RayLogFirstRole> log_first;
  DeviceArray<struct RayLogRole> log;
  auto kernel_args() const { return std::tie(frame, log_first, log); }
};
// megakernel_stages (the stage-cycle program): the same, and every
// work-item's cycles and clock readings per stage added to `cycles`
// (OPSILA_STAGE_COUNTERS 64-bit counters).
struct MegaStagesArgs {
  MegaArgs frame;
  DeviceArray<struct StageCyclesRole> cycles;
  auto kernel_args() const { return std::tie(frame, cycles); }
};

// kernels/baselines/traversal.cl: `count` rays (two float4 each), one
// answer word per ray.
struct TraversalArgs {
  BankGeometry geometry;
  SceneRoot root;
  float slack = 0;
  DeviceArray<struct TraversalRaysRole> rays;
  int count = 0;
  DeviceArray<struct TraversalAnswersRole> hits;
  auto kernel_args() const { return std::tie(geometry, root, slack, rays, count, hits); }
};

// kernels/baselines/copy.cl: the paper's scatter Vd(index(i)) = Vs(i) on
// its six vectors (pixel and PE, level, direct intensity, direction,
// coefficient, destination), on one record per descriptor, and a plain copy.
using ScatterIndex = DeviceArray<struct ScatterIndexRole>;
struct PaperVectors {
  std::array<cl::Buffer, 6> v;  // in the order above
  auto kernel_args() const { return std::tie(v[0], v[1], v[2], v[3], v[4], v[5]); }
};
struct SixVectorsArgs {
  int count = 0;
  ScatterIndex index;
  PaperVectors from, to;
  auto kernel_args() const { return std::tie(count, index, from, to); }
};
struct OneRecordArgs {
  int count = 0;
  ScatterIndex index;
  DescriptorRecords from, to;
  auto kernel_args() const { return std::tie(count, index, from, to); }
};
struct CopyArgs {
  cl::Buffer from, to;  // float4s
  int count = 0;
  auto kernel_args() const { return std::tie(from, to, count); }
};

}  // namespace opsila
