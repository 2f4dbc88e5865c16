// The Embree baseline: Embree finds the hits, the host reference
// (reference/reference.h) does everything else as CONTRACT says: the camera and
// its samples, smooth normals, texture maps, shading and the ray tree. So it
// is the OPSILA image's work with Embree's traversal, on all host threads.
// Instances are Embree instances of one scene per model. Built only when
// CMake finds Embree (OPSILA_HAVE_EMBREE); otherwise
// render_embree throws and embree_available() is false.
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>


#include "bench/bench.h"
#include "reference/reference.h"

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

// Embree 4 dropped the intersect context argument; Debian 12 ships 3.
#if RTC_VERSION_MAJOR >= 4
void intersect_one(RTCScene scene, RTCRayHit& rh) { rtcIntersect1(scene, &rh); }
void occluded_one(RTCScene scene, RTCRay& ray) { rtcOccluded1(scene, &ray); }
#else
RTCIntersectContext* fresh(RTCIntersectContext& ctx) {
  rtcInitIntersectContext(&ctx);
  return &ctx;
}
void intersect_one(RTCScene scene, RTCRayHit& rh) {
  RTCIntersectContext ctx;
  rtcIntersect1(scene, fresh(ctx), &rh);
}
void occluded_one(RTCScene scene, RTCRay& ray) {
  RTCIntersectContext ctx;
  rtcOccluded1(scene, fresh(ctx), &ray);
}
#endif

struct EmbreeScene {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  std::vector<RTCScene> models;  // one per prototype, instanced by `scene`
  ~EmbreeScene() {
    if (scene) rtcReleaseScene(scene);
    for (RTCScene m : models)
      if (m) rtcReleaseScene(m);
    if (device) rtcReleaseDevice(device);
  }
};

// The facets of `tris` with an area (no area, no normal: the reference's
// own BVH leaves them out too), as indices into `tris`.
std::vector<int> facets_with_area(const std::vector<Triangle>& tris) {
  std::vector<int> kept;
  for (std::size_t i = 0; i < tris.size(); ++i) {
    const Triangle& t = tris[i];
    const float area = length(cross(t.v1 - t.v0, t.v2 - t.v0));
    if (area > 0.0f && std::isfinite(area)) kept.push_back(static_cast<int>(i));
  }
  return kept;
}

// One Embree triangle geometry of tris[kept[i]] attached to `scene`.
void attach_triangles(RTCDevice device, RTCScene scene, const std::vector<Triangle>& tris,
                      const std::vector<int>& kept) {
  RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  const std::size_t nt = kept.size();
  auto* vb = static_cast<float*>(
      rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), 3 * nt));
  auto* ib = static_cast<unsigned*>(
      rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), nt));
  if (!vb || !ib) {
    rtcReleaseGeometry(geom);
    throw std::runtime_error("rtcSetNewGeometryBuffer failed");
  }
  for (std::size_t i = 0; i < nt; ++i) {
    const Triangle& t = tris[std::size_t(kept[i])];
    const Vec3* v[3] = {&t.v0, &t.v1, &t.v2};  // in order: Embree's u, v are CONTRACT's b1, b2
    for (int k = 0; k < 3; ++k)
      for (int a = 0; a < 3; ++a) vb[9 * i + 3 * k + a] = (*v[k])[a];
    for (int k = 0; k < 3; ++k) ib[3 * i + k] = static_cast<unsigned>(3 * i + k);
  }
  rtcCommitGeometry(geom);
  rtcAttachGeometryByID(scene, geom, 0);
  rtcReleaseGeometry(geom);
}

