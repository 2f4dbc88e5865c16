// The pixel sums' fixed-point conversion on the device (fixed3,
// kernels/lib/accum.cl) is the host's to_fixed (host/core/fixed_point.h)
// and OpenCL's convert_long_sat_rte, bit for bit: round to nearest even,
// NaN to 0, saturation at both ends of 64 bits, for every lane.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "batch.h"
#include "core/fixed_point.h"

namespace opsila {
namespace {

// Values whose product by the scale falls on the cases: halfway between
// integers (both parities), just inside and beyond +-2^63, zeros, NaN,
// infinities, subnormals, and a spread over every binade in between.
std::vector<float> cases() {
  const float scale = OPSILA_FIXED_SCALE;
  std::vector<float> x = {0.0f, -0.0f, std::numeric_limits<float>::quiet_NaN(),
                          std::numeric_limits<float>::infinity(), std::numeric_limits<float>::denorm_min(),
                          std::numeric_limits<float>::max(), std::numeric_limits<float>::min()};
  for (float k : {0.5f, 1.5f, 2.5f, 3.5f, 1023.5f, 8388607.5f})  // ties, to even and to odd
    x.push_back(k / scale);
  const float top = std::ldexp(1.0f, 63);
  for (float t : {top, std::nextafter(top, 0.0f), std::nextafter(top, 2 * top), std::ldexp(1.0f, 62)})
    x.push_back(t / scale);
  std::mt19937 rng(1987);
  std::uniform_real_distribution<float> mantissa(1.0f, 2.0f);
  std::uniform_int_distribution<int> binade(-40, 50);
  for (int i = 0; i < 1 << 14; ++i) x.push_back(std::ldexp(mantissa(rng), binade(rng)));
  return x;
}

TEST(DeviceArithmetic, FixedPointIsTheHostsAndOpenCLsSaturatingRoundToEven) {
  ClRuntime& rt = test::batch_runtime();
  const std::vector<float> x = cases();
  const std::size_t n = x.size();
  cl::Buffer bx = test::to_device(rt, x);
  cl::Buffer fixed = test::to_device(rt, std::vector<cl_long>(3 * n)), builtin = test::to_device(rt, std::vector<cl_long>(3 * n));
  cl::Kernel k = rt.kernel("fixed_point_batch");
  test::set_args(k, bx, cl_int(n), fixed, builtin);
  test::run_batch(rt, k, n);
  const std::vector<cl_long> got = test::from_device<cl_long>(rt, fixed, 3 * n),
                             want_cl = test::from_device<cl_long>(rt, builtin, 3 * n);
  for (std::size_t i = 0; i < n; ++i) {
    const float lanes[3] = {x[i], -x[i], x[i] * 0.5f};
    for (int c = 0; c < 3; ++c) {
      const std::string at = "value " + std::to_string(lanes[c]) + " (case " + std::to_string(i) + ", lane " +
                             std::to_string(c) + ")";
      ASSERT_EQ(got[3 * i + c], to_fixed(lanes[c])) << at << ": the host's to_fixed";
      // OpenCL converts NaN to 0, but Rusticl's built-in gives LONG_MIN:
      // fixed3 masks it, and is compared with the host alone there.
      if (!std::isnan(lanes[c])) ASSERT_EQ(got[3 * i + c], want_cl[3 * i + c]) << at << ": convert_long_sat_rte";
    }
  }
}

}  // namespace
}  // namespace opsila
