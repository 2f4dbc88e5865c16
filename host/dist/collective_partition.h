// The collective partition of a scene read in shares (Scene::share,
// docs/DISTRIBUTED.md). Every rank holds
// whole objects of the scene and its windows of the spread ones; together
// the ranks build exactly the banks partition_scene builds from the whole
// scene, each rank only its group's:
//  1. each rank cuts its own objects into clusters (partition/partition_split.cpp),
//     the spread ones together (dist/collective_cut.cpp);
//  2. the clusters' centres, boxes and sizes (a small table) go to every
//     rank, which runs the same bisection into PE regions on it;
//  3. each cluster's facets move to the rank that holds its PE, in chunks
//     of bounded size (MPI_Alltoallv);
//  4. each rank builds its banks; the cluster spheres and boxes, the PE
//     table and every bank's size go to every rank, which builds the
//     routing tables from them.
#pragma once

#include "partition/banks.h"
#include "dist/collective_cut.h"
#include "mpi/ranks.h"

namespace opsila {

// How the partition shares the scene: by facets (--balance facets), or by
// the work pilot frames measured (--balance measured, per facet of this
// rank's share, dist/pilot.h).
struct ShareBalance {
  const MeasuredWork* measured = nullptr;
  // Or --balance work: the frame's rays, sampled by the ranks together
  // (share_ray_sample, dist/collective_balance.h).
  const RaySample* sample = nullptr;
  // The pilots partition the share again and again: it keeps its facets
  // (held beside the banks while the pilots run, about twice the rank's
  // facets), and PreparedBanks::facet_cluster gets each one's cluster.
  bool keep_share = false;
  // The banks are a pilot frame's: they keep the maps from bank facets to
  // clusters and share facets (BalancePolicy::pilot).
  bool pilot = false;
  // The same: the clusters the objects are cut into before the balance's
  // cuts depend on the geometry alone, so the first call makes them into
  // *clusters (when given) and the next ones, with `reuse`, copy them (the
  // last, which does not keep the share, takes them); every rank alike:
  // the cuts of a spread object are collective.
  ShareClusters* clusters = nullptr;
  bool reuse = false;
};

// The banks of `group`, as bank_scene(whole scene) prepares them with the
// same balance, built by every rank of `ranks` together from their shares
// (a collective call: a failure inside it ends every rank).
// The share's facets (triangles and vertex attributes) are given up once
// they are sent (unless `how` keeps them): the banks are built from what
// the rank received.
PreparedBanks bank_share(Scene& share, int num_pes, int routing, const PeGroup& group, Ranks& ranks,
                         const ShareBalance& how = ShareBalance{});

}  // namespace opsila
