// Samples per pixel (CONTRACT "Camera"): the k x k grid, the mean, the centre
// ray's item buffer; in the reference, the replicated megakernel and the
// OPSILA renderer. Also the --spp / "spp" checks and the progress line.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>

#include "prepare/prepare_banks.h"
#include "bench/bench.h"
#include "core/progress.h"
#include "scene/work_bound.h"
#include "formats/json/scene_file.h"
#include "frame/renderer.h"
#include "reference/reference.h"
#include "test_device.h"
#include "test_scenes.h"
#include "test_util.h"

namespace opsila {
namespace {

using test::RunResult;
using test::run_opsila;

// One colour everywhere: a quad filling the view, ambient only, no lights.
// Every sample of every pixel has the same value.
Scene flat_scene(int width, int height) {
  Scene s;
  const int m = test::add_material(s, {0.3f, 0.55f, 0.7f}, {0, 0, 0}, {0, 0, 0}, 1, {0, 0, 0}, 1, 2);
  test::add_quad(s, {-50, -50, 0}, {50, -50, 0}, {50, 50, 0}, {-50, 50, 0}, 0, m);
  s.num_objects = 1;
  s.camera.eye = {0, 0, 5};
  s.camera.look_at = {0, 0, 0};
  s.width = width;
  s.height = height;
  s.ambient = {0.9f, 0.8f, 0.7f};
  s.has_camera = s.has_lights = true;
  return s;
}

Scene with_spp(Scene s, int spp) {
  s.spp = spp;
  return s;
}

// Box filter of a (k*W) x (k*H) image down to W x H.
std::vector<double> box_down(const std::vector<float>& rgb, int W, int H, int k) {
  std::vector<double> out(std::size_t(W) * H * 3, 0.0);
  for (int y = 0; y < H * k; ++y)
    for (int x = 0; x < W * k; ++x)
      for (int c = 0; c < 3; ++c)
        out[(std::size_t(y / k) * W + x / k) * 3 + c] += rgb[(std::size_t(y) * W * k + x) * 3 + c] / double(k * k);
  return out;
}

ClRuntime& runtime() { return test::shared_runtime(); }

// ------------------------------------------------------------- reference

TEST(SppReference, FlatSceneEqualsOneSample) {
  const Scene s = flat_scene(24, 18);
  const ImageResult one = render_reference(s);
  for (int spp : {4, 9, 16}) {
    const ImageResult many = render_reference(with_spp(s, spp));
    EXPECT_EQ(many.rgb, one.rgb) << spp;
    EXPECT_EQ(many.rays.primary, one.rays.primary * spp);
  }
}

// Sample (i, j) of pixel (x, y) at x + (i+0.5)/k is the centre of pixel
// (k x + i) of a k-times larger image: spp k^2 is the box-filtered larger
// image, up to float rounding of the ray directions.
TEST(SppReference, SamplesAreTheCellCentresOfAKByKGrid) {
  const Scene s = test::mirror_glass_scene(40);
  for (int k : {2, 3}) {
    Scene big = s;
    big.width *= k;
    big.height *= k;
    const std::vector<double> expect = box_down(render_reference(big).rgb, s.width, s.height, k);
    const ImageResult img = render_reference(with_spp(s, k * k));
    std::size_t off = 0;
    for (std::size_t i = 0; i < expect.size(); ++i) off += std::fabs(img.rgb[i] - expect[i]) > 1e-3;
    // A handful of samples may flip across an edge through rounding.
    EXPECT_LE(double(off) / expect.size(), 0.002) << "k = " << k;
  }
}

TEST(SppReference, ItemBufferIsTheCentreRaysWhateverTheSamples) {
  const Scene s = test::mirror_glass_scene(48);
  const ImageResult one = render_reference(s);
  for (int spp : {4, 9, 16}) EXPECT_EQ(render_reference(with_spp(s, spp)).item_buffer, one.item_buffer) << spp;
}

// ------------------------------------------------------------ megakernel

TEST(SppMegakernel, MatchesTheReferenceAndKeepsTheCentreItems) {
  const Scene s = with_spp(test::mirror_glass_scene(64), 4);
  const BaselineImage mega = render_megakernel(s, runtime());
  const ImageResult ref = render_reference(s);
  EXPECT_GE(test::clamped_psnr(mega.rgb, ref.rgb), 40.0);
  EXPECT_LE(test::fraction_off(mega.rgb, ref.rgb, 2), 0.005);
  EXPECT_EQ(mega.rays.primary, ref.rays.primary);
  const BaselineImage one = render_megakernel(with_spp(s, 1), runtime());
  EXPECT_EQ(mega.item_buffer, one.item_buffer);
  const Scene flat = flat_scene(16, 12);
  EXPECT_EQ(render_megakernel(with_spp(flat, 4), runtime()).rgb, render_megakernel(flat, runtime()).rgb);
}

TEST(SppEmbree, MatchesTheReferenceAndKeepsTheCentreItems) {
  if (!embree_available()) GTEST_SKIP() << "built without Embree";
  const Scene s = with_spp(test::mirror_glass_scene(48), 4);
  const ImageResult ref = render_reference(s);
  const BaselineImage e = render_embree(s, 2);
  EXPECT_GE(test::clamped_psnr(e.rgb, ref.rgb), 40.0);
  EXPECT_TRUE(e.rays.same_rays(ref.rays));
  EXPECT_EQ(e.item_buffer, ref.item_buffer);
}

// ------------------------------------------------------------ flag, key

struct SppInput : ::testing::Test {
  test::TempDir dir;
  std::string obj;
  void SetUp() override { obj = dir.write("q.obj", "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nf 1 2 3\n"); }
  void expect_rejected(const std::vector<std::string>& args, const std::string& named) {
    const RunResult r = run_opsila(args);
    SCOPED_TRACE("stderr: " + r.err);
    EXPECT_EQ(r.exit_code, 2);
    const std::vector<std::string> errors = r.error_lines();
    ASSERT_EQ(errors.size(), 1u);
    EXPECT_NE(errors[0].find(named), std::string::npos);
    EXPECT_FALSE(test::file_exists(dir.file("x.png")));
  }
};

TEST_F(SppInput, BadFlagValuesAreRejected) {
  for (const char* v : {"0", "-4", "2", "3", "8", "1025", "4096", "99999999999", "4.0", "x", ""})
    expect_rejected({"render", obj, "-o", dir.file("x.png"), "--reference", "--spp", v}, "--spp");
}

TEST_F(SppInput, BadSceneValuesAreRejected) {
  for (const char* v : {"0", "-1", "2", "12", "2000", "4.5", "\"4\"", "true"}) {
    const std::string scene = dir.write("s.json", std::string("{\"spp\": ") + v +
                                                      ", \"objects\": [{\"type\": \"obj\", \"file\": \"q.obj\"}]}");
    expect_rejected({"render", scene, "-o", dir.file("x.png"), "--reference"}, "s.json:1: spp");
  }
}

TEST_F(SppInput, SceneKeyIsReadAndTheFlagWins) {
  const std::string scene =
      dir.write("s.json", "{\"spp\": 9, \"objects\": [{\"type\": \"obj\", \"file\": \"q.obj\"}]}");
  RunResult r = run_opsila({"render", scene, "-o", dir.file("a.pfm"), "--reference", "--size", "8x6",
                            "--stats", dir.file("a.json")});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(test::read_file(dir.file("a.json")).find("\"primary\": 432"), std::string::npos);  // 48 x 9
  r = run_opsila({"render", scene, "-o", dir.file("b.pfm"), "--reference", "--size", "8x6", "--spp", "4",
                  "--stats", dir.file("b.json")});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(test::read_file(dir.file("b.json")).find("\"primary\": 192"), std::string::npos);  // 48 x 4
}

// -------------------------------------------------------------- progress

// OPSILA_PROGRESS_AFTER=0 (documented in README) lets a small render show
// what a long one shows after two seconds.
struct ProgressEnv : SppInput {
  void SetUp() override {
    SppInput::SetUp();
    ::setenv("OPSILA_PROGRESS_AFTER", "0", 1);
  }
  void TearDown() override { ::unsetenv("OPSILA_PROGRESS_AFTER"); }
};

TEST_F(ProgressEnv, ReferenceRenderShowsProgressUnlessQuiet) {
  RunResult r = run_opsila({"render", obj, "-o", dir.file("a.png"), "--reference", "--size", "64x48"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("opsila: render: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("% done, "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(" rays/s, "), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find('\r'), std::string::npos) << "stderr is not a terminal: plain lines only";
  r = run_opsila({"render", obj, "-o", dir.file("b.png"), "--reference", "--size", "64x48", "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");
}

TEST_F(SppInput, ShortRenderShowsNoProgress) {
  const RunResult r = run_opsila({"render", obj, "-o", dir.file("a.png"), "--reference", "--size", "16x12"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("% done"), std::string::npos) << r.err;
}

TEST_F(SppInput, LargeRayTreeIsAnnouncedUpFront) {
  // The glass box sits behind the camera: the bound counts it, the render is quick.
  const std::string scene = dir.write(
      "glass.json",
      "{\"depth\": 31, \"camera\": {\"eye\": [0, 0, 5], \"look_at\": [0, 0, 0]},"
      " \"materials\": {\"g\": {\"kr\": 0.5, \"kt\": 0.5, \"Ni\": 1.5}, \"p\": {\"Kd\": 0.5}},"
      " \"objects\": [{\"type\": \"box\", \"center\": [0, 0, 0], \"size\": 1, \"material\": \"p\"},"
      " {\"type\": \"box\", \"center\": [0, 0, 50], \"size\": 1, \"material\": \"g\"}]}");
  RunResult r = run_opsila({"render", scene, "-o", dir.file("a.png"), "--reference", "--size", "4x3"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("opsila: note: expected work: up to "), std::string::npos) << r.err;
  r = run_opsila({"render", scene, "-o", dir.file("b.png"), "--reference", "--size", "4x3", "-q"});
  EXPECT_EQ(r.err, "");
  r = run_opsila({"render", scene, "-o", dir.file("c.png"), "--reference", "--size", "4x3", "--depth", "3"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("expected work"), std::string::npos) << r.err;
  // Depth 31 with two branches and two lights: (2^31 - 1) x 3 rays per sample at most.
  Scene big = test::mirror_glass_scene(4);
  big.max_depth = 31;
  const WorkBound b = work_bound(big);
  EXPECT_EQ(b.branches, 2);
  EXPECT_DOUBLE_EQ(b.rays_per_sample, (std::ldexp(1.0, 31) - 1) * 3);
  EXPECT_DOUBLE_EQ(b.rays, b.rays_per_sample * 4 * 3);
}


// --------------------------------------------------------------- OPSILA

RenderResult render_opsila(const Scene& s, int pes) {
  RenderSettings rs;
  rs.num_pes = pes;
  return render(s, rs, runtime());
}

TEST(SppRenderer, FlatSceneEqualsOneSampleExactly) {
  const Scene s = flat_scene(24, 18);
  const RenderResult one = render_opsila(s, 4);
  for (int spp : {4, 9}) {
    const RenderResult many = render_opsila(with_spp(s, spp), 4);
    EXPECT_EQ(many.rgb, one.rgb) << spp;  // N equal fixed-point samples decode to the one sample
    EXPECT_EQ(many.rays.primary, one.rays.primary * spp);
  }
}

TEST(SppRenderer, MatchesTheReferenceOn1_16_64Pes) {
  for (int spp : {4, 16}) {
    const Scene s = with_spp(test::mirror_glass_scene(48), spp);
    const ImageResult ref = render_reference(s);
    for (int pes : {1, 16, 64}) {
      SCOPED_TRACE("spp " + std::to_string(spp) + ", " + std::to_string(pes) + " PEs");
      const RenderResult r = render_opsila(s, pes);
      EXPECT_GE(test::clamped_psnr(r.rgb, ref.rgb), 40.0);
      EXPECT_LE(test::fraction_off(r.rgb, ref.rgb, 2), 0.005);
      EXPECT_EQ(r.item_buffer, ref.item_buffer);
      EXPECT_EQ(r.rays.primary, ref.rays.primary);
      EXPECT_EQ(r.rays.primary_hits, ref.rays.primary_hits);
      EXPECT_EQ(r.stats.descriptors_spawned, r.stats.descriptors_finished) << "a descriptor was lost";
    }
  }
}

TEST(SppRenderer, ItemBufferIsTheCentreRaysAndRerunsAreBitIdentical) {
  const Scene s = test::mirror_glass_scene(40);
  const RenderResult one = render_opsila(s, 16);
  for (int spp : {4, 9}) {
    const RenderResult a = render_opsila(with_spp(s, spp), 16);
    EXPECT_EQ(a.item_buffer, one.item_buffer) << spp;
    const RenderResult b = render_opsila(with_spp(s, spp), 16);
    EXPECT_EQ(a.rgb, b.rgb) << spp;
  }
}

// The gallery's smooth-shading scene (vertex normals from OBJ, "smooth":
// true, "spp": 16) at a small size and 4 samples: OPSILA against the reference.
TEST(SppRenderer, SmoothGallerySceneMatchesTheReference) {
  Scene s = load_scene(std::string(OPSILA_SOURCE_DIR) + "/scenes/smooth.json");
  ASSERT_EQ(s.spp, 16);
  s.width = 64;
  s.height = 48;
  s.spp = 4;
  const ImageResult ref = render_reference(s);
  const RenderResult r = render_opsila(s, 16);
  EXPECT_GE(test::clamped_psnr(r.rgb, ref.rgb), 40.0);
  EXPECT_LE(test::fraction_off(r.rgb, ref.rgb, 2), 0.01);
  EXPECT_EQ(r.item_buffer, ref.item_buffer);
}

// Many sample passes through tiny banks: the passes wait for the injection,
// so nothing is lost and the image is the one with roomy banks.
TEST(SppRenderer, SamplePassesWithTinyBanks) {
  const Scene s = with_spp(test::mirror_glass_scene(24), 9);
  const RenderResult roomy = render_opsila(s, 4);
  RenderSettings rs;
  rs.num_pes = 4;
  rs.bank_capacity = 3;
  const RenderResult tiny = render(s, rs, runtime());
  EXPECT_EQ(tiny.rgb, roomy.rgb);
  EXPECT_EQ(tiny.stats.descriptors_spawned, tiny.stats.descriptors_finished);
}

TEST_F(ProgressEnv, OpenClRenderShowsProgressUnlessQuiet) {
  RunResult r = run_opsila({"render", obj, "-o", dir.file("a.png"), "--size", "32x24", "--spp", "4"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("opsila: render: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("% done, "), std::string::npos) << r.err;
  r = run_opsila({"render", obj, "-o", dir.file("b.png"), "--size", "32x24", "--spp", "4", "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");
}

}  // namespace
}  // namespace opsila
