// Division and square root on the device. The runtime builds the kernels
// with -cl-fp32-correctly-rounded-divide-sqrt wherever the device reports
// CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT, so there x / y, 1 / y and sqrt(x) are
// the host's IEEE results bit for bit (camera rays, slab inverses and hit
// distances then start from the same bits on every device). A device without
// it is held to OpenCL C 1.2's bounds instead: 2.5 ulp for x / y, 3 ulp for
// sqrt.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "batch.h"
#include "core/vec.h"

namespace opsila {
namespace {

// Distance in representable floats between two finite floats of one sign.
std::int64_t ulps(float a, float b) {
  std::int32_t ia, ib;
  std::memcpy(&ia, &a, 4);
  std::memcpy(&ib, &b, 4);
  return std::llabs(std::int64_t(ia) - std::int64_t(ib));
}

TEST(DeviceArithmetic, DivisionAndSquareRootAreTheHostsWhereTheDeviceOffersIt) {
  ClRuntime& rt = test::batch_runtime();
  const bool offered =
      (test::test_device().device.getInfo<CL_DEVICE_SINGLE_FP_CONFIG>() & CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT) != 0;
  EXPECT_EQ(rt.exact_divide(), offered) << "the build option follows the device's report";
  // Operands as the kernels meet them: direction components (tiny to 1, both
  // signs), coordinates and determinants over many binades.
  std::mt19937 rng(1987);
  std::uniform_real_distribution<float> mantissa(1.0f, 2.0f);
  std::uniform_int_distribution<int> binade(-40, 40), sign(0, 1);
  std::vector<float> x, y;
  for (int i = 0; i < 1 << 16; ++i) {
    x.push_back(std::ldexp(mantissa(rng), binade(rng)));
    y.push_back((sign(rng) ? -1.0f : 1.0f) * std::ldexp(mantissa(rng), binade(rng)));
  }
  const std::size_t n = x.size();
  cl::Buffer bx = test::to_device(rt, x), by = test::to_device(rt, y);
  cl::Buffer q = test::to_device(rt, std::vector<float>(n)), inv = test::to_device(rt, std::vector<float>(n)),
             root = test::to_device(rt, std::vector<float>(n));
  cl::Kernel k = rt.kernel("divide_batch");
  int a = 0;
  for (const cl::Buffer* b : {&bx, &by}) k.setArg(a++, *b);
  k.setArg(a++, cl_int(n));
  for (const cl::Buffer* b : {&q, &inv, &root}) k.setArg(a++, *b);
  test::run_batch(rt, k, n);
  const std::vector<float> got_q = test::from_device<float>(rt, q, n), got_inv = test::from_device<float>(rt, inv, n),
                           got_root = test::from_device<float>(rt, root, n);
  // Ulps allowed: none where correctly rounded; else OpenCL C 1.2's 2.5
  // (rounded up) for x / y and 1 / y, 3 for sqrt.
  const std::int64_t div_ulps = offered ? 0 : 3, sqrt_ulps = offered ? 0 : 3;
  for (std::size_t i = 0; i < n; ++i) {
    const std::string at = std::to_string(x[i]) + ", " + std::to_string(y[i]);
    ASSERT_LE(ulps(got_q[i], x[i] / y[i]), div_ulps) << at << ": x / y = " << got_q[i];
    ASSERT_LE(ulps(got_inv[i], 1.0f / y[i]), div_ulps) << at << ": 1 / y = " << got_inv[i];
    ASSERT_LE(ulps(got_root[i], std::sqrt(x[i])), sqrt_ulps) << at << ": sqrt(x) = " << got_root[i];
  }
  if (!offered)
    GTEST_SKIP() << "the device does not report CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT: held to OpenCL's bounds only";
}

// Lengths and unit vectors: the host's and the kernels' scale a vector
// whose square leaves the float range by the same power of two, so they
// agree to the bit where division and square root do, far beyond the
// square's range too (components near 2^100 and 2^-100).
TEST(DeviceArithmetic, LengthsAndUnitVectorsAreTheHosts) {
  ClRuntime& rt = test::batch_runtime();
  std::mt19937 rng(1987);
  std::uniform_real_distribution<float> mantissa(1.0f, 2.0f);
  std::uniform_int_distribution<int> binade(-8, 8), scale(-110, 110), sign(0, 1);
  std::vector<float> v;
  for (int i = 0; i < 1 << 14; ++i) {
    const int s = scale(rng);
    for (int c = 0; c < 3; ++c) v.push_back((sign(rng) ? -1.0f : 1.0f) * std::ldexp(mantissa(rng), s + binade(rng)));
  }
  const std::size_t n = v.size() / 3;
  cl::Buffer bv = test::to_device(rt, v), len = test::to_device(rt, std::vector<float>(n)),
             unit = test::to_device(rt, std::vector<float>(3 * n));
  cl::Kernel k = rt.kernel("unit_batch");
  test::set_args(k, bv, cl_int(n), len, unit);
  test::run_batch(rt, k, n);
  const std::vector<float> got_len = test::from_device<float>(rt, len, n),
                           got_unit = test::from_device<float>(rt, unit, 3 * n);
  const std::int64_t allowed = rt.exact_divide() ? 0 : 6;  // two roundings of OpenCL's bounds where not exact
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 a{v[3 * i], v[3 * i + 1], v[3 * i + 2]};
    const Vec3 u = normalize(a);
    const std::string at = std::to_string(a[0]) + ", " + std::to_string(a[1]) + ", " + std::to_string(a[2]);
    ASSERT_TRUE(std::isfinite(length(a)) && length(a) > 0.0f) << at;
    ASSERT_LE(ulps(got_len[i], length(a)), allowed) << at << ": length " << got_len[i] << " against " << length(a);
    for (int c = 0; c < 3; ++c)
      ASSERT_LE(ulps(got_unit[3 * i + c], u[c]), allowed) << at << ": unit[" << c << "] " << got_unit[3 * i + c];
  }
}

}  // namespace
}  // namespace opsila