// The scene's own facets in one Embree triangle geometry, and each
// prototype in a scene of its own that Embree instances at every placement
// (its own two-level walk); Embree answers the reference tracer's
// nearest-hit and shadow queries.
class EmbreeQueries : public FacetQueries {
 public:
  explicit EmbreeQueries(const Scene& s) {
    es_.device = rtcNewDevice(nullptr);
    if (!es_.device)  // Embree's threads and arenas: the host's limits (ulimit -v, -u) as a rule
      throw InputError("Embree, the bench's baseline, could not start (rtcNewDevice failed, error " +
                       std::to_string(int(rtcGetDeviceError(nullptr))) +
                       "): the process's memory or thread limit (ulimit -v, ulimit -u) is too low");
    es_.scene = rtcNewScene(es_.device);
    facet_of_ = facets_with_area(s.triangles);
    if (!facet_of_.empty()) attach_triangles(es_.device, es_.scene, s.triangles, facet_of_);
    for (const Prototype& p : s.prototypes) {
      model_facet_of_.push_back(facets_with_area(p.triangles));
      es_.models.push_back(rtcNewScene(es_.device));
      attach_triangles(es_.device, es_.models.back(), p.triangles, model_facet_of_.back());
      rtcCommitScene(es_.models.back());
    }
    for (std::size_t i = 0; i < s.instances.size(); ++i) {
      const InstanceDesc& in = s.instances[i];
      prototype_of_.push_back(in.prototype);
      RTCGeometry geom = rtcNewGeometry(es_.device, RTC_GEOMETRY_TYPE_INSTANCE);
      rtcSetGeometryInstancedScene(geom, es_.models[std::size_t(in.prototype)]);
      float m[12];
      for (int k = 0; k < 12; ++k) m[k] = static_cast<float>(in.to_world[std::size_t(k)]);
      rtcSetGeometryTransform(geom, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, m);
      rtcCommitGeometry(geom);
      rtcAttachGeometryByID(es_.scene, geom, static_cast<unsigned>(i + 1));  // 0: the scene's own
      rtcReleaseGeometry(geom);
    }
    rtcCommitScene(es_.scene);
  }

  bool nearest(const Vec3& org, const Vec3& dir, float t_min, FacetHit& hit) const override {
    RTCRayHit rh;
    set_ray(rh.ray, org, dir, t_min, std::numeric_limits<float>::infinity());
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    intersect_one(es_.scene, rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
    hit.t = rh.ray.tfar;
    const unsigned inst = rh.hit.instID[0];
    hit.inst = inst == RTC_INVALID_GEOMETRY_ID ? -1 : static_cast<int>(inst) - 1;
    hit.tri = hit.inst < 0 ? facet_of_[rh.hit.primID]
                           : model_facet_of_[std::size_t(prototype_of_[std::size_t(hit.inst)])][rh.hit.primID];
    hit.b1 = rh.hit.u;
    hit.b2 = rh.hit.v;
    return true;
  }

  bool occluded(const Vec3& org, const Vec3& dir, float t_min, float t_max) const override {
    RTCRay ray;
    set_ray(ray, org, dir, t_min, t_max);
    occluded_one(es_.scene, ray);
    return ray.tfar < 0.0f;  // -inf when something was hit
  }

 private:
  static void set_ray(RTCRay& ray, const Vec3& org, const Vec3& dir, float t_min, float t_max) {
    ray.org_x = org[0], ray.org_y = org[1], ray.org_z = org[2];
    ray.dir_x = dir[0], ray.dir_y = dir[1], ray.dir_z = dir[2];
    ray.tnear = t_min;
    ray.tfar = t_max;
    ray.time = 0.0f;
    ray.mask = 0xFFFFFFFFu;
    ray.id = 0;
    ray.flags = 0;
  }

  EmbreeScene es_;
  std::vector<int> facet_of_;  // Embree primitive -> index in Scene::triangles
  std::vector<std::vector<int>> model_facet_of_;  // per prototype: primitive -> its triangle
  std::vector<int> prototype_of_;  // per instance
};

}  // namespace

BaselineImage render_embree(const Scene& s, int threads) {
  if (s.triangles.empty() && s.instances.empty()) throw InputError("scene has no facets");
  const auto t_build = std::chrono::steady_clock::now();
  const EmbreeQueries queries(s);
  const ReferenceTracer tracer(s, &queries);
  BaselineImage out;
  static_cast<ImageResult&>(out) = blank_image(s.width, s.height);
  out.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_build).count();

  const auto t0 = std::chrono::steady_clock::now();
  tracer.render_image(out, threads);
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

#endif  // OPSILA_HAVE_EMBREE

}  // namespace opsila
