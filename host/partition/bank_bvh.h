// Wide bounding-volume hierarchies (BankNode, kernels/opsila_shared.h):
//  - the bank BVH of each PE: its clusters at the top (each cluster keeps a
//    node of its own, where the item buffer starts), its facets below;
//  - the routing BVH of each PE: its cluster boxes, one cluster per leaf,
//    which every PE knows and traverses to choose destinations.
// Both are binned-SAH binary trees collapsed into OPSILA_BVH_WIDTH-wide
// nodes, with every root-to-leaf path bounded so that the kernels' private
// stack of OPSILA_BVH_STACK entries never overflows.
#pragma once

#include <utility>
#include <vector>

#include "core/vec.h"
#include "partition/bank_array.h"
#include "opsila_shared.h"

namespace opsila {

// Builds the BVH of one bank whose clusters [c_begin, c_end) own the facets
// tris[ranges[c].first, ranges[c].second) (their boxes are made here, one
// bank's at a time). Facets are reordered inside each cluster's range;
// clusters[c].root is set. The bank's root is appended first, so it is the
// first node added. Returns the depth of the wide tree (0 when the bank is
// empty). Each non-empty array of `follow` holds one value per facet and is
// reordered with them (so per-facet data elsewhere can follow them).
using FacetFollowers = std::vector<std::vector<int>*>;
int build_bank_bvh(BankArray<BankNode>& nodes, BankArray<BankTriangle>& tris, std::vector<Cluster>& clusters,
                   int c_begin, int c_end, const std::vector<std::pair<int, int>>& ranges,
                   const FacetFollowers& follow = {});

// Every PE's bank BVH at once, on the host threads (core/parallel.h):
// pe_clusters[p] is PE p's cluster range; its nodes are appended to `nodes`
// in PE order, exactly as successive build_bank_bvh calls would lay them
// out (a stage of its own, core/stage_clock.h).
struct BankBvh {
  int node_begin = 0, node_end = 0, depth = 0;
};
std::vector<BankBvh> build_bank_bvhs(BankArray<BankNode>& nodes, BankArray<BankTriangle>& tris,
                                     std::vector<Cluster>& clusters,
                                     const std::vector<std::pair<int, int>>& pe_clusters,
                                     const std::vector<std::pair<int, int>>& ranges, const FacetFollowers& follow);

// Builds the routing BVH of one PE over `boxes` (one per cluster, ids in
// `cluster_ids`) into nodes[root] (already allocated; an empty PE keeps a
// root with only empty slots). Children are appended to `nodes`.
void build_route_bvh(BankArray<BankNode>& nodes, int root, const std::vector<Box>& boxes,
                     const std::vector<int>& cluster_ids);

// A node with every child slot empty (count -1). An empty slot's box is
// inverted (lo = +inf, hi = -inf): every slab distance pair is then
// (+inf, -inf), so no ray meets it and the node tests of the bank and
// routing walks need not read the counts (kernels/lib/walk.cl).
BankNode empty_node();

// The union of a node's child boxes (its slots in use), in the nodes' own
// floats: a box that a ray misses, under the same slab test, holds no child
// box the ray meets. False when the node has no slot in use.
bool children_box(const BankNode &node, Box &box);

}  // namespace opsila
