// The cluster table of a scene read in shares (docs/DISTRIBUTED.md), with
// what --balance measured or work adds to it: each cluster's heat, and
// region_weights' cuts of the clusters too hot for one PE, made by the
// ranks together so that the table every rank bisects into PE regions is
// the one one process bisects, in the same order, with the same figures.
// And the ray sample of --balance work, traced by the ranks together.
// Internal to host/machine (dist/collective_partition.cpp).
#pragma once

#include <cstdint>
#include <vector>

#include "scene/ray_sample.h"
#include "dist/collective_cut.h"
#include "mpi/ranks.h"

namespace opsila {

// One cluster as every rank learns it: enough to place it in a region and
// to find its facets (rank, index in that rank's list).
struct ClusterSummary {
  std::int32_t object = 0, rank = 0, local = 0;  // a spread cluster: rank 0, local its index in ShareClusters::spread
  std::int32_t spread = 0;                        // 1: its facets lie on several ranks
  std::uint64_t facets = 0;
  float c[3] = {0, 0, 0}, lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
};

// What a cluster's heat is made of (region_weights' on one process): the
// work pilot frames measured on its facets, per level, in fixed point
// (partition_steps::measured_sums), which the ranks holding parts of a
// spread cluster add up; or the sampled rays that cross its box, one
// figure, which every rank finds alike (the box is the whole cluster's).
// Neither: facets alone.
struct ShareHeat {
  const MeasuredWork* measured = nullptr;  // per facet of this rank's share
  const RaySample* sample = nullptr;
  int levels() const;
  bool summed() const { return measured != nullptr; }
  // This rank's figures for its facets `tris` of a cluster whose box is `box`.
  std::vector<std::int64_t> of(const std::vector<int>& tris, const Box& box) const;
};

// Every cluster of the scene in partition_scene's order (by object, then
// the order the cuts made them; region_weights' pieces after), and each
// one's heat (ShareHeat): work[k * levels + l].
struct ClusterTable {
  std::vector<ClusterSummary> clusters;
  int levels = 0;
  bool sampled = false;  // the heat is sampled rays (--balance work), not measured work
  std::vector<std::int64_t> work;
};

// The table from every rank's clusters (MPI_Allgatherv).
ClusterTable gather_clusters(const Scene& share, const ShareClusters& split, const ShareHeat& heat, Ranks& ranks);

// region_weights' cuts on a share: pass after pass, every cluster hotter
// than half a PE's share of the pass's work is cut at its median by its
// owner (a spread one by every rank, collective_cut.h), the pieces' figures
// gathered to every rank and put where one process puts them (the lower
// half in the cluster's place, the upper ones after every cluster, in
// order). `split` gets the pieces' facets.
void cut_hot_clusters(const Scene& share, const ShareHeat& heat, int num_pes, ShareClusters& split,
                      ClusterTable& table, Ranks& ranks);

// The ray sample of --balance work, traced by `sampler`
// (ReferenceTracer::sample_rays). On a scene read in shares every rank
// traces it through its own facets and the ranks join each level's hits (a
// collective call); the sample is one process's, on every rank.
RaySample balance_sample(const Scene& scene, const RaySampler& sampler, Ranks& ranks);

}  // namespace opsila
