// Pilot frames (--balance measured): before the real frame is prepared, the
// machine renders the same view at a reduced size on the same device, with
// the program that counts each cluster's ray-box and ray-facet tests per
// level (kernels/lib/bvh.cl, OPSILA_MEASURE_COST). The partition then shares
// that measured work among the PEs, level by level (partition/partition.h).
// The first pilot runs on the facets' partition. The work a cluster does
// depends on where it lies (which PE's bank, beside which clusters: a
// shadow ray stops at the first occluder, every visit to a PE pays its
// bank's top nodes), so each later pilot runs on the partition of the mean
// of the measurements so far and measures again; the frame gets the
// partition whose pilot measured the best occupancy (the facets' one
// included). Deterministic: the counts are integers from deterministic
// traversals, the partitions are deterministic functions of them.
#pragma once

#include <cstdint>
#include <vector>

#include "scene/ray_sample.h"
#include "scene/scene.h"
#include "device/cl_runtime.h"
#include "dist/collective_cut.h"
#include "scene/render_types.h"

namespace opsila {

// At most this many pixels per pilot frame: the image is shrunk by a whole
// factor in x and y until it has no more. On hundreds, 2^13 to 2^17 pixels
// chose partitions of the same quality (docs/BENCHMARKS.md); the pilots'
// cost is mostly the partition and bank BVH build each one needs.
constexpr int kPilotPixels = 1 << 14;
// Pilot frames run; the measured occupancy does not rise steadily from one
// to the next (a partition cut moves many clusters at once), hence the
// choice of the best one.
constexpr int kPilotFrames = 5;

// What the pilot frames cost.
struct PilotFigures {
  int frames = 0;       // run
  double seconds = 0;   // their time
  // RenderSettings::pilot_warm_up: the first pilot frame's untimed run
  // before them (not in `seconds`).
  double warm_up_seconds = 0;
  // A scene read in shares: the most facets this rank held at once while
  // they ran, its share beside a pilot's banks (0 for a whole scene).
  std::uint64_t facets_held = 0;
};

// A pilot's per-cluster counts (Renderer::cluster_work, [level * C +
// cluster]) spread evenly over each cluster's facets: facet_cluster holds
// the cluster of every facet (PreparedBanks), facets (when given) every
// cluster's facet count over the whole scene, else counted from
// facet_cluster. Empty when nothing was counted. Each facet's figure
// depends only on its cluster's counts, so a rank holding part of the
// scene gets the figures one process gets for the same facets.
MeasuredWork spread_cluster_work(const std::vector<std::uint64_t>& work, int levels,
                                 const std::vector<int>& facet_cluster);
MeasuredWork spread_cluster_work(const std::vector<std::uint64_t>& work, int levels,
                                 const std::vector<int>& facet_cluster, const std::vector<std::uint64_t>& facets);

// The work measured by the pilot frames for `settings` (its PEs, routing
// and work-groups; one sample per pixel), per facet of `scene`. The pilots'
// view of a const scene is a copy of it (host memory for a second copy of
// its facets while they run); the overload below lends them out instead.
MeasuredWork pilot_work(const Scene& scene, const RenderSettings& settings, ClRuntime& runtime,
                        PilotFigures& figures);
// A scene read in shares: every rank runs the pilots together, each
// partition made collectively from the shares (dist/collective_partition.h),
// which keep their facets until the last pilot; the work is per facet of
// this rank's share. A whole scene: as above, its view copied without the
// facets, their attributes and the texture images (lent out meanwhile).
// `clusters` gets the share's clusters before the balance's cuts (the
// same for the frame's partition: ShareBalance::clusters).
MeasuredWork pilot_work(Scene& share, const RenderSettings& settings, ClRuntime& runtime, PilotFigures& figures,
                        ShareClusters& clusters);

}  // namespace opsila
