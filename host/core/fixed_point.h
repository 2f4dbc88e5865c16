// Pixel sums in 64-bit fixed point with OPSILA_FIXED_SHIFT fraction bits
// (kernels/lib/accum.cl): integer sums do not depend on the order in which
// PEs finish, so images are bit-identical run to run. The quantisation and
// the decode every renderer shares.
#pragma once

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

// A sum back to a linear value.
inline float from_fixed(std::int64_t sum) { return static_cast<float>(static_cast<double>(sum) / OPSILA_FIXED_SCALE); }

// The mean of `samples` values whose fixed-point sum is `sum` (SPEC's N
// samples per pixel): one division by samples x 2^24, so one sample decodes
// exactly as from_fixed does, and N equal samples (a sum N*s, exact in double
// up to 2^53) decode to exactly the one sample's value.
inline float from_fixed(std::int64_t sum, int samples) {
  return static_cast<float>(static_cast<double>(sum) / (static_cast<double>(OPSILA_FIXED_SCALE) * samples));
}

// One 64-bit counter from the (low, high) 32-bit words the kernels add to.
inline std::uint64_t join_words(std::uint32_t low, std::uint32_t high) {
  return (std::uint64_t(high) << 32) | low;
}

}  // namespace opsila
