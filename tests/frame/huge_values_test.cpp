// Accepted values never give wrong pixels: sums beyond what 64-bit fixed
// point holds saturate at kMaxPixelValue in every renderer (OpenCL, the
// megakernel and Embree baselines, the reference), never wrap; no pixel is
// negative, NaN or infinite.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "prepare/prepare_banks.h"
#include "bench/bench.h"
#include "core/fixed_point.h"
#include "formats/image/image_io.h"
#include "formats/json/scene_file.h"
#include "frame/renderer.h"
#include "reference/reference.h"
#include "test_device.h"
#include "test_util.h"

namespace opsila {
namespace {

ClRuntime& runtime() { return test::shared_runtime(); }

// Intensities and coefficients at the top of float: single terms overflow.
const char* kHotScene = R"({"image": {"size": [32, 24]}, "depth": 3,
  "camera": {"eye": [0, 0, 5], "look_at": [0, 0, 0]}, "ambient": 0,
  "lights": [{"position": [0, 0, 5], "intensity": 1e38}],
  "materials": {"hot": {"Kd": 3e38, "kr": [0.5, 0, 1]}},
  "objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "hot"},
              {"type": "box", "min": [-5, -5, -3], "max": [5, 5, -2], "material": "hot"}]})";

// Each term fits the fixed point, their sum does not: 64 lights of 2e10.
std::string many_lights_scene() {
  std::string lights;
  for (int i = 0; i < 64; ++i)
    lights += std::string(i ? "," : "") + "{\"position\": [" + std::to_string(i % 8 - 3.5) + ", " +
              std::to_string(i / 8 - 3.5) + ", 6], \"intensity\": 2e10}";
  return R"({"image": {"size": [32, 24]}, "depth": 1, "ambient": 0,
    "camera": {"eye": [0, 0, 5], "look_at": [0, 0, 0]}, "lights": [)" +
         lights + R"(], "objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1.5,
    "material": {"Kd": 1}}]})";
}

Scene scene_of(const std::string& text) { return load_scene_from_string(text, "s.json", ""); }

// Every value finite and >= 0; where the reference saturates, so does the
// other renderer, and elsewhere they agree closely. Returns the saturated
// channels (of the reference).
int expect_agrees_with_reference(const std::vector<float>& rgb, const std::vector<float>& ref,
                                 const char* who, float top = kMaxPixelValue) {
  EXPECT_EQ(rgb.size(), ref.size());
  int saturated = 0, mismatched = 0;
  for (std::size_t i = 0; i < rgb.size() && i < ref.size(); ++i) {
    EXPECT_TRUE(std::isfinite(rgb[i]) && rgb[i] >= 0) << who << " value " << rgb[i] << " at " << i;
    EXPECT_TRUE(std::isfinite(ref[i]) && ref[i] >= 0) << "reference value " << ref[i] << " at " << i;
    EXPECT_LE(rgb[i], top);
    saturated += ref[i] == top;
    // Sums within rounding of the limit may fall either way.
    const bool near_limit = ref[i] > 0.999f * top || rgb[i] > 0.999f * top;
    if (!near_limit && std::fabs(rgb[i] - ref[i]) > 1e-3f * std::max(1.0f, ref[i])) ++mismatched;
    if (ref[i] == top && rgb[i] != top) ++mismatched;
  }
  EXPECT_LE(mismatched, int(rgb.size() / 100)) << who;  // edge pixels may differ
  return saturated;
}

TEST(HugeValues, TermsBeyondFloatSaturateEverywhere) {
  const Scene s = scene_of(kHotScene);
  const ImageResult ref = render_reference(s);
  const RenderResult cl = render(s, RenderSettings{}, runtime());
  EXPECT_GT(expect_agrees_with_reference(cl.rgb, ref.rgb, "OpenCL"), 100);
  expect_agrees_with_reference(render_megakernel(s, runtime()).rgb, ref.rgb, "megakernel");
#ifdef OPSILA_HAVE_EMBREE
  expect_agrees_with_reference(render_embree(s, 2).rgb, ref.rgb, "Embree");
#endif
  // The green channel has kr = 0 where the others reflect: no 0 x inf NaN.
  EXPECT_NO_THROW(encode_pfm(cl.width, cl.height, cl.rgb));
}

