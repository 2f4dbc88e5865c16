// The wide bank and routing BVHs (host/partition/bank_bvh.cpp) as the kernels
// read them: every facet under exactly one leaf, every child box around what
// it holds, cluster roots over their own facets, paths within the stack.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <limits>
#include <string>
#include <vector>

#include "formats/json/scene_file.h"
#include "partition/bank_bvh.h"
#include "partition/partition.h"
#include "opsila_shared.h"
#include "test_scenes.h"

namespace opsila {
namespace {

bool inside(const BankNode& n, int k, const float* p) {
  return p[0] >= n.lo_x[k] && p[0] <= n.hi_x[k] && p[1] >= n.lo_y[k] && p[1] <= n.hi_y[k] && p[2] >= n.lo_z[k] &&
         p[2] <= n.hi_z[k];
}

// An empty slot's box is inverted (lo = +inf, hi = -inf): the bank walks'
// node test then never meets it without reading its count.
bool inverted(const BankNode& n, int k) {
  const float inf = std::numeric_limits<float>::infinity();
  return n.lo_x[k] == inf && n.lo_y[k] == inf && n.lo_z[k] == inf && n.hi_x[k] == -inf && n.hi_y[k] == -inf &&
         n.hi_z[k] == -inf;
}

// Walks nodes[root]; counts facet visits, checks boxes; returns the stack need.
int walk(const BankedScene& bs, int node, std::vector<int>& seen) {
  const BankNode& n = bs.nodes[node];
  int k_used = 0, deeper = 0;
  for (int k = 0; k < OPSILA_BVH_WIDTH; ++k) {
    if (n.count[k] < 0) {
      EXPECT_TRUE(inverted(n, k)) << "node " << node << ", empty slot " << k << " has a box a ray can meet";
      continue;
    }
    ++k_used;
    if (n.count[k] > 0) {
      for (int i = n.child[k]; i < n.child[k] + n.count[k]; ++i) {
        ++seen[i];
        const BankTriangle& t = bs.triangles[i];
        EXPECT_TRUE(inside(n, k, t.v0) && inside(n, k, t.v1) && inside(n, k, t.v2)) << "facet " << i;
      }
    } else {
      const BankNode& c = bs.nodes[n.child[k]];
      for (int j = 0; j < OPSILA_BVH_WIDTH; ++j) {
        if (c.count[j] < 0) continue;
        float lo[3] = {c.lo_x[j], c.lo_y[j], c.lo_z[j]}, hi[3] = {c.hi_x[j], c.hi_y[j], c.hi_z[j]};
        EXPECT_TRUE(inside(n, k, lo) && inside(n, k, hi)) << "child box outside its parent's";
      }
      deeper = std::max(deeper, walk(bs, n.child[k], seen));
    }
  }
  EXPECT_GT(k_used, 0) << "node " << node << " has no child";
  return std::max(k_used, k_used - 1 + deeper);
}

// A partition weighted by sampled rays: still every facet once, and the same
// partition from the same rays.
TEST(BankBvh, WorkBalancedPartitionKeepsEveryFacetOnceAndIsDeterministic) {
  Scene s = test::mirror_glass_scene(32);
  RaySample sample;
  for (int i = 0; i < 200; ++i) {  // rays fanning from the camera side
    RaySegment r;
    r.origin = {0.0f, 0.0f, 10.0f};
    r.direction = {0.01f * float(i % 20) - 0.1f, 0.01f * float(i / 20) - 0.05f, -1.0f};
    sample.rays.push_back(r);
  }
  for (int pes : {4, 16}) {
    const BankedScene a = partition_scene(s, pes, false, &sample), b = partition_scene(s, pes, false, &sample);
    std::vector<int> seen(a.triangles.size(), 0);
    for (int p = 0; p < pes; ++p)
      if (a.pes[p].node_begin != a.pes[p].node_end) walk(a, a.pes[p].node_begin, seen);
    for (std::size_t i = 0; i < seen.size(); ++i) EXPECT_EQ(seen[i], 1) << "facet " << i << ", " << pes << " PEs";
    EXPECT_EQ(a.triangles.size(), s.triangles.size());
    EXPECT_EQ(a.bank_bytes, b.bank_bytes);
    ASSERT_EQ(a.triangles.size(), b.triangles.size());
    for (std::size_t i = 0; i < a.triangles.size(); ++i)
      EXPECT_EQ(a.triangles[i].facet_id, b.triangles[i].facet_id) << "bank order differs at " << i;
  }
}

TEST(BankBvh, EveryFacetOnceInsideItsBoxesWithinTheStack) {
  Scene s = test::mirror_glass_scene(32);
  for (int pes : {1, 4, 16}) {
    BankedScene bs = partition_scene(s, pes);
    std::vector<int> seen(bs.triangles.size(), 0);
    for (int p = 0; p < pes; ++p) {
      if (bs.pes[p].node_begin == bs.pes[p].node_end) continue;
      EXPECT_LE(walk(bs, bs.pes[p].node_begin, seen), OPSILA_BVH_STACK) << "PE " << p;
    }
    for (std::size_t i = 0; i < seen.size(); ++i) EXPECT_EQ(seen[i], 1) << "facet " << i << ", " << pes << " PEs";
    // A cluster's root reaches exactly its own facets (the item buffer starts there).
    for (std::size_t c = 0; c < bs.clusters.size(); ++c) {
      std::vector<int> mine(bs.triangles.size(), 0);
      walk(bs, bs.clusters[c].root, mine);
      const int begin = static_cast<int>(std::find(mine.begin(), mine.end(), 1) - mine.begin());
      int count = 0;
      for (int v : mine) count += v;
      for (int i = begin; i < begin + count; ++i) EXPECT_EQ(mine[i], 1) << "cluster " << c;
      EXPECT_GT(count, 0) << "cluster " << c;
    }
  }
}

TEST(BankBvh, RoutingTreesHoldEachClusterOfTheirPeOnceAroundItsBox) {
  Scene s = test::mirror_glass_scene(32);
  BankedScene bs = partition_scene(s, 16);
  ASSERT_GE(bs.route_nodes.size(), 16u);
  std::vector<int> seen(bs.clusters.size(), 0);
  for (int p = 0; p < 16; ++p) {
    std::vector<int> stack = {p};
    while (!stack.empty()) {
      const BankNode& n = bs.route_nodes[stack.back()];
      stack.pop_back();
      for (int k = 0; k < OPSILA_BVH_WIDTH; ++k) {
        if (n.count[k] < 0) continue;
        if (n.count[k] == 0) {
          stack.push_back(n.child[k]);
          continue;
        }
        ASSERT_EQ(n.count[k], 1);
        const Cluster& c = bs.clusters[n.child[k]];
        EXPECT_EQ(c.pe, p);
        ++seen[n.child[k]];
        // Padded: strictly around the cluster's box.
        EXPECT_TRUE(n.lo_x[k] < c.bmin[0] && n.lo_y[k] < c.bmin[1] && n.lo_z[k] < c.bmin[2]);
        EXPECT_TRUE(n.hi_x[k] > c.bmax[0] && n.hi_y[k] > c.bmax[1] && n.hi_z[k] > c.bmax[2]);
      }
    }
  }
  for (std::size_t c = 0; c < seen.size(); ++c) EXPECT_EQ(seen[c], 1) << "cluster " << c;
}

// The routing top level: PE q's box at node P + q / W, slot q % W, around
// every box of its root; absent for a PE without clusters.
TEST(BankBvh, RoutingTopLevelHoldsEachPeBoxAroundItsRoot) {
  Scene s = test::mirror_glass_scene(32);
  for (int pes : {3, 16, 64}) {  // 64 PEs leave some banks empty
    BankedScene bs = partition_scene(s, pes);
    const int W = OPSILA_BVH_WIDTH, top = (pes + W - 1) / W;
    ASSERT_GE(bs.route_nodes.size(), std::size_t(pes + top));
    for (int q = 0; q < pes; ++q) {
      const BankNode& t = bs.route_nodes[pes + q / W];
      const int k = q % W;
      const BankNode& root = bs.route_nodes[q];
      bool any = false;
      for (int j = 0; j < W; ++j) {
        if (root.count[j] < 0) continue;
        any = true;
        EXPECT_TRUE(t.lo_x[k] <= root.lo_x[j] && t.lo_y[k] <= root.lo_y[j] && t.lo_z[k] <= root.lo_z[j]) << q;
        EXPECT_TRUE(t.hi_x[k] >= root.hi_x[j] && t.hi_y[k] >= root.hi_y[j] && t.hi_z[k] >= root.hi_z[j]) << q;
      }
      EXPECT_EQ(t.count[k], any ? 1 : -1) << "PE " << q;
      if (any) EXPECT_EQ(t.child[k], q);
    }
    for (int k = pes % W == 0 ? W : pes % W; k < W; ++k) EXPECT_EQ(bs.route_nodes[pes + top - 1].count[k], -1);
  }
}

}  // namespace
}  // namespace opsila

