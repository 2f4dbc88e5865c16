// The ranks agree on one triangle limit: the smallest host memory among
// them, with where it came from, so that each reads the scene's budget
// alike.
#include <gtest/gtest.h>

#include <mutex>
#include <vector>

#include "prepare/scene_limits.h"
#include "sim_ranks.h"

namespace opsila {
namespace {

constexpr std::uint64_t kGiB = std::uint64_t(1) << 30;

TEST(SceneLimits, RanksWithDifferentMemoryAgreeOnTheSmallest) {
  // Rank r's host has (8 - r % 3) GiB available, shared by two ranks.
  std::mutex m;
  std::vector<HostMemory> agreed;
  test::run_ranks(4, [&](Ranks& ranks) {
    const HostMemory mine = host_memory_of(0, (8 - std::uint64_t(ranks.rank() % 3)) * kGiB, 2);
    const HostMemory a = agree_host_memory(ranks, mine);
    std::lock_guard<std::mutex> lock(m);
    agreed.push_back(a);
  });
  ASSERT_EQ(agreed.size(), 4u);
  for (const HostMemory& a : agreed) {
    EXPECT_EQ(a.bytes, 3 * kGiB) << "rank 2's 6 GiB over its host's two ranks";
    EXPECT_EQ(a.available, 6 * kGiB);
    EXPECT_EQ(a.local_ranks, 2);
    EXPECT_FALSE(a.from_flag);
    EXPECT_EQ(TriangleLimit::of_memory(a).triangles, triangles_for_memory(3 * kGiB));
  }
}

TEST(SceneLimits, TheFlagGivesEveryRankItsLimit) {
  std::mutex m;
  std::vector<TriangleLimit> limits;
  test::run_ranks(3, [&](Ranks& ranks) {
    const TriangleLimit limit = host_triangle_limit(ranks, kGiB);
    std::lock_guard<std::mutex> lock(m);
    limits.push_back(limit);
  });
  for (const TriangleLimit& l : limits) {
    EXPECT_EQ(l.triangles, triangles_for_memory(kGiB));
    EXPECT_TRUE(l.memory.from_flag);
    EXPECT_EQ(l.why, TriangleLimit::Why::memory);
  }
  OneProcess solo;
  const TriangleLimit alone = host_triangle_limit(solo, 0);
  EXPECT_FALSE(alone.memory.from_flag);
  EXPECT_EQ(alone.memory.local_ranks, 1);
  EXPECT_GT(alone.memory.available, 0u) << "what this host has available";
}

}  // namespace
}  // namespace opsila
