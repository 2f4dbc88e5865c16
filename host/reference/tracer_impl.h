// The reference tracer's state and its rules of the contract (nearest hit,
// shading), shared by the tracer (reference.cpp) and its ray sample
// (ray_sample.cpp). Private to host/reference.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "scene/camera.h"
#include "scene/texture.h"
#include "hit_order.h"
#include "reference/reference.h"
#include "reference/reference_bvh.h"

namespace opsila {

using reference::Bvh;
using reference::Node;
using reference::Tri;
using Hit = FacetHit;

struct ReferenceTracer::Impl {
  const Scene& scene;
  std::vector<MaterialDesc> materials;  // the scene's, or SPEC's default if it has none
  std::vector<Tri> tris;
  Bvh bvh;
  CameraFrame frame;
  float epsilon = 0;
  const FacetQueries* queries = nullptr;  // instead of `bvh`, when given

  explicit Impl(const Scene& s) : scene(s) {}

  // The BVH walk both searches share: nodes whose box the ray meets within
  // [t_min, t_max()] (read at each node: the nearest search narrows it),
  // their triangles handed to leaf(index), which returns true to stop.
  template <typename TMax, typename Leaf>
  void walk(const Vec3& origin, const Vec3& dir, float t_min, TMax t_max, Leaf leaf) const {
    if (bvh.nodes.empty()) return;
    int stack[128];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& node = bvh.nodes[stack[--top]];
      if (!reference::hits_box(node, origin, dir, t_min, t_max())) continue;
      if (node.count == 0) {
        stack[top++] = node.first;
        stack[top++] = node.first + 1;
        continue;
      }
      for (int i = node.first; i < node.first + node.count; ++i)
        if (leaf(bvh.order[i])) return;
    }
  }

  // The hit order's key of triangle `index` hit at t (hit_order.h).
  HitKey key_of(float t, int index) const {
    const Tri& tri = tris[std::size_t(index)];
    return hit_key(t, -1, tri.facet_id, tri.fan);
  }

  // Nearest hit with t > t_min: the least in the one hit order (hit_order.h),
  // whatever order the BVH visits the triangles in. Boxes are culled only
  // beyond the end of the best hit's grid cell (widened in hits_box).
  bool own_nearest(const Vec3& origin, const Vec3& dir, float t_min, Hit& hit) const {
    HitKey best = hit.tri < 0 ? hit_none() : key_of(hit.t, hit.tri);
    walk(origin, dir, t_min, [&] { return hit_limit(best.t); }, [&](int index) {
      float t, b1, b2;
      const Tri& tri = tris[std::size_t(index)];
      if (reference::intersect(tri, origin, dir, t, &b1, &b2) && t > t_min && hit_before(t, -1, tri.facet_id, tri.fan, best)) {
        best = key_of(t, index);
        hit.t = t;
        hit.tri = index;
        hit.b1 = b1;
        hit.b2 = b2;
      }
      return false;
    });
    return hit.tri >= 0;
  }

  bool nearest(const Vec3& origin, const Vec3& dir, float t_min, Hit& hit) const {
    if (queries) return queries->nearest(origin, dir, t_min, hit);
    return own_nearest(origin, dir, t_min, hit);
  }

  // Shadow test: is any triangle hit with t in (t_min, t_max)?
  bool occluded(const Vec3& origin, const Vec3& dir, float t_min, float t_max) const {
    if (queries) return queries->occluded(origin, dir, t_min, t_max);
    bool blocked = false;
    walk(origin, dir, t_min, [&] { return t_max; }, [&](int index) {
      float t;
      blocked = reference::intersect(tris[index], origin, dir, t) && t > t_min && t < t_max;
      return blocked;
    });
    return blocked;
  }

  // SPEC "Smooth shading": the interpolated vertex normal, turned to the
  // side n_facing (the facet normal facing the ray) is on; n_facing itself
  // without vertex normals (or when they cancel out).
  Vec3 shading_normal(const Triangle& t, const Hit& hit, const Vec3& n_facing) const {
    if (!scene.smooth || t.attributes < 0) return n_facing;
    const VertexAttributes& a = scene.attributes[t.attributes];
    if (!a.has_normals) return n_facing;
    const float b0 = 1.0f - hit.b1 - hit.b2;
    const Vec3 ns = b0 * a.normal[0] + hit.b1 * a.normal[1] + hit.b2 * a.normal[2];
    const float len = length(ns);
    if (!(len > 0.0f) || !std::isfinite(len)) return n_facing;
    const Vec3 unit = ns / len;
    return dot(unit, n_facing) < 0.0f ? -unit : unit;
  }

  // SPEC "Texture maps": the material's colour times its map at the hit's
  // interpolated texture coordinates, where the facet has them.
  Vec3 mapped(const Triangle& t, const Hit& hit, const Vec3& colour, int map) const {
    if (map < 0 || map >= static_cast<int>(scene.textures.size()) || t.attributes < 0) return colour;
    const VertexAttributes& a = scene.attributes[t.attributes];
    if (!a.has_uv) return colour;
    const float b0 = 1.0f - hit.b1 - hit.b2;
    const float u = b0 * a.uv[0][0] + hit.b1 * a.uv[1][0] + hit.b2 * a.uv[2][0];
    const float v = b0 * a.uv[0][1] + hit.b1 * a.uv[1][1] + hit.b2 * a.uv[2][1];
    return colour * sample_texture(scene.textures[map], u, v);
  }

