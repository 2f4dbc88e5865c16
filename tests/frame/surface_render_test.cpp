// Texture maps and smooth shading on the OpenCL renderer and the replicated
// megakernel, against the sequential reference (CONTRACT in plain C++), on 1, 16
// and 64 PEs.
#include <gtest/gtest.h>

#include <filesystem>

#include "bench/bench.h"
#include "formats/json/scene_file.h"
#include "frame/renderer.h"
#include "reference/reference.h"
#include "test_device.h"
#include "test_scenes.h"
#include "test_render.h"
#include "test_util.h"

namespace opsila {
namespace {

using test::render_on_pes;

class SurfaceRender : public ::testing::TestWithParam<bool> {};

TEST_P(SurfaceRender, MatchesReferenceOnOneSixteenAndSixtyFourPes) {
  const bool smooth = GetParam();
  const Scene s = test::textured_smooth_scene(128, smooth);
  const ImageResult ref = render_reference(s);
  for (int pes : {1, 16, 64}) {
    SCOPED_TRACE(std::to_string(pes) + " PEs");
    const RenderResult r = render_on_pes(s, pes);
    test::expect_near_reference(r, ref, 0.005, 0.999);
    EXPECT_EQ(r.stats.descriptors_spawned, r.stats.descriptors_finished);
  }
  const BaselineImage mega = render_megakernel(s, test::shared_runtime());
  EXPECT_GE(test::clamped_psnr(mega.rgb, ref.rgb), 40.0);
  EXPECT_LE(test::fraction_off(mega.rgb, ref.rgb, 2), 0.005);
}

INSTANTIATE_TEST_SUITE_P(FlatAndSmooth, SurfaceRender, ::testing::Values(false, true),
                         [](const ::testing::TestParamInfo<bool>& p) { return p.param ? "Smooth" : "Flat"; });

// The maps and the normals do change the image (so the comparisons above
// could fail), and only where CONTRACT says.
TEST(SurfaceRenderEffect, TexturesAndSmoothNormalsChangeTheImage) {
  const Scene smooth = test::textured_smooth_scene(96, true);
  const Scene flat = test::textured_smooth_scene(96, false);
  Scene plain = flat;
  for (MaterialDesc& m : plain.materials) m.map_kd = m.map_ka = -1;
  const RenderResult rs = render_on_pes(smooth, 16), rf = render_on_pes(flat, 16), rp = render_on_pes(plain, 16);
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
  Scene s = test::framed_model(duck, 64, 48);
  s.smooth = true;
  const ImageResult ref = render_reference(s);
  for (int pes : {1, 16, 64}) {
    SCOPED_TRACE(std::to_string(pes) + " PEs");
    test::expect_near_reference(render_on_pes(s, pes), ref, 0.01, 0.995);
  }
}

}  // namespace
}  // namespace opsila
