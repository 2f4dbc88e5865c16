// A scene that gives its triangles up to the banks (PartitionUse::release)
// gets the same banks as one that keeps them: the triangles are put in the
// banks' order in place and handed back a batch at a time, and the scene
// keeps its figures (count, bounds, epsilon) for the frame.
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "formats/json/primitives.h"
#include "partition/partition.h"
#include "test_scenes.h"

namespace opsila {
namespace {

template <class V>
std::vector<unsigned char> bytes(const V& v) {
  const auto* p = reinterpret_cast<const unsigned char*>(v.data());
  return std::vector<unsigned char>(p, p + v.size() * sizeof(v[0]));
}

void expect_release_changes_nothing(const Scene& kept, int pes) {
  const BankedScene a = partition_scene(kept, pes);
  Scene given = kept;
  PartitionUse use;
  use.release = &given;
  const BankedScene b = partition_scene(given, pes, false, nullptr, nullptr, use);
  EXPECT_TRUE(given.triangles.empty()) << "the triangles went to the banks";
  EXPECT_TRUE(given.attributes.empty());
  EXPECT_EQ(given.total_triangles(), kept.triangles.size());
  Vec3 lo0, hi0, lo1, hi1;
  kept.bounds(lo0, hi0);
  given.bounds(lo1, hi1);
  EXPECT_EQ(std::memcmp(&lo0, &lo1, sizeof lo0), 0);
  EXPECT_EQ(std::memcmp(&hi0, &hi1, sizeof hi0), 0);
  EXPECT_EQ(kept.epsilon(), given.epsilon());
  ASSERT_EQ(a.triangles.size(), kept.triangles.size());
  EXPECT_EQ(bytes(a.triangles), bytes(b.triangles));
  EXPECT_EQ(bytes(a.nodes), bytes(b.nodes));
  EXPECT_EQ(bytes(a.clusters), bytes(b.clusters));
  EXPECT_EQ(bytes(a.route_nodes), bytes(b.route_nodes));
  EXPECT_EQ(bytes(a.pes), bytes(b.pes));
  EXPECT_EQ(bytes(a.attributes), bytes(b.attributes));
  EXPECT_EQ(bytes(a.textures), bytes(b.textures));
  EXPECT_EQ(bytes(a.texels), bytes(b.texels));
  EXPECT_EQ(a.bank_bytes, b.bank_bytes);
  // A frame's banks keep no pilot maps: 4 bytes a facet each.
  EXPECT_TRUE(b.source.empty() && b.tri_cluster.empty() && b.node_cluster.empty());
}

TEST(PartitionRelease, GivenUpTrianglesMakeTheSameBanks) {
  expect_release_changes_nothing(test::mirror_glass_scene(16, 4), 13);
}

TEST(PartitionRelease, VertexAttributesFollowTheFacetsWithoutThem) {
  const Scene s = test::textured_smooth_scene(16, true);
  ASSERT_FALSE(s.attributes.empty());
  expect_release_changes_nothing(s, 7);
}

// Large enough for two batches (kReleaseBatch facets): the second is
// filled after the first one's pages were handed back.
TEST(PartitionRelease, ATerrainFilledInBatches) {
  Scene s;
  const int ground = test::add_material(s, {0.5f, 0.5f, 0.5f}, {0.5f, 0.5f, 0.5f}, {0, 0, 0}, 1, {0, 0, 0}, 1, 2);
  TerrainDesc t;
  t.size_x = 60, t.size_z = 30;
  t.quads_x = 1100, t.quads_z = 500;
  t.height = 4;
  s.num_facets = add_terrain(s.triangles, t, 0, ground, ground, 0);
  test::add_sphere(s, {0, 6, 0}, 3, 3, 1, ground);
  s.num_objects = 2;
  ASSERT_GT(s.triangles.size(), std::size_t(1) << 20);
  expect_release_changes_nothing(s, 16);
}

// Pilot frames read the maps from bank facets to clusters and scene facets.
TEST(PartitionRelease, PilotMapsOnlyWhenAsked) {
  const Scene s = test::mirror_glass_scene(16, 4);
  PartitionUse use;
  use.pilot_maps = true;
  const BankedScene bs = partition_scene(s, 5, false, nullptr, nullptr, use);
  ASSERT_EQ(bs.source.size(), s.triangles.size());
  ASSERT_EQ(bs.tri_cluster.size(), s.triangles.size());
  ASSERT_EQ(bs.node_cluster.size(), bs.nodes.size());
  for (std::size_t k = 0; k < bs.source.size(); ++k)
    EXPECT_EQ(bs.triangles[k].facet_id, s.triangles[std::size_t(bs.source[k])].facet_id);
}

}  // namespace
}  // namespace opsila
