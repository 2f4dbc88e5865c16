// The Embree baseline: the same rays and the same shading as the OPSILA
// renderer (kernels/spmd_phase.cl), traced with Embree on all host threads.
// Built only when CMake finds Embree (OPSILA_HAVE_EMBREE); otherwise
// render_embree throws and embree_available() is false.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <thread>

#include "bench/bench.h"
#include "core/camera.h"
#include "core/fixed_point.h"
#include "opsila_shared.h"

#ifdef OPSILA_HAVE_EMBREE
#if __has_include(<embree4/rtcore.h>)
#include <embree4/rtcore.h>
#else
#include <embree3/rtcore.h>
#endif
#endif

namespace opsila {

#ifndef OPSILA_HAVE_EMBREE

bool embree_available() { return false; }
std::string embree_version() { return ""; }
BaselineImage render_embree(const Scene&, int) {
  throw std::runtime_error("this opsila was built without Embree (install libembree-dev and reconfigure)");
}

#else

bool embree_available() { return true; }
std::string embree_version() { return RTC_VERSION_STRING; }

namespace {

// float3 arithmetic as OpenCL C does it, operation by operation.
struct F3 {
  float x, y, z;
};
inline F3 operator+(F3 a, F3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline F3 operator-(F3 a, F3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline F3 operator-(F3 a) { return {-a.x, -a.y, -a.z}; }
inline F3 operator*(F3 a, F3 b) { return {a.x * b.x, a.y * b.y, a.z * b.z}; }
inline F3 operator*(float s, F3 a) { return {s * a.x, s * a.y, s * a.z}; }
inline F3 operator/(F3 a, float s) { return {a.x / s, a.y / s, a.z / s}; }
inline float dot(F3 a, F3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline F3 cross(F3 a, F3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
inline float length(F3 a) { return std::sqrt(dot(a, a)); }
inline F3 normalize(F3 a) { return a / length(a); }
inline bool nonzero(F3 a) { return a.x != 0.0f || a.y != 0.0f || a.z != 0.0f; }
inline F3 f3(const Vec3& v) { return {v[0], v[1], v[2]}; }

struct Shading {
  F3 ka, kd, ks, kr, kt;
  float ns, ni;
};

struct EmbreeScene {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  ~EmbreeScene() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
};

struct Tracer {
  const Scene& s;
  RTCScene scene;
  std::vector<Shading> materials;
  std::vector<F3> normals;  // Ng = normalize(cross(v1 - v0, v2 - v0)) per triangle
  F3 eye, forward, right, up, ambient, background;
  float tan_half_fov, aspect, eps;

  bool nearest(F3 org, F3 d, float tmin, float& t, unsigned& prim) const {
    RTCRayHit rh;
    rh.ray.org_x = org.x, rh.ray.org_y = org.y, rh.ray.org_z = org.z;
    rh.ray.dir_x = d.x, rh.ray.dir_y = d.y, rh.ray.dir_z = d.z;
    rh.ray.tnear = tmin;
    rh.ray.tfar = std::numeric_limits<float>::infinity();
    rh.ray.time = 0.0f;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.ray.id = 0;
    rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
#if RTC_VERSION_MAJOR >= 4
    rtcIntersect1(scene, &rh);
#else
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    rtcIntersect1(scene, &ctx, &rh);
#endif
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
    t = rh.ray.tfar;
    prim = rh.hit.primID;
    return true;
  }

  bool occluded(F3 org, F3 d, float tmin, float tmax) const {
    RTCRay ray;
    ray.org_x = org.x, ray.org_y = org.y, ray.org_z = org.z;
    ray.dir_x = d.x, ray.dir_y = d.y, ray.dir_z = d.z;
    ray.tnear = tmin;
    ray.tfar = tmax;
    ray.time = 0.0f;
    ray.mask = 0xFFFFFFFFu;
    ray.id = 0;
    ray.flags = 0;
#if RTC_VERSION_MAJOR >= 4
    rtcOccluded1(scene, &ray);
#else
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    rtcOccluded1(scene, &ctx, &ray);
#endif
    return ray.tfar < 0.0f;  // -inf when something was hit
  }

  // The camera ray through image point (px, py); pixel x's centre is x + 0.5.
  F3 camera_ray(float px, float py) const {
    const float sx = (2.0f * px / static_cast<float>(s.width) - 1.0f) * tan_half_fov * aspect;
    const float sy = (1.0f - 2.0f * py / static_cast<float>(s.height)) * tan_half_fov;
    return normalize(forward + sx * right + sy * up);
  }

  // (object, facet) of the centre ray's hit, for even k where no sample is it.
  void centre_item(int x, int y, std::int32_t item[2]) const {
    float t;
    unsigned prim;
    if (nearest(eye, camera_ray(static_cast<float>(x) + 0.5f, static_cast<float>(y) + 0.5f), 0.0f, t, prim))
      item[0] = s.triangles[prim].object_id, item[1] = s.triangles[prim].facet_id;
  }

  // One sample's Whitted tree, shaded as kernels/spmd_phase.cl shades it;
  // `item` (the centre ray's sample only) gets the primary hit.
  void sample(float px, float py, std::int64_t sum[3], std::int32_t* item, RayCounts& rays) const {
    struct Pending {
      F3 org, dir, w;
      int level;
    };
    Pending stack[OPSILA_MAX_DEPTH + 2];
    int sp = 0;
    stack[sp++] = {eye, camera_ray(px, py), {1.0f, 1.0f, 1.0f}, 0};
    ++rays.primary;
    auto add = [&](F3 v) {
      sum[0] = add_fixed_saturating(sum[0], to_fixed(v.x));  // >= 0, as add_fixed saturates
      sum[1] = add_fixed_saturating(sum[1], to_fixed(v.y));
      sum[2] = add_fixed_saturating(sum[2], to_fixed(v.z));
    };
    while (sp > 0) {
      const Pending r = stack[--sp];
      const F3 d = r.dir;
      float t;
      unsigned prim;
      if (!nearest(r.org, d, r.level == 0 ? 0.0f : eps, t, prim)) {
        add(r.w * background);
        continue;
      }
      const Triangle& tri = s.triangles[prim];
      if (r.level == 0 && item) item[0] = tri.object_id, item[1] = tri.facet_id;
      const F3 ng = normals[prim];
      const F3 p = r.org + t * d;
      const bool entering = dot(ng, d) < 0.0f;
      const F3 n = entering ? ng : -ng;
      const Shading& m = materials[tri.material];
      add(r.w * ambient * m.ka);
      for (const LightDesc& light : s.lights) {
        const F3 to_light = f3(light.position) - p;
        const float dist = length(to_light);
        const F3 lv = to_light / dist;
        const float ndl = dot(n, lv);
        if (!(ndl > 0.0f)) continue;
        const F3 rl = (2.0f * ndl) * n - lv;
        const float spec = std::max(0.0f, dot(rl, -d));
        const float highlight = std::pow(spec, m.ns);
        const F3 term = ndl * m.kd + highlight * m.ks;
        const F3 contrib = r.w * f3(light.intensity) * term;
        if (!nonzero(contrib)) continue;
        ++rays.shadow;
        if (!occluded(p, lv, eps, dist)) add(contrib);
      }
      if (r.level + 1 >= s.max_depth) continue;
      if (nonzero(m.kt)) {
        const float eta = entering ? 1.0f / m.ni : m.ni;
        const float c = -dot(n, d);
        const float k = 1.0f - eta * eta * (1.0f - c * c);
        if (k >= 0.0f) {
          ++rays.secondary;
          stack[sp++] = {p, normalize(eta * d + (eta * c - std::sqrt(k)) * n), r.w * m.kt, r.level + 1};
        }
      }
      if (nonzero(m.kr)) {
        ++rays.secondary;
        stack[sp++] = {p, normalize(d - (2.0f * dot(d, n)) * n), r.w * m.kr, r.level + 1};
      }
    }
  }
};

}  // namespace

BaselineImage render_embree(const Scene& s, int threads) {
  if (s.triangles.empty()) throw InputError("scene has no facets");
  BaselineImage out;
  out.width = s.width;
  out.height = s.height;
  const std::size_t npix = std::size_t(s.width) * s.height;

  auto t_build = std::chrono::steady_clock::now();
  EmbreeScene es;
  es.device = rtcNewDevice(nullptr);
  if (!es.device) throw std::runtime_error("rtcNewDevice failed");
  es.scene = rtcNewScene(es.device);
  RTCGeometry geom = rtcNewGeometry(es.device, RTC_GEOMETRY_TYPE_TRIANGLE);
  const std::size_t nt = s.triangles.size();
  auto* vb = static_cast<float*>(
      rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), 3 * nt));
  auto* ib = static_cast<unsigned*>(
      rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), nt));
  if (!vb || !ib) throw std::runtime_error("rtcSetNewGeometryBuffer failed");
  Tracer tr{s, nullptr, {}, {}, {}, {}, {}, {}, {}, {}, 0, 0, 0};
  tr.normals.resize(nt);
  for (std::size_t i = 0; i < nt; ++i) {
    const Triangle& t = s.triangles[i];
    const Vec3* v[3] = {&t.v0, &t.v1, &t.v2};
    for (int k = 0; k < 3; ++k)
      for (int a = 0; a < 3; ++a) vb[9 * i + 3 * k + a] = (*v[k])[a];
    for (int k = 0; k < 3; ++k) ib[3 * i + k] = static_cast<unsigned>(3 * i + k);
    tr.normals[i] = normalize(cross(f3(t.v1) - f3(t.v0), f3(t.v2) - f3(t.v0)));
  }
  rtcCommitGeometry(geom);
  rtcAttachGeometry(es.scene, geom);
  rtcReleaseGeometry(geom);
  rtcCommitScene(es.scene);
  tr.scene = es.scene;
  std::vector<MaterialDesc> materials = s.materials;
  if (materials.empty()) materials.push_back(MaterialDesc::default_material());
  for (const MaterialDesc& m : materials)
    tr.materials.push_back({f3(m.ka), f3(m.kd), f3(m.ks), f3(m.kr()), f3(m.kt()), m.ns, m.ni});