  // SPEC "Shading": the shadow ray from P (shading normal n) to `light`,
  // cast only where the light term can be non-zero (n.Lv > 0): false when
  // there is none.
  static bool shadow_ray(const Vec3& p, const Vec3& n, const LightDesc& light, Vec3& lv, float& distance,
                         float& n_dot_l) {
    const Vec3 to_light = light.position - p;
    distance = length(to_light);
    if (!(distance > 0.0f)) return false;  // light at P: no direction to it
    lv = to_light / distance;
    n_dot_l = dot(n, lv);
    return n_dot_l > 0.0f;  // SPEC: else the whole light term is 0
  }

  // Local intensity at P with shading normal n, for a ray of unit direction
  // d, with the (texture-mapped) ka and kd at P.
  Vec3 local_intensity(const Vec3& p, const Vec3& n, const Vec3& d, const MaterialDesc& m, const Vec3& ka,
                       const Vec3& kd, RayCounts& counts) const {
    Vec3 result = scene.ambient * ka;
    for (const LightDesc& light : scene.lights) {
      Vec3 lv;
      float distance, n_dot_l;
      if (!shadow_ray(p, n, light, lv, distance, n_dot_l)) continue;
      ++counts.shadow;
      if (occluded(p, lv, epsilon, distance)) continue;  // vis = 0
      const Vec3 rl = 2.0f * n_dot_l * n - lv;
      const float r_dot_v = std::max(0.0f, dot(rl, -d));
      // C's powf: powf(0, 0) = 1, so Ns = 0 gives the full Ks.
      const float highlight = std::pow(r_dot_v, m.ns);
      result += light.intensity * (kd * n_dot_l + m.ks * highlight);
    }
    return result;
  }

  // What a ray meets at its hit (SPEC "Shading"): the point, the side and
  // the shading normal there.
  struct Surface {
    Vec3 p, n;
    bool entering;
    const MaterialDesc* m;
    const Triangle* source;
  };
  Surface surface(const Vec3& origin, const Vec3& d, const Hit& hit) const {
    const Tri& tri = tris[hit.tri];
    Surface s;
    s.m = &materials[tri.material];
    s.p = origin + hit.t * d;
    s.entering = dot(tri.normal, d) < 0.0f;
    s.source = &scene.triangles[hit.tri];
    s.n = shading_normal(*s.source, hit, s.entering ? tri.normal : -tri.normal);
    return s;
  }

  // SPEC "Materials": the reflected direction, renormalised (SPEC treats
  // every ray direction as unit, and epsilon is a distance).
  static Vec3 reflected(const Vec3& d, const Vec3& n) { return normalize(d - 2.0f * dot(d, n) * n); }
  // The transmitted direction; false on total internal reflection (k < 0).
  static bool transmitted(const Vec3& d, const Vec3& n, bool entering, float ni, Vec3& out) {
    const float eta = entering ? 1.0f / ni : ni;
    const float c = -dot(n, d);
    const float k = 1.0f - eta * eta * (1.0f - c * c);
    if (!(k >= 0.0f)) return false;
    out = normalize(eta * d + (eta * c - std::sqrt(k)) * n);
    return true;
  }

  // As the kernels' fixed point: a NaN term (0 x infinity, from values near
  // the float limit) adds nothing.
  static void add_contribution(Vec3& pixel, const Vec3& c) {
    for (int k = 0; k < 3; ++k)
      if (!std::isnan(c[k])) pixel[k] += c[k];
  }

  // Adds weight x (radiance of the ray tree rooted at this ray) to `pixel`.
  // Returns the triangle hit (for the item buffer), or -1.
  int trace(const Vec3& origin, const Vec3& d, float t_min, int level, const Vec3& weight,
            Vec3& pixel, RayCounts& counts) const {
    Hit hit;
    if (!nearest(origin, d, t_min, hit)) {
      add_contribution(pixel, weight * scene.background);
      return -1;
    }
    const Surface s = surface(origin, d, hit);
    const MaterialDesc& m = *s.m;
    const Vec3 ka = mapped(*s.source, hit, m.ka, m.map_ka), kd = mapped(*s.source, hit, m.kd, m.map_kd);
    add_contribution(pixel, weight * local_intensity(s.p, s.n, d, m, ka, kd, counts));

    if (level + 1 >= scene.max_depth) return hit.tri;
    // SPEC "Materials": kr = Ks for illum 3..7, kt = Tf for illum 4, 6, 7.
    const Vec3 kr = m.kr();
    const Vec3 kt = m.kt();
    if (any_nonzero(kr)) {
      ++counts.secondary;
      trace(s.p, reflected(d, s.n), epsilon, level + 1, weight * kr, pixel, counts);
    }
    Vec3 t_dir;
    if (any_nonzero(kt) && transmitted(d, s.n, s.entering, m.ni, t_dir)) {
      ++counts.secondary;
      trace(s.p, t_dir, epsilon, level + 1, weight * kt, pixel, counts);
    }
    return hit.tri;
  }

  // The sample's key of a triangle after the distance's cell: (facet, fan),
  // the rest of the hit order (sample_rays joins holders on both).
  std::uint64_t sample_key(int index) const {
    const Tri& t = tris[std::size_t(index)];
    return std::uint64_t(std::uint32_t(t.facet_id)) << 32 | std::uint32_t(t.fan);
  }
};

}  // namespace opsila
