// CONTRACT "Texture maps" sampling, written once for the host: the sRGB decode
// table (also uploaded to the kernels, so both decode texels identically)
// and the bilinear, repeating lookup the reference tracer uses.
// kernels/lib/texture.cl is the same lookup, expression for expression.
#pragma once

#include <array>
#include <cstdint>

#include "scene/scene.h"

namespace opsila {

// Linear value of each 8-bit sRGB code (IEC 61966-2-1), computed in double.
const std::array<float, 256>& srgb_decode_table();

// The colour of `texture` at (u, v): texel (i, j) has its centre at
// u = (i + 0.5) / w, v = 1 - (j + 0.5) / h; coordinates repeat outside
// [0, 1); the four nearest texels are decoded to linear, then blended
// bilinearly. A non-finite coordinate reads as 0.
Vec3 sample_texture(const Texture& texture, float u, float v);

}  // namespace opsila
