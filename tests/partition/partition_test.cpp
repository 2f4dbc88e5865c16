// The partition (host/partition/partition.cpp): scenes into clusters and
// clusters into banks, whatever the routing asks of the clusters.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "formats/json/scene_file.h"
#include "partition/partition.h"

namespace opsila {
namespace {

// With split_flat (routing on spheres), flat pieces are cut finer; the
// facets are the same, each in exactly one cluster.
TEST(Partition, FlatPiecesAreCutFinerForSphereRouting) {
  Scene s = load_scene(std::string(OPSILA_SOURCE_DIR) + "/scenes/hundreds.json");  // a 40 x 40 floor
  BankedScene plain = partition_scene(s, 16), fine = partition_scene(s, 16, true);
  EXPECT_GT(fine.clusters.size(), plain.clusters.size());
  EXPECT_EQ(fine.triangles.size(), plain.triangles.size());
  float largest_plain = 0, largest_fine = 0;
  for (const Cluster& c : plain.clusters) largest_plain = std::max(largest_plain, c.radius);
  for (const Cluster& c : fine.clusters) largest_fine = std::max(largest_fine, c.radius);
  EXPECT_LT(largest_fine, largest_plain);
}

}  // namespace
}  // namespace opsila
