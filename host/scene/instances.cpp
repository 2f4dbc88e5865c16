#include "scene/instances.h"

#include <cfloat>
#include <cmath>
#include <cstdio>
#include <string>

#include "core/errors.h"

namespace opsila {

InstanceDesc make_instance(int prototype, const std::array<double, 12>& w, const std::string& where) {
  // The 3 x 3 part's inverse by cofactors, in double.
  const double a = w[0], b = w[1], c = w[2], d = w[4], e = w[5], f = w[6], g = w[8], h = w[9], k = w[10];
  const double det = a * (e * k - f * h) - b * (d * k - f * g) + c * (d * h - e * g);
  double scale = 0;
  for (int i = 0; i < 12; ++i)
    if (i % 4 != 3) scale = std::max(scale, std::fabs(w[std::size_t(i)]));
  const auto number = [](double v) {
    char text[32];
    std::snprintf(text, sizeof text, "%.6g", v);
    return std::string(text);
  };
  if (!std::isfinite(det) || !(std::fabs(det) > 1e-30 * scale * scale * scale))
    throw InputError(where + ": the transform is singular or nearly so (determinant " + number(det) +
                     " for a largest entry of " + number(scale) + ": at most 1e-30 of its cube)");
  const double inv[9] = {(e * k - f * h) / det, (c * h - b * k) / det, (b * f - c * e) / det,
                         (f * g - d * k) / det, (a * k - c * g) / det, (c * d - a * f) / det,
                         (d * h - e * g) / det, (b * g - a * h) / det, (a * e - b * d) / det};
  InstanceDesc in;
  in.prototype = prototype;
  in.to_world = w;
  for (int r = 0; r < 3; ++r) {
    double t = 0;
    for (int j = 0; j < 3; ++j) {
      in.to_object[std::size_t(4 * r + j)] = static_cast<float>(inv[3 * r + j]);
      t -= inv[3 * r + j] * w[std::size_t(4 * j + 3)];
    }
    in.to_object[std::size_t(4 * r + 3)] = static_cast<float>(t);
  }
  for (float x : in.to_object)
    if (!std::isfinite(x)) throw InputError(where + ": the transform's inverse overflows float");
  return in;
}

Vec3 apply_point(const std::array<float, 12>& m, const Vec3& p) {
  Vec3 out;
  for (int r = 0; r < 3; ++r) {
    const float* row = &m[std::size_t(4 * r)];
    out[std::size_t(r)] = row[0] * p[0] + row[1] * p[1] + row[2] * p[2] + row[3];
  }
  return out;
}

Vec3 apply_vector(const std::array<float, 12>& m, const Vec3& v) {
  Vec3 out;
  for (int r = 0; r < 3; ++r) {
    const float* row = &m[std::size_t(4 * r)];
    out[std::size_t(r)] = row[0] * v[0] + row[1] * v[1] + row[2] * v[2];
  }
  return out;
}

Vec3 instance_normal(const std::array<float, 12>& m, const Vec3& n) {
  return {m[0] * n[0] + m[4] * n[1] + m[8] * n[2], m[1] * n[0] + m[5] * n[1] + m[9] * n[2],
          m[2] * n[0] + m[6] * n[1] + m[10] * n[2]};
}

namespace {

// The model's box through to_world, every corner in double: l, u per axis.
void placed_corners(const Scene& scene, const InstanceDesc& in, double l[3], double u[3]) {
  const Prototype& p = scene.prototypes[std::size_t(in.prototype)];
  for (int r = 0; r < 3; ++r) l[r] = INFINITY, u[r] = -INFINITY;
  for (int corner = 0; corner < 8; ++corner) {
    const double x[3] = {(corner & 1) ? p.hi[0] : p.lo[0], (corner & 2) ? p.hi[1] : p.lo[1],
                         (corner & 4) ? p.hi[2] : p.lo[2]};
    for (int r = 0; r < 3; ++r) {
      const double* row = &in.to_world[std::size_t(4 * r)];
      const double y = row[0] * x[0] + row[1] * x[1] + row[2] * x[2] + row[3];
      l[r] = std::min(l[r], y);
      u[r] = std::max(u[r], y);
    }
  }
}

}  // namespace

void instance_box(const Scene& scene, const InstanceDesc& in, Vec3& lo, Vec3& hi) {
  double l[3], u[3];
  placed_corners(scene, in, l, u);
  for (int r = 0; r < 3; ++r) lo[std::size_t(r)] = static_cast<float>(l[r]), hi[std::size_t(r)] = static_cast<float>(u[r]);
}

void instance_holding_box(const Scene& scene, const InstanceDesc& in, Vec3& lo, Vec3& hi) {
  double l[3], u[3];
  placed_corners(scene, in, l, u);
  double size = 0, magnitude = 0;
  for (int r = 0; r < 3; ++r) {
    size = std::max(size, u[r] - l[r]);
    magnitude = std::max({magnitude, std::fabs(l[r]), std::fabs(u[r])});
  }
  const double pad = std::ldexp(size + magnitude, -16);
  for (int r = 0; r < 3; ++r) {
    lo[std::size_t(r)] = std::nextafter(static_cast<float>(l[r] - pad), -INFINITY);
    hi[std::size_t(r)] = std::nextafter(static_cast<float>(u[r] + pad), INFINITY);
  }
}

std::uint64_t instanced_triangles(const Scene& scene) {
  std::uint64_t n = 0;
  for (const InstanceDesc& in : scene.instances) n += scene.prototypes[std::size_t(in.prototype)].triangles.size();
  return n;
}

std::uint64_t prototype_triangles(const Scene& scene) {
  std::uint64_t n = 0;
  for (const Prototype& p : scene.prototypes) n += p.triangles.size();
  return n;
}

}  // namespace opsila
