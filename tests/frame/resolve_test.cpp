// The image resolved on the device (kernels/resolve.cl; a GPU's way, forced
// here by OPSILA_DEVICE_RESOLVE=1) is the host's decode (MeanDecoder), bit
// for bit: on sums of every size, saturated ones, pixels outside the traced
// rectangle, and whole frames at any PE count and sample count.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "core/errors.h"
#include "core/fixed_point.h"
#include "device/device_buffers.h"
#include "formats/json/scene_file.h"
#include "frame/frame_kernels.h"
#include "prepare/prepare_banks.h"
#include "test_device.h"
#include "test_scenes.h"

namespace opsila {
namespace {

struct DeviceResolveHook {  // OPSILA_DEVICE_RESOLVE while it lives
  explicit DeviceResolveHook(const char* v) { ::setenv("OPSILA_DEVICE_RESOLVE", v, 1); }
  ~DeviceResolveHook() { ::unsetenv("OPSILA_DEVICE_RESOLVE"); }
};

std::string no_doubles(ClRuntime& rt) {
  return rt.device().device_name + " has no doubles (cl_khr_fp64): its images are decoded on the host";
}

// Sums of every magnitude and the edge cases, three a pixel.
std::vector<std::uint64_t> sums_to_resolve(std::size_t pixels, int samples) {
  std::mt19937_64 rng(1987 + samples);
  std::vector<std::uint64_t> sums = {0, 1, std::uint64_t(1) << 53, (std::uint64_t(1) << 53) + 1,
                                     (std::uint64_t(1) << 53) + 3, std::uint64_t(1) << 63, ~std::uint64_t(0),
                                     std::uint64_t(std::numeric_limits<std::int64_t>::max()),
                                     std::uint64_t(std::numeric_limits<std::int64_t>::max()) - 1};
  while (sums.size() < 3 * pixels) {
    const std::uint64_t r = rng();
    sums.push_back(sums.size() % 7 == 0 ? std::uint64_t(samples) * (r >> 40) : r >> (rng() % 64));
  }
  return sums;
}

TEST(DeviceResolve, IsTheHostsDecodeBitForBit) {
  ClRuntime& rt = test::shared_runtime();
  if (!rt.doubles()) GTEST_SKIP() << no_doubles(rt);
  frame_kernels::ResolveKernel resolve(rt, "resolve_image");
  const int width = 64, height = 96;
  const std::size_t npix = std::size_t(width) * height;
  for (int samples : {1, 3, 4, 9, 16, 25, 1024}) {
    SCOPED_TRACE(std::to_string(samples) + " samples");
    const std::vector<std::uint64_t> sums = sums_to_resolve(npix, samples);
    std::vector<cl_uint> words(2 * sums.size());
    for (std::size_t i = 0; i < sums.size(); ++i) words[2 * i] = cl_uint(sums[i]), words[2 * i + 1] = cl_uint(sums[i] >> 32);
    frame_kernels::ResolveArgs a;
    a.accum = PixelSums(upload(rt, words, "pixel sums"));
    a.npix = int(npix);
    a.width = width;
    a.traced = {{3, 1, width - 9, height - 2}};  // the pixels around it get the background's sums
    a.background = {{sums[5], sums[6], std::uint64_t(samples) * 12345, 0}};
    MeanDecoder(samples).kernel_constants(a.divisor, a.inverse, a.exact);
    a.rgb = ResolvedImage(upload(rt, std::vector<cl_float>(3 * npix, -1.0f), "image"));
    cl_check(rt.queue().enqueueNDRangeKernel(resolve.bind(a), cl::NullRange, cl::NDRange(npix), cl::NullRange),
             "clEnqueueNDRangeKernel(resolve_image)");
    const std::vector<cl_float> got = test::from_device<cl_float>(rt, a.rgb, 3 * npix);
    const MeanDecoder mean(samples);
    for (std::size_t p = 0; p < npix; ++p) {
      const int x = int(p % width), y = int(p / width);
      const bool traced = x >= 3 && x <= width - 9 && y >= 1 && y <= height - 2;
      for (int c = 0; c < 3; ++c) {
        const float want = mean(traced ? sums[3 * p + c] : a.background.s[c]);
        ASSERT_EQ(0, std::memcmp(&want, &got[3 * p + c], sizeof(float)))
            << "pixel " << p << " channel " << c << ": sum " << (traced ? sums[3 * p + c] : a.background.s[c])
            << " gives " << got[3 * p + c] << ", the host " << want;
      }
    }
  }
}

// Whole frames, with and without the device's resolve: the same bytes, and
// the resolve launched only when asked.
RenderResult render_resolved(const Scene& s, const RenderSettings& rs, const char* hook) {
  DeviceResolveHook on(hook);
  return render(s, rs, test::shared_runtime());
}

bool launched(const RenderResult& r, const char* name) {
  for (const LaunchRecord& l : r.stats.launches)
    if (l.name == name) return true;
  return false;
}

void expect_same_frame(const Scene& s, const RenderSettings& rs, const std::string& what) {
  const RenderResult host = render_resolved(s, rs, "0"), device = render_resolved(s, rs, "1");
  ASSERT_EQ(host.rgb.size(), device.rgb.size()) << what;
  EXPECT_EQ(0, std::memcmp(host.rgb.data(), device.rgb.data(), host.rgb.size() * sizeof(float))) << what;
  EXPECT_EQ(host.item_buffer, device.item_buffer) << what;
  EXPECT_FALSE(launched(host, "resolve_image")) << what;
  EXPECT_TRUE(launched(device, "resolve_image")) << what;
}

TEST(DeviceResolve, GivesTheHostsImage) {
  ClRuntime& rt = test::shared_runtime();
  if (!rt.doubles()) GTEST_SKIP() << no_doubles(rt);
  for (int spp : {1, 4, 9})
    for (int pes : {1, 16, 64}) {
      Scene s = test::mirror_glass_scene(48, 3);
      s.spp = spp;
      RenderSettings rs;
      rs.num_pes = pes;
      expect_same_frame(s, rs, "spp " + std::to_string(spp) + ", " + std::to_string(pes) + " PEs");
    }
  // Only the background, saturated: no pixel traced (the sphere is behind
  // the eye), every sum the background's, four samples past 2^63.
  const Scene misses = load_scene_from_string(R"({"image": {"size": [16, 8]}, "spp": 4, "background": 3.3e11,
    "camera": {"eye": [0, 0, 5], "look_at": [0, 0, 0]},
    "objects": [{"type": "sphere", "center": [0, 0, 9], "radius": 1, "material": {"Kd": 1}}]})",
                                              "misses.json", "");
  for (bool items : {true, false}) {
    RenderSettings rs;
    rs.item_buffer_output = items;
    expect_same_frame(misses, rs, std::string("misses, item buffer ") + (items ? "on" : "off"));
    EXPECT_EQ(render_resolved(misses, rs, "1").rgb[0], kMaxPixelValue / 4);
  }
}

TEST(DeviceResolve, ABadSwitchIsAnInputError) {
  DeviceResolveHook bad("yes");
  try {
    render(test::mirror_glass_scene(16, 1), RenderSettings(), test::shared_runtime());
    FAIL() << "OPSILA_DEVICE_RESOLVE=yes was taken";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "OPSILA_DEVICE_RESOLVE=yes: expected 0 or 1");
  }
}

}  // namespace
}  // namespace opsila