  // The camera basis in float, as the renderer computes it.
  const CameraFrame cam = camera_frame(s.camera, s.width, s.height);
  tr.eye = f3(cam.eye);
  tr.forward = f3(cam.forward);
  tr.right = f3(cam.right);
  tr.up = f3(cam.up);
  tr.ambient = f3(s.ambient);
  tr.background = f3(s.background);
  tr.tan_half_fov = cam.tan_half_fov;
  tr.aspect = cam.aspect;
  tr.eps = s.epsilon();
  out.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_build).count();

  std::vector<std::int64_t> sums(npix * 3, 0);
  out.item_buffer.assign(npix * 2, -1);
  threads = std::max(1, std::min(threads, s.height));
  std::vector<RayCounts> counts(threads);
  auto t0 = std::chrono::steady_clock::now();
  constexpr int kBand = 4;  // interleaved bands of rows, as the host reference does
  const int k = spp_side(s.spp);  // SPEC's k x k samples; the item is the centre ray's
  const std::vector<float> offsets = sample_offsets(s.spp);
  auto work = [&](int w) {
    for (int y0 = w * kBand; y0 < s.height; y0 += threads * kBand)
      for (int y = y0; y < std::min(y0 + kBand, s.height); ++y)
        for (int x = 0; x < s.width; ++x) {
          const std::size_t i = std::size_t(y) * s.width + x;
          for (int j = 0; j < k; ++j)
            for (int c = 0; c < k; ++c) {
              std::int32_t* item = 2 * c + 1 == k && 2 * j + 1 == k ? &out.item_buffer[2 * i] : nullptr;
              tr.sample(static_cast<float>(x) + offsets[c], static_cast<float>(y) + offsets[j], &sums[3 * i], item,
                        counts[w]);
            }
          if (k % 2 == 0) tr.centre_item(x, y, &out.item_buffer[2 * i]);
        }
  };
  std::vector<std::thread> pool;
  for (int w = 1; w < threads; ++w) pool.emplace_back(work, w);
  work(0);
  for (std::thread& t : pool) t.join();
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  out.rgb.resize(npix * 3);
  for (std::size_t i = 0; i < npix * 3; ++i)
    out.rgb[i] = from_fixed(static_cast<std::uint64_t>(sums[i]), s.spp);
  for (const RayCounts& c : counts) {
    out.rays.primary += c.primary;
    out.rays.secondary += c.secondary;
    out.rays.shadow += c.shadow;
  }
  return out;
}

#endif  // OPSILA_HAVE_EMBREE

}  // namespace opsila