// Colours are finite but unbounded: two mirrors of kr = 1e30 face each
// other, and after two bounces a weight is infinite; times a light's or the
// ambient's zero channel it is NaN, which adds nothing (to_fixed's 0, and
// OpenCL's), on every device: Rusticl's own conversion gave the largest sum.
TEST(HugeValues, InfiniteWeightsTimesZeroChannelsAddNothing) {
  const Scene s = scene_of(R"({"image": {"size": [32, 24]}, "depth": 6, "ambient": [0.1, 0, 0.1],
    "camera": {"eye": [0, 0, 0], "look_at": [0, 0, -1]},
    "lights": [{"position": [0, 0.5, 0], "intensity": [1, 0, 1]}],
    "materials": {"m": {"Kd": 0.5, "kr": 1e30}},
    "objects": [{"type": "box", "min": [-5, -5, -3], "max": [5, 5, -2], "material": "m"},
                {"type": "box", "min": [-5, -5, 2], "max": [5, 5, 3], "material": "m"}]})");
  const ImageResult ref = render_reference(s);
  const RenderResult cl = render(s, RenderSettings{}, runtime());
  EXPECT_GT(expect_agrees_with_reference(cl.rgb, ref.rgb, "OpenCL"), 100);
  expect_agrees_with_reference(render_megakernel(s, runtime()).rgb, ref.rgb, "megakernel");
  for (std::size_t i = 1; i < cl.rgb.size(); i += 3) ASSERT_EQ(cl.rgb[i], 0.0f) << "green of pixel " << i / 3;
}

TEST(HugeValues, SumsBeyondTheFixedPointSaturateNotWrap) {
  const Scene s = scene_of(many_lights_scene());
  const ImageResult ref = render_reference(s);
  for (int pes : {1, 7}) {
    RenderSettings settings;
    settings.num_pes = pes;
    const RenderResult cl = render(s, settings, runtime());
    EXPECT_GT(expect_agrees_with_reference(cl.rgb, ref.rgb, "OpenCL"), 30) << pes << " PEs";
  }
  expect_agrees_with_reference(render_megakernel(s, runtime()).rgb, ref.rgb, "megakernel");
#ifdef OPSILA_HAVE_EMBREE
  expect_agrees_with_reference(render_embree(s, 2).rgb, ref.rgb, "Embree");
#endif
  // With 4 samples a pixel, the sum of the samples saturates, then is divided.
  Scene four = s;
  four.spp = 4;
  const ImageResult ref4 = render_reference(four);
  EXPECT_GT(expect_agrees_with_reference(render(four, RenderSettings{}, runtime()).rgb, ref4.rgb, "spp 4",
                                         kMaxPixelValue / 4),
            30);
}

// Misses add the background without atomics (each pixel's own work-item):
// four samples of 3.3e11 each fit the fixed point, and their sum carries
// out of 64 bits; four of 2e11 reach 2^63; both saturate.
// Four of 1e11 fit, and their mean is the background. Without item buffer
// output no pixel is traced here (the sphere is behind the eye) and the
// read-back gives every pixel the background's sum (owned_sum): the same.
TEST(HugeValues, BackgroundSumsOfMissesSaturateNotWrap) {
  for (const char* bg : {"3.3e11", "2e11", "1e11"}) {
    Scene s = scene_of(std::string(R"({"image": {"size": [16, 8]}, "spp": 4, "background": )") + bg +
                       R"(, "camera": {"eye": [0, 0, 5], "look_at": [0, 0, 0]},
      "objects": [{"type": "sphere", "center": [0, 0, 9], "radius": 1, "material": {"Kd": 1}}]})");
    const float expect = std::string(bg) != "1e11" ? kMaxPixelValue / 4 : from_fixed(4 * to_fixed(1e11f), 4);
    for (int pes : {1, 4})
      for (bool items : {true, false}) {
        RenderSettings settings;
        settings.num_pes = pes;
        settings.item_buffer_output = items;
        const RenderResult cl = render(s, settings, runtime());
        ASSERT_EQ(cl.rgb.size(), std::size_t(16 * 8 * 3));
        for (float v : cl.rgb) ASSERT_EQ(v, expect) << bg << ", " << pes << " PEs, items " << items;
      }
  }
}

