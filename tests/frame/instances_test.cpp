// Instances on the machine: the same image at any PE count, and the image
// of the scene with its instances written out, but for rounding.
#include <gtest/gtest.h>

#include "bench/bench.h"
#include "instance_scenes.h"
#include "test_render.h"

namespace opsila::test {
namespace {

TEST(Instances, SameImageAndItemsOnOneFourSixteenAndSixtyFourPes) {
  const Scene s = instanced_scene(96);
  const RenderResult one = render_on_pes(s, 1);
  for (int pes : {4, 16, 64}) {
    const RenderResult r = render_on_pes(s, pes);
    EXPECT_EQ(r.rgb, one.rgb) << pes << " PEs";
    EXPECT_EQ(r.item_buffer, one.item_buffer) << pes << " PEs";
  }
}

// Routing on spheres, banks of a few descriptors (rays wait and are sent
// again), the balance by sampled work, spp 4: the same bytes as the
// default machine.
TEST(Instances, SameImageWhateverTheRoutingBankSizeAndBalance) {
  Scene s = instanced_scene(64);
  s.spp = 4;
  RenderSettings base;
  base.num_pes = 16;
  const RenderResult want = render(s, base, shared_runtime());
  const RaySample sample = ReferenceTracer(s).sample_rays(2000);
  for (int k = 0; k < 3; ++k) {
    RenderSettings rs = base;
    if (k == 0) rs.routing = OPSILA_ROUTING_SPHERES;
    if (k == 1) rs.bank_capacity = 7;
    if (k == 2) rs.balance = Balance::work, rs.ray_sample = &sample;
    const RenderResult r = render(s, rs, shared_runtime());
    EXPECT_EQ(r.rgb, want.rgb) << "variant " << k;
    EXPECT_EQ(r.item_buffer, want.item_buffer) << "variant " << k;
  }
}

// The instances' hits are the written-out objects', but where rounding of
// the two transforms decides an edge.
TEST(Instances, MatchTheSceneWithTheInstancesWrittenOut) {
  const Scene s = instanced_scene(128);
  const RenderResult inst = render_on_pes(s, 16);
  const RenderResult flat = render_on_pes(flattened(s), 16);
  EXPECT_GE(clamped_psnr(inst.rgb, flat.rgb), 35.0);
  EXPECT_LE(fraction_off(inst.rgb, flat.rgb, 2), 0.02);
  EXPECT_GE(item_agreement(inst.item_buffer, as_instance_items(s, flat.item_buffer)), 0.97);
}

// The sequential reference, which meets instances in its own code, agrees
// (within what float rounding across implementations allows).
TEST(Instances, MatchTheReference) {
  const Scene s = instanced_scene(128);
  const RenderResult machine = render_on_pes(s, 16);
  const ImageResult ref = render_reference(s);
  expect_near_reference(machine, ref, 0.01, 0.99);
}

// The bench's replicated megakernel walks the instances too: the same
// items (one hit order) and the same image but for the order of sums.
TEST(Instances, TheMegakernelSeesThemAsTheMachineDoes) {
  const Scene s = instanced_scene(96);
  const RenderResult machine = render_on_pes(s, 16);
  const BaselineImage mega = render_megakernel(s, shared_runtime());
  EXPECT_EQ(mega.item_buffer, machine.item_buffer);
  EXPECT_GE(clamped_psnr(mega.rgb, machine.rgb), 60.0);
}

// The bench's Embree baseline instances one Embree scene per model.
TEST(Instances, EmbreeInstancesThemToo) {
  if (!embree_available()) GTEST_SKIP() << "built without Embree";
  const Scene s = instanced_scene(128);
  const ImageResult ref = render_reference(s);
  const BaselineImage embree = render_embree(s, 2);
  EXPECT_GE(clamped_psnr(embree.rgb, ref.rgb), 40.0);
  EXPECT_LE(fraction_off(embree.rgb, ref.rgb, 2), 0.01);
  EXPECT_GE(item_agreement(embree.item_buffer, ref.item_buffer), 0.99);
}

// Rays that are NaN (a camera whose float basis underflows; the command
// line refuses it, scene/camera.h) meet every box, empty slots too: the
// walks must still end (they never did: an empty slot taken as a node
// restarted the walk at node 0).
TEST(Instances, NanRaysEndTheirWalks) {
  Scene s = instanced_scene(16);
  s.camera.eye = {0, 0, 1e-25f};
  s.camera.look_at = {0, 0, 0};
  const RenderResult r = render_on_pes(s, 4);
  EXPECT_EQ(r.rgb.size(), std::size_t(16 * 12 * 3));
}

// Rays with a direction component of exactly zero (the camera's centre
// column, a shadow ray straight up to a light) meet an instance as they
// meet the facets written out. Its model-frame inverse direction is then
// infinite, which the walk once took for an overflowed ray: the column saw
// the floor through the instance, and its shadow had a lit stripe.
TEST(Instances, AxisAlignedRaysMeetThem) {
  Scene s;
  const int grey = add_material(s, {0.8f, 0.8f, 0.8f}, {0.8f, 0.8f, 0.8f}, {0, 0, 0}, 1, {0, 0, 0}, 1, 2);
  add_quad(s, {-2, 0, -3}, {-2, 0, 2}, {2, 0, 2}, {2, 0, -3}, 0, grey);
  s.num_objects = 1;
  const int tile = add_prototype(s, "tile", [&](Scene& m) {
    add_quad(m, {-0.5f, 0, -0.4f}, {-0.5f, 0, 0.4f}, {0.5f, 0, 0.4f}, {0.5f, 0, -0.4f}, 0, grey);
  });
  s.instances.push_back(make_instance(tile, placement({0, 2, -0.6f}, 0.0, 0.0, {1, 1, 1}), "test"));
  s.lights.push_back({{0, 4, 0}, {1, 1, 1}});
  s.camera.eye = {0, 5, 4};
  s.camera.look_at = {0, 0, -1};
  s.camera.fov_deg = 40;
  s.width = s.height = 21;
  s.has_camera = s.has_lights = true;
  const RenderResult inst = render_on_pes(s, 4);
  const RenderResult flat = render_on_pes(flattened(s), 4);
  const std::vector<std::int32_t> want = as_instance_items(s, flat.item_buffer);
  int column_hits = 0;
  for (int y = 0; y < s.height; ++y) {
    const std::size_t k = std::size_t(2 * (y * s.width + s.width / 2));
    EXPECT_EQ(inst.item_buffer[k], want[k]) << "row " << y;
    column_hits += want[k] == 1;
    for (std::size_t c = 0; c < 3; ++c)
      EXPECT_NEAR(int(to_srgb8(inst.rgb[3 * (k / 2) + c])), int(to_srgb8(flat.rgb[3 * (k / 2) + c])), 2)
          << "row " << y;
  }
  EXPECT_GT(column_hits, 0) << "the instance is in the centre column";
  EXPECT_LE(fraction_off(inst.rgb, flat.rgb, 2), 0.01);
}

// A scene of instances alone: every bank's own walk starts at an empty root.
TEST(Instances, AloneRenderTheSameOnOneAndSixteenPes) {
  Scene s = instanced_scene(64, 4, 3);
  s.triangles.clear();
  s.num_objects = 0;
  s.num_facets = 0;
  const RenderResult one = render_on_pes(s, 1);
  const RenderResult many = render_on_pes(s, 16);
  EXPECT_EQ(many.rgb, one.rgb);
  EXPECT_EQ(many.item_buffer, one.item_buffer);
  std::size_t hits = 0;
  for (std::size_t k = 0; k < one.item_buffer.size(); k += 2) hits += one.item_buffer[k] >= 0;
  EXPECT_GT(hits, one.item_buffer.size() / 100) << "the instances are in view";
}

}  // namespace
}  // namespace opsila::test
