// kernels/lib/shading.cl's specular power, x^Ns, both ways the host can
// build it (ClRuntimeOptions::specular_pow): in doubles, where it must be
// the correctly rounded power (held against the host's long double powl)
// but in rare near-halfway cases, and with the device's float pow, held to
// OpenCL's bound for pow (16 ulp). Both keep pow's special cases, and
// both render the same image but for the last bits of a few pixel sums.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "prepare/prepare_banks.h"
#include "batch.h"
#include "frame/renderer.h"

namespace opsila {
namespace {

using SpecularPow = ClRuntimeOptions::SpecularPow;

bool device_has_fp64() {
  const std::string ext = " " + query_capabilities(test::test_device().device).extensions + " ";
  return ext.find(" cl_khr_fp64 ") != std::string::npos;
}

ClRuntimeOptions batch_options(SpecularPow how) {
  ClRuntimeOptions o;
  o.kernel_source = test_kernel_source();
  o.kernel_source_origin = "test batch kernels";
  o.read_environment = false;
  o.specular_pow = how;
  return o;
}

std::vector<float> device_pow(ClRuntime& rt, const std::vector<float>& x, const std::vector<float>& y) {
  cl::Kernel k = rt.kernel("specular_pow_batch");
  cl::Buffer bx = test::to_device(rt, x), by = test::to_device(rt, y), out = test::to_device(rt, x);
  const int count = static_cast<int>(x.size());
  cl_check(k.setArg(0, bx), "setArg");
  cl_check(k.setArg(1, by), "setArg");
  cl_check(k.setArg(2, count), "setArg");
  cl_check(k.setArg(3, out), "setArg");
  cl_check(rt.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(x.size()), cl::NullRange),
           "specular_pow_batch");
  return test::from_device<float>(rt, out, x.size());
}

// Bases as light_term meets them, (0, 1] and a hair above 1 (a rounded dot
// product of unit vectors), and exponents from the scenes and real models.
void samples(std::vector<float>& x, std::vector<float>& y) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::vector<float> bases;
  for (int i = 0; i < 4000; ++i) bases.push_back(std::max(unit(rng), std::numeric_limits<float>::min()));
  for (int k = 0; k < 400; ++k) bases.push_back(1.0f - float(k) * 0x1p-24f);
  for (int k = 1; k < 8; ++k) bases.push_back(1.0f + float(k) * 0x1p-23f);
  for (float e : {0.0f, 0.5f, 1.0f, 2.0f, 7.0f, 30.0f, 96.078431f, 150.0f, 1000.0f})
    for (float b : bases) {
      x.push_back(b);
      y.push_back(e);
    }
}

// Distance in representable floats between two non-negative finite floats.
std::int64_t ulps(float a, float b) {
  std::int32_t ia, ib;
  std::memcpy(&ia, &a, 4);
  std::memcpy(&ib, &b, 4);
  return std::llabs(std::int64_t(ia) - std::int64_t(ib));
}

float correctly_rounded(float x, float y) { return static_cast<float>(std::pow((long double)x, (long double)y)); }

TEST(SpecularPow, InDoublesItIsTheCorrectlyRoundedPower) {
  if (!device_has_fp64()) {
    EXPECT_THROW(ClRuntime(test::test_device(), batch_options(SpecularPow::fp64)), ClError);
    GTEST_SKIP() << "the test device has no cl_khr_fp64: the specular power in doubles is refused (checked)";
  }
  ClRuntime rt(test::test_device(), batch_options(SpecularPow::fp64));
  ASSERT_TRUE(rt.specular_pow_fp64());
  std::vector<float> x, y;
  samples(x, y);
  const std::vector<float> got = device_pow(rt, x, y);
  std::size_t exact = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const float want = correctly_rounded(x[i], y[i]);
    ASSERT_LE(ulps(got[i], want), 1) << x[i] << "^" << y[i] << " = " << got[i] << ", not " << want;
    exact += got[i] == want;
  }
  // Off by one only where the exact power lies within about 2^-13 ulp of a
  // halfway point: almost never.
  EXPECT_GE(double(exact), 0.9999 * double(x.size())) << exact << " of " << x.size();
}

TEST(SpecularPow, TheDevicesFloatPowStaysWithinOpenClsBound) {
  ClRuntime rt(test::test_device(), batch_options(SpecularPow::fp32));
  ASSERT_FALSE(rt.specular_pow_fp64());
  std::vector<float> x, y;
  samples(x, y);
  const std::vector<float> got = device_pow(rt, x, y);
  for (std::size_t i = 0; i < x.size(); ++i)
    ASSERT_LE(ulps(got[i], correctly_rounded(x[i], y[i])), 16) << x[i] << "^" << y[i] << " = " << got[i];
}

TEST(SpecularPow, BothWaysKeepPowsSpecialCases) {
  const float inf = std::numeric_limits<float>::infinity();
  const std::vector<float> x = {0.0f, 0.0f, 1.0f, 0.5f, 1.0f, 0.25f, 0.0f};
  const std::vector<float> y = {0.0f, 2.0f, inf, inf, 0.0f, 0.0f, 96.078431f};
  const std::vector<float> want = {1.0f, 0.0f, 1.0f, 0.0f, 1.0f, 1.0f, 0.0f};
  for (SpecularPow how : {SpecularPow::fp32, SpecularPow::fp64}) {
    if (how == SpecularPow::fp64 && !device_has_fp64()) continue;  // refused, checked above
    ClRuntime rt(test::test_device(), batch_options(how));
    const std::vector<float> got = device_pow(rt, x, y);
    for (std::size_t i = 0; i < x.size(); ++i)
      EXPECT_EQ(got[i], want[i]) << x[i] << "^" << y[i] << (how == SpecularPow::fp64 ? " (doubles)" : " (floats)");
  }
}

// The frame with either power: byte-identical across PE counts each way,
// and the two ways within a few units of the pixel sums' last place (2^-24).
TEST(SpecularPow, BothWaysRenderTheSameImageButForTheLastBits) {
  if (!device_has_fp64()) GTEST_SKIP() << "the test device has no cl_khr_fp64: only the float pow can render";
  const Scene s = test::mirror_glass_scene(64, 5);
  std::vector<float> first[2];
  for (SpecularPow how : {SpecularPow::fp32, SpecularPow::fp64}) {
    ClRuntimeOptions o;
    o.read_environment = false;
    o.specular_pow = how;
    ClRuntime rt(test::test_device(), o);
    const int w = how == SpecularPow::fp64;
    for (int pes : {1, 16}) {
      RenderSettings rs;
      rs.num_pes = pes;
      const RenderResult r = render(s, rs, rt);
      if (first[w].empty()) first[w] = r.rgb;
      EXPECT_EQ(r.rgb, first[w]) << pes << " PEs";
    }
  }
  ASSERT_EQ(first[0].size(), first[1].size());
  for (std::size_t i = 0; i < first[0].size(); ++i)
    ASSERT_NEAR(first[0][i], first[1][i], 16 * 0x1p-24) << "channel " << i;
}

}  // namespace
}  // namespace opsila