TEST(HugeValues, DecodeSaturatesAtTheLargestSum) {
  EXPECT_EQ(from_fixed(0), 0.0f);
  EXPECT_EQ(from_fixed(std::uint64_t(3) << OPSILA_FIXED_SHIFT), 3.0f);
  EXPECT_EQ(from_fixed(std::uint64_t(std::numeric_limits<std::int64_t>::max())), kMaxPixelValue);
  EXPECT_EQ(from_fixed(std::uint64_t(1) << 63 | 12345), kMaxPixelValue);  // the kernels' mark
  EXPECT_EQ(add_fixed_saturating(std::numeric_limits<std::int64_t>::max() - 1, 5),
            std::numeric_limits<std::int64_t>::max());
  EXPECT_EQ(from_fixed(std::uint64_t(1) << 63, 4), kMaxPixelValue / 4);  // the mean of 4 samples
  // What N adds of one value leave (kernels/lib/accum.cl, add_fixed_owned).
  EXPECT_EQ(owned_sum(7, 9), 63u);
  EXPECT_EQ(owned_sum(std::int64_t(1) << 62, 2), std::uint64_t(1) << 63);  // reaches 2^63: saturated
  EXPECT_EQ(owned_sum(std::numeric_limits<std::int64_t>::max(), 3) >> 63, 1u);  // carried out: marked
  EXPECT_EQ(from_fixed(owned_sum(std::numeric_limits<std::int64_t>::max(), 3), 3), kMaxPixelValue / 3);
  EXPECT_EQ(saturate_sum(std::numeric_limits<double>::infinity()), double(kMaxPixelValue));
  EXPECT_EQ(saturate_sum(std::nan("")), 0.0);
}

// The image's decode (MeanDecoder: a product by the exact reciprocal where
// N x 2^24 is a power of two) gives from_fixed's floats, bit for bit, on
// sums of every size, saturated ones, and the sums of N equal samples.
TEST(HugeValues, TheImageDecodeIsFromFixedBitForBit) {
  std::uint64_t state = 0x9e3779b97f4a7c15u;
  auto next = [&state] {
    state ^= state << 13, state ^= state >> 7, state ^= state << 17;  // xorshift64
    return state;
  };
  for (int samples : {1, 2, 3, 4, 9, 16, 25, 64, 256, 1024}) {
    const MeanDecoder mean(samples);
    std::vector<std::uint64_t> sums = {0, 1, std::uint64_t(1) << 63, ~std::uint64_t(0),
                                       std::uint64_t(std::numeric_limits<std::int64_t>::max())};
    for (int i = 0; i < 20000; ++i) sums.push_back(next() >> (next() % 64));  // every magnitude
    for (int i = 0; i < 200; ++i) sums.push_back(std::uint64_t(samples) * (next() >> 40));  // N equal samples
    for (std::uint64_t s : sums) {
      const float a = mean(s), b = from_fixed(s, samples);
      ASSERT_EQ(0, std::memcmp(&a, &b, sizeof(float))) << "sum " << s << ", " << samples << " samples";
      // Before the rounding to float too, where a product by an inexact
      // reciprocal would differ in the last bits.
      const double q = (saturated(s) ? double(kMaxPixelValue) * OPSILA_FIXED_SCALE : double(s)) /
                       (double(OPSILA_FIXED_SCALE) * samples);
      const double m = mean.mean(s);
      ASSERT_EQ(0, std::memcmp(&m, &q, sizeof(double))) << "sum " << s << ", " << samples << " samples";
    }
  }
}

TEST(HugeValues, NoPfmHoldsANonFiniteValue) {
  EXPECT_THROW(encode_pfm(1, 1, {0.0f, std::nanf(""), 0.0f}), std::logic_error);
  EXPECT_THROW(encode_pfm(1, 1, {std::numeric_limits<float>::infinity(), 0.0f, 0.0f}), std::logic_error);
  EXPECT_NO_THROW(encode_pfm(1, 1, {kMaxPixelValue, 0.0f, 1.0f}));
}

TEST(HugeValues, EndToEndThePfmIsFiniteAndSaturated) {
  test::TempDir dir;
  const std::string scene = dir.write("hot.json", kHotScene);
  const test::RunResult r = test::run_opsila({"render", scene, "-o", dir.file("hot.pfm"), "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const FloatImage image = read_pfm(dir.file("hot.pfm"));
  int saturated = 0;
  for (float v : image.rgb) {
    EXPECT_TRUE(std::isfinite(v) && v >= 0) << v;
    saturated += v == kMaxPixelValue;
  }
  EXPECT_GT(saturated, 100);
}

}  // namespace
}  // namespace opsila
