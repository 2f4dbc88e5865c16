// Renders where the nearest hit is decided by the hit order's ids
// (kernels/hit_order.h): non-planar fans and coincident facets of two
// objects give the same bytes, image and item buffer, whatever the PE
// count, balance, bank capacity and routing (each changes which bank holds
// a facet and the order in which a ray meets them). The MPI ranks' share of
// this is in tests/app/mpi_render_test.cpp (HitOrderAcrossRanks).
#include <gtest/gtest.h>

#include <cstring>
#include <string>

#include "formats/json/scene_file.h"
#include "prepare/prepare_banks.h"
#include "frame/renderer.h"
#include "reference/reference.h"
#include "test_device.h"
#include "test_scenes.h"
#include "test_util.h"

namespace opsila {
namespace {

RenderResult render_tie_scene(const Scene& s, int pes, Balance balance = Balance::facets,
                              const RaySample* sample = nullptr, int capacity = 0) {
  RenderSettings rs;
  rs.num_pes = pes;
  rs.balance = balance;
  rs.ray_sample = sample;
  rs.bank_capacity = capacity;
  return render(s, rs, test::shared_runtime());
}

void expect_same_bytes(const RenderResult& want, const RenderResult& got, const std::string& what) {
  ASSERT_EQ(want.rgb.size(), got.rgb.size()) << what;
  std::size_t pixels = 0;
  for (std::size_t i = 0; i < got.rgb.size(); i += 3)
    pixels += std::memcmp(&want.rgb[i], &got.rgb[i], 3 * sizeof(float)) != 0;
  EXPECT_EQ(pixels, 0u) << what << ": pixels that differ";
  EXPECT_EQ(want.item_buffer, got.item_buffer) << what;
  EXPECT_EQ(got.stats.descriptors_spawned, got.stats.descriptors_finished) << what << ": a descriptor was lost";
}

TEST(HitOrderRender, NonPlanarAndCoincidentFacetsAreTheSameBytesOnAnyPeCount) {
  const Scene s = test::tie_scene(160, 24);
  const RenderResult one = render_tie_scene(s, 1);
  for (int pes : {3, 16, 64, 256}) expect_same_bytes(one, render_tie_scene(s, pes), std::to_string(pes) + " PEs");
  // Banks of a few descriptors: many more rounds, visits in another order.
  expect_same_bytes(one, render_tie_scene(s, 16, Balance::facets, nullptr, 7), "16 PEs, banks of 7");
}

TEST(HitOrderRender, EveryBalanceGivesTheSameBytes) {
  const Scene s = test::tie_scene(128, 40);  // finer quads: more creases per pixel
  const RenderResult one = render_tie_scene(s, 1);
  const RaySample sample = ReferenceTracer(s).sample_rays(3000);
  for (int pes : {3, 64}) {
    const std::string at = std::to_string(pes) + " PEs";
    expect_same_bytes(one, render_tie_scene(s, pes, Balance::work, &sample), at + ", balance work");
    expect_same_bytes(one, render_tie_scene(s, pes, Balance::measured), at + ", balance measured");
  }
}

// A grazing view: distances along the crease differ by less than a grid
// cell over many pixels, and the item buffer still does not move.
TEST(HitOrderRender, AGrazingViewIsTheSameBytesOnAnyPeCount) {
  Scene s = test::tie_scene(160, 60);
  s.camera.eye = {0.0f, 0.9f, 7.5f};
  s.camera.look_at = {0.0f, 0.2f, -4.0f};
  const RenderResult one = render_tie_scene(s, 1);
  for (int pes : {3, 64, 256}) expect_same_bytes(one, render_tie_scene(s, pes), std::to_string(pes) + " PEs");
}

// Far from the origin a hit point is rounded by some 0.06 (at 1e6), far
// more than the cluster spheres were padded (1e-5 of the scene's size):
// --routing spheres skipped PEs that held the winner, and mirrors showed
// other pixels at 3, 16 and 64 PEs. The spheres are padded by the
// coordinates' magnitude now, as the routing boxes are.
TEST(HitOrderRender, AFarSceneIsTheSameBytesWithEitherRoutingOnAnyPeCount) {
  // A mirror box holding a red sphere, about (1e6, -2e6, 5e5).
  test::TempDir dir;
  const std::string far = dir.write("far.json", R"({"depth": 8, "image": {"width": 64, "height": 48},
    "camera": {"eye": [1000000, -1999999, 500000], "look_at": [1000001, -1999998.95, 500000.08]},
    "materials": {"mirror": {"Kd": 0.05, "kr": 0.9, "Ns": 50}, "red": {"Kd": [0.9, 0.1, 0.1]}},
    "lights": [{"position": [1000000, -1999998.2, 500000.5]}],
    "objects": [{"type": "box", "min": [999998, -2000000, 499997], "max": [1000002, -1999998, 500003],
                 "material": "mirror"},
                {"type": "sphere", "center": [1000000.5, -1999999.5, 500001], "radius": 0.4, "material": "red"}]})");
  const Scene s = load_scene(far);
  const RenderResult boxes = render_tie_scene(s, 16);
  for (int pes : {1, 3, 16, 64}) {
    RenderSettings rs;
    rs.num_pes = pes;
    rs.routing = OPSILA_ROUTING_SPHERES;
    expect_same_bytes(boxes, render(s, rs, test::shared_runtime()), std::to_string(pes) + " PEs, spheres");
  }
}

// Coincident facets show the lower object's: never the upper copy of a quad
// made of the same triangles, and mostly the lower of a square cut along
// the other diagonal (where rounding can put the two in different cells).
TEST(HitOrderRender, CoincidentFacetsShowTheLowerObject) {
  const Scene s = test::tie_scene(160, 8);
  const RenderResult r = render_tie_scene(s, 16);
  // tie_scene's objects: the grid, three hexagons, then the two pairs.
  const int same_lower = 4, same_upper = 5, cut_lower = 6, cut_upper = 7;
  std::size_t counts[8] = {};
  for (std::size_t i = 0; i < r.item_buffer.size(); i += 2)
    if (r.item_buffer[i] >= 0 && r.item_buffer[i] < 8) ++counts[r.item_buffer[i]];
  EXPECT_GT(counts[same_lower], 200u);
  EXPECT_EQ(counts[same_upper], 0u);
  EXPECT_GT(counts[cut_lower], 200u);
  EXPECT_LT(counts[cut_upper] * 20, counts[cut_lower]);
}

}  // namespace
}  // namespace opsila
