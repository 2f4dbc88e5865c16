// Texture maps and smooth shading on the OpenCL renderer and the replicated
// megakernel, against the sequential reference (SPEC in plain C++), on 1, 16
// and 64 PEs.
#include <gtest/gtest.h>

#include <filesystem>

#include "bench/bench.h"
#include "input/scene_file.h"
#include "machine/renderer.h"
#include "reference/reference.h"
#include "test_device.h"
#include "test_scenes.h"
#include "test_util.h"

namespace opsila {
namespace {

RenderResult render_with(const Scene& s, int pes) {
  RenderSettings rs;
  rs.num_pes = pes;
  return render(s, rs, test::shared_runtime());
}

double item_agreement(const std::vector<std::int32_t>& a, const std::vector<std::int32_t>& b) {
  std::size_t same = 0;
  for (std::size_t i = 0; i + 1 < a.size(); i += 2) same += (a[i] == b[i] && a[i + 1] == b[i + 1]);
  return double(same) / double(a.size() / 2);
}

class SurfaceRender : public ::testing::TestWithParam<bool> {};

TEST_P(SurfaceRender, MatchesReferenceOnOneSixteenAndSixtyFourPes) {
  const bool smooth = GetParam();
  const Scene s = test::textured_smooth_scene(128, smooth);
  const ImageResult ref = render_reference(s);
  for (int pes : {1, 16, 64}) {
    SCOPED_TRACE(std::to_string(pes) + " PEs");
    const RenderResult r = render_with(s, pes);
    EXPECT_GE(test::clamped_psnr(r.rgb, ref.rgb), 40.0);
    EXPECT_LE(test::fraction_off(r.rgb, ref.rgb, 2), 0.005);
    EXPECT_GE(item_agreement(r.item_buffer, ref.item_buffer), 0.999);
    EXPECT_EQ(r.stats.descriptors_spawned, r.stats.descriptors_finished);
  }
  const BaselineImage mega = render_megakernel(s, test::shared_runtime());
  EXPECT_GE(test::clamped_psnr(mega.rgb, ref.rgb), 40.0);
  EXPECT_LE(test::fraction_off(mega.rgb, ref.rgb, 2), 0.005);
}

INSTANTIATE_TEST_SUITE_P(FlatAndSmooth, SurfaceRender, ::testing::Values(false, true),
                         [](const ::testing::TestParamInfo<bool>& p) { return p.param ? "Smooth" : "Flat"; });

// The maps and the normals do change the image (so the comparisons above
// could fail), and only where SPEC says.
TEST(SurfaceRenderEffect, TexturesAndSmoothNormalsChangeTheImage) {
  const Scene smooth = test::textured_smooth_scene(96, true);
  const Scene flat = test::textured_smooth_scene(96, false);
  Scene plain = flat;
  for (MaterialDesc& m : plain.materials) m.map_kd = m.map_ka = -1;
  const RenderResult rs = render_with(smooth, 16), rf = render_with(flat, 16), rp = render_with(plain, 16);
  EXPECT_LT(test::clamped_psnr(rs.rgb, rf.rgb), 40.0);
  EXPECT_LT(test::clamped_psnr(rf.rgb, rp.rgb), 30.0);
  EXPECT_EQ(rf.item_buffer, rp.item_buffer);  // shading only: the same facets are seen
  EXPECT_EQ(rs.item_buffer, rf.item_buffer);
  // A scene with no maps and no smooth shading stores no attributes at all.
  EXPECT_EQ(rp.stats.texture_replicated_bytes, 0u);
  EXPECT_GT(rf.stats.texture_replicated_bytes, 0u);
}

// A real textured, smooth model read by the importer (COLLADA duck with a
// TGA map), framed and lit as a bare model is.
TEST(SurfaceRenderModels, ImportedTexturedModelMatchesReference) {
  const std::string duck = "/usr/share/assimp/models/Collada/duck.dae";
  if (!std::filesystem::exists(duck)) GTEST_SKIP() << "Debian package assimp-testmodels is not installed";
  Scene s = load_scene(duck);
  s.width = 64;
  s.height = 48;
  Vec3 lo, hi;
  s.bounds(lo, hi);
  s.camera = frame_bounds(lo, hi, 45.0f, 64.0f / 48.0f);
  s.lights.push_back({s.camera.eye, {1, 1, 1}});
  s.smooth = true;
  const ImageResult ref = render_reference(s);
  for (int pes : {1, 16, 64}) {
    SCOPED_TRACE(std::to_string(pes) + " PEs");
    const RenderResult r = render_with(s, pes);
    EXPECT_GE(test::clamped_psnr(r.rgb, ref.rgb), 40.0);
    EXPECT_LE(test::fraction_off(r.rgb, ref.rgb, 2), 0.01);
    EXPECT_GE(item_agreement(r.item_buffer, ref.item_buffer), 0.995);
  }
}

}  // namespace
}  // namespace opsila