namespace opsila {
namespace {

// The banks are built side by side on the host threads: the same bytes
// whatever the number of threads (OPSILA_THREADS), as one after another.
TEST(BankBvh, BanksBuiltInParallelAreTheSameBytes) {
  const Scene s = test::mirror_glass_scene(40);
  auto banked = [&](const char* threads) {
    ::setenv("OPSILA_THREADS", threads, 1);
    PartitionUse use;
    use.pilot_maps = true;  // `source` follows the facets
    BankedScene bs = partition_scene(s, 13, false, nullptr, nullptr, use);
    ::unsetenv("OPSILA_THREADS");
    return bs;
  };
  const BankedScene one = banked("1"), many = banked("5");
  auto bytes = [](const auto& v) {
    const auto* p = reinterpret_cast<const unsigned char*>(v.data());
    return std::vector<unsigned char>(p, p + v.size() * sizeof(v[0]));
  };
  ASSERT_GT(one.nodes.size(), 13u);
  EXPECT_EQ(bytes(one.nodes), bytes(many.nodes));
  EXPECT_EQ(bytes(one.triangles), bytes(many.triangles));
  EXPECT_EQ(bytes(one.clusters), bytes(many.clusters));
  EXPECT_EQ(bytes(one.pes), bytes(many.pes));
  ASSERT_EQ(one.source.size(), one.triangles.size());
  EXPECT_EQ(one.source, many.source);
}

}  // namespace
}  // namespace opsila
