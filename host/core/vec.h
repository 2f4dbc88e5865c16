// The host's one vocabulary for geometry: Vec3 (three floats, as the scene
// holds them), the few operations the camera, the partition, the bank BVH
// builder and the reference use, the axis-aligned Box, and the one slab
// test. All in float, each operation written once, in a fixed order of
// operations (left to right), so that every caller rounds the same way.
#pragma once

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>

namespace opsila {

using Vec3 = std::array<float, 3>;

inline Vec3 operator+(const Vec3& a, const Vec3& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
inline Vec3 operator-(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
inline Vec3 operator-(const Vec3& a) { return {-a[0], -a[1], -a[2]}; }
inline Vec3 operator*(const Vec3& a, const Vec3& b) { return {a[0] * b[0], a[1] * b[1], a[2] * b[2]}; }
inline Vec3 operator*(float s, const Vec3& a) { return {s * a[0], s * a[1], s * a[2]}; }
inline Vec3 operator*(const Vec3& a, float s) { return {a[0] * s, a[1] * s, a[2] * s}; }
inline Vec3 operator/(const Vec3& a, float s) { return {a[0] / s, a[1] / s, a[2] / s}; }
inline Vec3& operator+=(Vec3& a, const Vec3& b) { return a = a + b; }
inline Vec3 splat(float s) { return {s, s, s}; }

inline float dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
// Where a.a leaves the float range (a cross product of edges 2^40 long) or
// its normal range, `a` is first scaled by a power of two, exactly, so that
// its largest component lies in [1, 2); elsewhere it is as it is. `e` gets
// the power (0 unscaled). The kernels' in_range3 (kernels/lib/geometry.cl),
// step for step, so that lengths and unit vectors agree to the bit.
inline Vec3 in_range(const Vec3& a, int& e) {
  const float d = dot(a, a), m = std::fmax(std::fmax(std::fabs(a[0]), std::fabs(a[1])), std::fabs(a[2]));
  e = 0;
  if ((d < INFINITY && d >= FLT_MIN) || !(m > 0.0f) || std::isinf(m)) return a;
  e = std::ilogb(m);
  return {std::ldexp(a[0], -e), std::ldexp(a[1], -e), std::ldexp(a[2], -e)};
}
inline float length(const Vec3& a) {
  int e;
  const Vec3 s = in_range(a, e);
  return e == 0 ? std::sqrt(dot(s, s)) : std::ldexp(std::sqrt(dot(s, s)), e);
}
// Times the inverse length (one division, three products): the reference's
// ray directions and the camera's primary rays.
inline Vec3 normalize(const Vec3& a) {
  int e;
  const Vec3 s = in_range(a, e);
  return s * (1.0f / std::sqrt(dot(s, s)));
}
inline Vec3 min(const Vec3& a, const Vec3& b) {
  return {std::min(a[0], b[0]), std::min(a[1], b[1]), std::min(a[2], b[2])};
}
inline Vec3 max(const Vec3& a, const Vec3& b) {
  return {std::max(a[0], b[0]), std::max(a[1], b[1]), std::max(a[2], b[2])};
}
inline bool any_nonzero(const Vec3& v) { return v[0] != 0.0f || v[1] != 0.0f || v[2] != 0.0f; }

// An axis-aligned box; empty (lo above hi) until it grows. A NaN coordinate
// never enters it (std::min and std::max keep the box's own value).
struct Box {
  Vec3 lo{INFINITY, INFINITY, INFINITY};
  Vec3 hi{-INFINITY, -INFINITY, -INFINITY};
  void grow(const float* p) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], p[a]);
      hi[a] = std::max(hi[a], p[a]);
    }
  }
  void grow(const Vec3& p) { grow(p.data()); }
  // By another box, side by side: an empty one changes nothing.
  void grow(const Box& b) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], b.lo[a]);
      hi[a] = std::max(hi[a], b.hi[a]);
    }
  }
  float extent(int a) const { return hi[a] - lo[a]; }
  float center(int a) const { return 0.5f * (lo[a] + hi[a]); }
  Vec3 center() const { return {center(0), center(1), center(2)}; }
  int longest() const {
    int a = 0;
    for (int k = 1; k < 3; ++k)
      if (extent(k) > extent(a)) a = k;
    return a;
  }
  float diagonal() const {
    float s = 0;
    for (int a = 0; a < 3; ++a) s += extent(a) * extent(a);
    return std::sqrt(s);
  }
  float area() const {
    if (empty()) return 0.0f;
    const float x = extent(0), y = extent(1), z = extent(2);
    return 2 * (x * y + y * z + z * x);
  }
  bool empty() const { return !(lo[0] <= hi[0]); }
};

// The slab test: does the ray origin + t dir meet the closed box for some t
// in [t_min, t_max]? A direction component of zero keeps the ray in its
// slab or out of it (no 0 x infinity). `slack` widens each slab's exit by
// that fraction of its distance (the reference keeps it above the tie
// tolerance, so that rounding never culls a box that holds a possible tie).
inline bool slab_test(const Box& b, const Vec3& origin, const Vec3& dir, float t_min, float t_max,
                      float slack = 0.0f) {
  for (int a = 0; a < 3; ++a) {
    if (dir[a] == 0.0f) {
      if (origin[a] < b.lo[a] || origin[a] > b.hi[a]) return false;
      continue;
    }
    const float inv = 1.0f / dir[a];
    float t0 = (b.lo[a] - origin[a]) * inv;
    float t1 = (b.hi[a] - origin[a]) * inv;
    if (t0 > t1) std::swap(t0, t1);
    t_min = std::max(t_min, t0);
    t_max = std::min(t_max, slack != 0.0f ? t1 + std::fabs(t1) * slack : t1);
    if (t_min > t_max) return false;
  }
  return true;
}

}  // namespace opsila
