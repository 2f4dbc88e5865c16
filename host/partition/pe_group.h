// Groups of PEs: with R MPI ranks, the P PEs are split into R contiguous
// groups, one per rank (and per OpenCL device). Every rank partitions the
// scene identically (partition_scene is deterministic) and then keeps only
// its own banks, so each device holds about 1/R of the scene plus the small
// global tables every PE knows.
#pragma once

#include <cstdint>
#include <vector>

#include "partition/partition.h"

namespace opsila {

struct PeGroup {
  int rank = 0, ranks = 1;
  int begin = 0, end = 0;  // PEs [begin, end)
  int size() const { return end - begin; }
  bool all() const { return ranks == 1; }
};

// Group of `rank` among `ranks`: PEs [rank*P/R, (rank+1)*P/R). Throws
// InputError when there are more ranks than PEs.
PeGroup pe_group(int num_pes, int ranks, int rank);
// The rank holding PE `pe`.
int rank_of_pe(int num_pes, int ranks, int pe);
// The rank of every PE, in PE order.
std::vector<int> devices_of_pes(int num_pes, int ranks);

// Drops every bank outside the group from `bs` (facets, BVH nodes) and
// renumbers what is left from 0: BVH links and the node ranges in the
// cluster and PE tables become local to the device; PE facet ranges stay
// global, since descriptors name facets by their global index. Returns the
// global index of the group's first facet (FrameParams::tri_base).
// bank_bytes, global_bytes and replicated_bytes keep describing the whole scene.
int keep_group_banks(BankedScene& bs, const PeGroup& group);

}  // namespace opsila
