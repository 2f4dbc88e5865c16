#include "scene/texture.h"

#include <cmath>

namespace opsila {

const std::array<float, 256>& srgb_decode_table() {
  static const std::array<float, 256> table = [] {
    std::array<float, 256> t{};
    for (int c = 0; c < 256; ++c) {
      const double s = c / 255.0;
      t[c] = static_cast<float>(s <= 0.04045 ? s / 12.92 : std::pow((s + 0.055) / 1.055, 2.4));
    }
    return t;
  }();
  return table;
}

namespace {

struct Rgb {
  float r, g, b;
};

Rgb texel(const Texture& t, int i, int j) {
  const std::uint32_t c = t.texels[static_cast<std::size_t>(j) * t.width + i];
  const std::array<float, 256>& lut = srgb_decode_table();
  return {lut[c & 255u], lut[(c >> 8) & 255u], lut[(c >> 16) & 255u]};
}

// OpenCL's mix(a, b, t) = a + (b - a) * t.
float mix(float a, float b, float t) { return a + (b - a) * t; }

}  // namespace

Vec3 sample_texture(const Texture& t, float u, float v) {
  if (t.width <= 0 || t.height <= 0 || t.texels.empty()) return Vec3{1, 1, 1};
  if (!std::isfinite(u)) u = 0.0f;
  if (!std::isfinite(v)) v = 0.0f;
  // Repeat, then the texel-centre convention: x = i + 0.5 at u = (i + 0.5) / w.
  const float x = (u - std::floor(u)) * static_cast<float>(t.width) - 0.5f;
  const float y = (1.0f - (v - std::floor(v))) * static_cast<float>(t.height) - 0.5f;
  const float fx = std::floor(x), fy = std::floor(y);
  const float tx = x - fx, ty = y - fy;
  int i0 = static_cast<int>(fx), j0 = static_cast<int>(fy);  // in [-1, w-1] and [-1, h-1]
  if (i0 < 0) i0 += t.width;
  if (j0 < 0) j0 += t.height;
  if (i0 >= t.width) i0 -= t.width;
  if (j0 >= t.height) j0 -= t.height;
  const int i1 = i0 + 1 == t.width ? 0 : i0 + 1;
  const int j1 = j0 + 1 == t.height ? 0 : j0 + 1;
  const Rgb a = texel(t, i0, j0), b = texel(t, i1, j0), c = texel(t, i0, j1), d = texel(t, i1, j1);
  return Vec3{mix(mix(a.r, b.r, tx), mix(c.r, d.r, tx), ty), mix(mix(a.g, b.g, tx), mix(c.g, d.g, tx), ty),
              mix(mix(a.b, b.b, tx), mix(c.b, d.b, tx), ty)};
}

}  // namespace opsila
