// What only ran under mpirun before, run in one process: the groups of PEs
// of R ranks, the rank of a PE, the banks a rank keeps, and the rank x rank
// traffic built from the ranks' reports.
#include <gtest/gtest.h>

#include <set>
#include <vector>

#include "scene/scene.h"
#include "partition/banks.h"
#include "partition/pe_group.h"
#include "frame/stats.h"
#include "opsila_shared.h"
#include "test_scenes.h"

namespace opsila {
namespace {

TEST(PeGroup, RanksSplitThePesIntoContiguousNearlyEqualGroups) {
  for (int P : {1, 2, 7, 16, 64, 1000})
    for (int R = 1; R <= std::min(P, 9); ++R) {
      int next = 0;
      for (int r = 0; r < R; ++r) {
        const PeGroup g = pe_group(P, R, r);
        EXPECT_EQ(g.begin, next) << P << " PEs, " << R << " ranks, rank " << r;
        EXPECT_GE(g.size(), P / R);
        EXPECT_LE(g.size(), P / R + 1);
        EXPECT_EQ(g.all(), R == 1);
        for (int pe = g.begin; pe < g.end; ++pe) EXPECT_EQ(rank_of_pe(P, R, pe), r) << "PE " << pe;
        next = g.end;
      }
      EXPECT_EQ(next, P) << "every PE has a rank";
    }
  EXPECT_THROW(pe_group(3, 4, 0), InputError) << "more ranks than PEs";
}

// Each rank keeps its group's banks, renumbered from 0; together the ranks
// hold every facet once, and the global tables are the same on all.
TEST(PeGroup, EachRankKeepsItsOwnBanksAndTheGlobalTables) {
  const Scene s = test::mirror_glass_scene(16, 4);
  const int P = 8, R = 3;
  BalancePolicy pilot;
  pilot.pilot = true;  // facet_cluster too
  const PreparedBanks whole = bank_scene(s, P, OPSILA_ROUTING_BOXES, pilot, pe_group(P, 1, 0));
  ASSERT_EQ(whole.tri_base, 0);
  std::multiset<int> facets;
  for (int r = 0; r < R; ++r) {
    const PreparedBanks mine = bank_scene(s, P, OPSILA_ROUTING_BOXES, pilot, pe_group(P, R, r));
    const PeGroup& g = mine.group;
    EXPECT_EQ(mine.tri_base, whole.scene.pes[g.begin].tri_begin);
    EXPECT_EQ(int(mine.scene.triangles.size()), whole.scene.pes[g.end - 1].tri_end - mine.tri_base);
    EXPECT_EQ(mine.scene.clusters.size(), whole.scene.clusters.size()) << "every PE knows every cluster";
    EXPECT_EQ(mine.scene.bank_bytes, whole.scene.bank_bytes) << "bank sizes describe the whole scene";
    EXPECT_EQ(mine.facet_cluster, whole.facet_cluster);
    for (const BankTriangle& t : mine.scene.triangles) facets.insert(t.facet_id);
    for (const Cluster& c : mine.scene.clusters) {
      const bool own = c.pe >= g.begin && c.pe < g.end;
      EXPECT_EQ(c.root >= 0, own) << "a cluster of another rank has no root here";
      if (own) EXPECT_LT(c.root, int(mine.scene.nodes.size()));
    }
    for (const BankNode& node : mine.scene.nodes)
      for (int k = 0; k < OPSILA_BVH_WIDTH; ++k) {
        if (node.count[k] == 0) EXPECT_LT(node.child[k], int(mine.scene.nodes.size())) << "a local node";
        if (node.count[k] > 0) EXPECT_LE(node.child[k] + node.count[k], int(mine.scene.triangles.size()));
      }
  }
  std::multiset<int> all;
  for (const BankTriangle& t : whole.scene.triangles) all.insert(t.facet_id);
  EXPECT_EQ(facets, all) << "the ranks hold every facet once";
}

// The rank x rank traffic from what each rank says it sent and received.
TEST(RankTraffic, AddsUpTheReportsAndChecksThatTheyMirror) {
  std::vector<RankReport> reports(3);
  // Round 0: 0 -> 1 five, 1 -> 2 two; round 1: 2 -> 0 seven. Own PEs: diagonal.
  reports[0].sent = {{4, 5, 0}, {0, 0, 0}};
  reports[1].sent = {{0, 1, 2}, {0, 0, 0}};
  reports[2].sent = {{0, 0, 3}, {7, 0, 0}};
  reports[0].received = {{4, 0, 0}, {0, 0, 7}};
  reports[1].received = {{5, 1, 0}, {0, 0, 0}};
  reports[2].received = {{0, 2, 3}, {0, 0, 0}};
  RankTraffic t = rank_traffic(reports);
  EXPECT_TRUE(t.balanced);
  EXPECT_EQ(t.sent, 14u);
  EXPECT_EQ(t.received, 14u);
  EXPECT_EQ(t.total[0][1], 5u);
  EXPECT_EQ(t.total[2][0], 7u);
  EXPECT_EQ(t.rounds[1][2][0], 7u);
  EXPECT_EQ(t.sent_by_rank, (std::vector<std::uint64_t>{5, 2, 7}));
  EXPECT_EQ(t.received_by_rank, (std::vector<std::uint64_t>{7, 5, 2}));
  reports[1].received[0][0] = 4;  // rank 1 got one record fewer than rank 0 sent
  t = rank_traffic(reports);
  EXPECT_FALSE(t.balanced);
}

}  // namespace
}  // namespace opsila
