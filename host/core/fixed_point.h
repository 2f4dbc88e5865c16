// Pixel sums in 64-bit fixed point with OPSILA_FIXED_SHIFT fraction bits
// (kernels/lib/accum.cl): integer sums do not depend on the order in which
// PEs finish, so images are bit-identical run to run. The quantisation and
// the decode every renderer shares.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "opsila_shared.h"

namespace opsila {

// As the kernels' convert_long_sat_rte(v * OPSILA_FIXED_SCALE): round to
// nearest even, saturating; NaN gives 0.
inline std::int64_t to_fixed(float v) {
  const float s = v * OPSILA_FIXED_SCALE;
  if (std::isnan(s)) return 0;
  if (s >= 9.2233720368547758e18f) return std::numeric_limits<std::int64_t>::max();
  if (s <= -9.2233720368547758e18f) return std::numeric_limits<std::int64_t>::min();
  return static_cast<std::int64_t>(std::nearbyint(s));
}

// The largest pixel sum: 2^63 - 1 in fixed point, 2^39 (about 5.5e11) as a
// value. Every term of a pixel is >= 0, so sums only grow: the kernels'
// add_fixed marks a sum that reached 2^63, the megakernel and the Embree
// baseline stop at 2^63 - 1, and the reference stops at the same value
// (saturate_sum). Such a sum decodes as the largest, never as a wrapped one.
constexpr float kMaxPixelValue = static_cast<float>(std::uint64_t(1) << (63 - OPSILA_FIXED_SHIFT));

inline bool saturated(std::uint64_t sum) {
  return sum >= std::uint64_t(std::numeric_limits<std::int64_t>::max());
}

// Two sums added as the kernels' add_fixed adds to one: a sum that reached
// 2^63 (bit 63 set) stays marked, and two that reach it together are marked
// (each below 2^63 unmarked, their sum cannot wrap). How the MPI ranks'
// pixel sums are added (Ranks::reduce_sum), so that ranks saturate as one
// device does.
inline std::uint64_t add_sums(std::uint64_t a, std::uint64_t b) {
  return (a + b) | ((a | b) & (std::uint64_t(1) << 63));
}

// A sum back to a linear value.
inline float from_fixed(std::uint64_t sum) {
  if (saturated(sum)) return kMaxPixelValue;
  return static_cast<float>(static_cast<double>(sum) / OPSILA_FIXED_SCALE);
}

// The mean of `samples` values whose fixed-point sum is `sum` (CONTRACT's N
// samples per pixel): one division by samples x 2^24, so one sample decodes
// exactly as from_fixed does, and N equal samples (a sum N*s, exact in double
// up to 2^53) decode to exactly the one sample's value. A saturated sum gives
// kMaxPixelValue / samples.
inline float from_fixed(std::uint64_t sum, int samples) {
  const double s = saturated(sum) ? static_cast<double>(kMaxPixelValue) * OPSILA_FIXED_SCALE
                                  : static_cast<double>(sum);
  return static_cast<float>(s / (static_cast<double>(OPSILA_FIXED_SCALE) * samples));
}

// from_fixed(sum, samples) for a whole image: the same floats. Where the
// divisor samples x 2^24 is a power of two (1, 4, 16, 64 ... samples), its
// reciprocal is exact and so is a product by it (a power-of-two scaling of a
// double far from under- and overflow), so a multiplication replaces the
// division; other counts divide as from_fixed does.
class MeanDecoder {
 public:
  explicit MeanDecoder(int samples)
      : divisor_(static_cast<double>(OPSILA_FIXED_SCALE) * samples),
        exact_(samples > 0 && (samples & (samples - 1)) == 0),
        inverse_(1.0 / divisor_) {}
  float operator()(std::uint64_t sum) const { return static_cast<float>(mean(sum)); }
  // What kernels/resolve.cl computes the same floats with.
  void kernel_constants(double& divisor, double& inverse, int& exact) const {
    divisor = divisor_, inverse = inverse_, exact = exact_ ? 1 : 0;
  }
  // The mean before its rounding to float: from_fixed's quotient, exactly.
  double mean(std::uint64_t sum) const {
    const double s = saturated(sum) ? static_cast<double>(kMaxPixelValue) * OPSILA_FIXED_SCALE
                                    : static_cast<double>(sum);
    return exact_ ? s * inverse_ : s / divisor_;
  }

 private:
  double divisor_;
  bool exact_;
  double inverse_;
};

// The pixel sum that `n` adds of q (>= 0) leave in a zero sum, as
// add_fixed_owned in kernels/lib/accum.cl makes it: a carry out of the 64
// bits sets the top bit (from_fixed then reads the saturated value). What a
// pixel that misses in every sample pass holds (frame_readback.cpp).
inline std::uint64_t owned_sum(std::int64_t q, int n) {
  std::uint64_t s = 0;
  for (int k = 0; k < n; ++k) {
    const std::uint64_t old = s;
    s += static_cast<std::uint64_t>(q);
    if (s < old) s |= std::uint64_t(1) << 63;
  }
  return s;
}

// Adds a contribution (>= 0) to a host-side sum, saturating at 2^63 - 1.
inline std::int64_t add_fixed_saturating(std::int64_t sum, std::int64_t q) {
  return q > std::numeric_limits<std::int64_t>::max() - sum ? std::numeric_limits<std::int64_t>::max()
                                                            : sum + q;
}

// A float renderer's (the reference's) sum as the fixed-point ones give it:
// NaN terms (0 x infinity) were left out, and it stops at kMaxPixelValue,
// infinity included.
inline double saturate_sum(double v) {
  return std::isnan(v) ? 0.0 : std::min(v, static_cast<double>(kMaxPixelValue));
}

// One 64-bit counter from the (low, high) 32-bit words the kernels add to.
inline std::uint64_t join_words(std::uint32_t low, std::uint32_t high) {
  return (std::uint64_t(high) << 32) | low;
}

}  // namespace opsila
