/* CONTRACT "Texture maps": the bilinear, repeating lookup of a bank's texture
 * copy. host/scene/texture.cpp is the same lookup, expression for
 * expression; srgb is the host's 256-entry sRGB decode table. */
#include "geometry.cl"

inline float3 texel_linear(__global const uint *texels, __global const float *srgb, int index) {
  uint c = texels[index];
  return (float3)(srgb[c & 255u], srgb[(c >> 8) & 255u], srgb[(c >> 16) & 255u]);
}

inline float3 sample_texture(__global const BankTexture *tex, __global const uint *texels, __global const float *srgb,
                             float u, float v) {
  int w = tex->width, h = tex->height;
  if (!isfinite(u)) u = 0.0f;
  if (!isfinite(v)) v = 0.0f;
  /* Repeat, then the texel-centre convention: x = i + 0.5 at u = (i + 0.5) / w. */
  float x = (u - floor(u)) * (float)w - 0.5f;
  float y = (1.0f - (v - floor(v))) * (float)h - 0.5f;
  float fx = floor(x), fy = floor(y);
  float tx = x - fx, ty = y - fy;
  int i0 = (int)fx, j0 = (int)fy; /* in [-1, w-1] and [-1, h-1] */
  if (i0 < 0) i0 += w;
  if (j0 < 0) j0 += h;
  if (i0 >= w) i0 -= w;
  if (j0 >= h) j0 -= h;
  int i1 = i0 + 1 == w ? 0 : i0 + 1;
  int j1 = j0 + 1 == h ? 0 : j0 + 1;
  int base = tex->texel_begin;
  float3 a = texel_linear(texels, srgb, base + j0 * w + i0), b = texel_linear(texels, srgb, base + j0 * w + i1);
  float3 c = texel_linear(texels, srgb, base + j1 * w + i0), d = texel_linear(texels, srgb, base + j1 * w + i1);
  float3 top = a + (b - a) * tx, bottom = c + (d - c) * tx;
  return top + (bottom - top) * ty;
}
