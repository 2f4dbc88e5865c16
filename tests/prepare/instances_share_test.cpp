// A JSON scene with instances read in shares by simulated ranks
// (tests/sim_ranks.h): every rank keeps every model and placement, and the
// bounds the ranks join hold the instances, as one process's do.
#include <gtest/gtest.h>

#include <string>

#include "formats/json/scene_file.h"
#include "prepare/prepare.h"
#include "sim_ranks.h"

namespace opsila {
namespace {

// Instances far from the scene's own objects, so that only their boxes
// reach out there; and a scene of instances alone.
const char* const kWithFloor = R"({"objects": [
  {"type": "plane", "size": 10},
  {"type": "instances", "model": {"type": "box", "center": [0, 0, 0], "size": 1},
   "transforms": [{"translate": [100, 0, 0]}, {"translate": [0, -50, 0], "rotate": [0, 45, 0]}],
   "grid": {"counts": [3, 1, 2], "min": [-20, 5, 30], "max": [20, 5, 60], "jitter": 1, "scale": [1, 3], "seed": 2}},
  {"type": "grid", "counts": [3, 1, 1], "min": [-4, 1, -4], "max": [4, 1, 4], "radius": 0.5, "subdivisions": 0}]})";
const char* const kAlone = R"({"objects": [
  {"type": "instances", "model": {"type": "sphere", "center": [0, 0, 0], "radius": 1, "subdivisions": 1},
   "transforms": [{"translate": [-3, 0, 0]}, {"translate": [3, 0, 0]}]}]})";

TEST(InstancesShare, EveryRankKeepsEveryInstanceAndTheJoinedBoundsHoldThem) {
  for (const char* text : {kWithFloor, kAlone}) {
    SCOPED_TRACE(text);
    const Scene whole = load_scene_from_string(text, "s.json", "");
    Vec3 lo, hi;
    whole.bounds(lo, hi);
    test::run_ranks(3, [&](Ranks& ranks) {
      const Scene share = load_scene_from_string(text, "s.json", "", kMaxTriangles, scene_share_for(ranks));
      EXPECT_EQ(share.total_triangles(), whole.triangles.size());
      EXPECT_EQ(share.num_objects, whole.num_objects);
      ASSERT_EQ(share.prototypes.size(), 1u);
      EXPECT_EQ(share.prototypes[0].triangles.size(), whole.prototypes[0].triangles.size());
      ASSERT_EQ(share.instances.size(), whole.instances.size());
      for (std::size_t k = 0; k < share.instances.size(); ++k)
        EXPECT_EQ(share.instances[k].to_world, whole.instances[k].to_world);
      Vec3 l, h;
      share.bounds(l, h);
      EXPECT_EQ(l, lo);
      EXPECT_EQ(h, hi);
    });
  }
}

}  // namespace
}  // namespace opsila
