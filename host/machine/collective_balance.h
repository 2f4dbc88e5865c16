// The cluster table of a scene read in shares (docs/DISTRIBUTED.md), with
// what --balance measured adds to it: each cluster's measured work, and
// region_weights' cuts of the clusters too hot for one PE, made by the
// ranks together so that the table every rank bisects into PE regions is
// the one one process bisects, in the same order, with the same figures.
// Internal to host/machine (machine/collective_partition.cpp).
#pragma once

#include <cstdint>
#include <cstring>
#include <vector>

#include "core/ray_sample.h"
#include "machine/collective_cut.h"

namespace opsila {

// Records sent between ranks as bytes (trivially copyable types).
template <typename T>
std::vector<unsigned char> bytes_of(const std::vector<T>& v) {
  std::vector<unsigned char> b(v.size() * sizeof(T));
  if (!v.empty()) std::memcpy(b.data(), v.data(), b.size());
  return b;
}

template <typename T>
std::vector<T> records_of(const std::vector<unsigned char>& b) {
  std::vector<T> v(b.size() / sizeof(T));
  if (!v.empty()) std::memcpy(v.data(), b.data(), v.size() * sizeof(T));
  return v;
}

// One cluster as every rank learns it: enough to place it in a region and
// to find its facets (rank, index in that rank's list).
struct ClusterSummary {
  std::int32_t object = 0, rank = 0, local = 0;  // a spread cluster: rank 0, local its index in ShareClusters::spread
  std::int32_t spread = 0;                        // 1: its facets lie on several ranks
  std::uint64_t facets = 0;
  float c[3] = {0, 0, 0}, lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
};

// Every cluster of the scene in partition_scene's order (by object, then
// the order the cuts made them; region_weights' pieces after), and with
// measured work each one's sums per level in fixed point
// (partition_steps::measured_sums): work[k * levels + l].
struct ClusterTable {
  std::vector<ClusterSummary> clusters;
  int levels = 0;
  std::vector<std::int64_t> work;
};

// The table from every rank's clusters (MPI_Allgatherv); `measured` (may
// be null: none) is per facet of this rank's share.
ClusterTable gather_clusters(const Scene& share, const ShareClusters& split, const MeasuredWork* measured,
                             Ranks& ranks);

// region_weights' cuts on a share: pass after pass, every cluster hotter
// than half a PE's share of the pass's work is cut at its median by its
// owner (a spread one by every rank, collective_cut.h), the pieces' figures
// gathered to every rank and put where one process puts them (the lower
// half in the cluster's place, the upper ones after every cluster, in
// order). `split` gets the pieces' facets.
void cut_hot_clusters(const Scene& share, const MeasuredWork& measured, int num_pes, ShareClusters& split,
                      ClusterTable& table, Ranks& ranks);

}  // namespace opsila
