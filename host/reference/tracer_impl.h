// The reference tracer's state and its rules of the contract (nearest hit,
// shading), shared by the tracer (reference.cpp) and its ray sample
// (ray_sample.cpp). Private to host/reference.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "scene/camera.h"
#include "scene/instances.h"
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
  // A prototype's triangles and BVH in its own frame, built once for all
  // of its instances.
  struct Model {
    std::vector<Tri> tris;
    Bvh bvh;
  };

  const Scene& scene;
  std::vector<MaterialDesc> materials;  // the scene's, or CONTRACT's default if it has none
  std::vector<Tri> tris;
  Bvh bvh;
  std::vector<Model> models;   // per Scene::prototypes
  std::vector<Box> inst_boxes; // per Scene::instances: instance_holding_box, padded
  Bvh inst_bvh;                // over inst_boxes: leaves name instances
  CameraFrame frame;
  float epsilon = 0;
  const FacetQueries* queries = nullptr;  // instead of `bvh`, when given

  explicit Impl(const Scene& s) : scene(s) {}

  // The BVH walk every search shares: nodes of `tree` whose box the ray
  // meets within [t_min, t_max()] (read at each node: the nearest search
  // narrows it), their items handed to leaf(index), which returns true to
  // stop. Returns whether a leaf stopped it.
  template <typename TMax, typename Leaf>
  static bool walk(const Bvh& tree, const Vec3& origin, const Vec3& dir, float t_min, TMax t_max, Leaf leaf) {
    if (tree.nodes.empty()) return false;
    int stack[128];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& node = tree.nodes[stack[--top]];
      if (!reference::hits_box(node.box, origin, dir, t_min, t_max())) continue;
      if (node.count == 0) {
        stack[top++] = node.first;
        stack[top++] = node.first + 1;
        continue;
      }
      for (int i = node.first; i < node.first + node.count; ++i)
        if (leaf(tree.order[i])) return true;
    }
    return false;
  }

  // The instances the world ray may meet within [t_min, t_max()], each
  // handed to leaf(i, origin', dir') with the ray in its model's frame
  // (instances.h: not normalised, so t is the same parameter in both).
  template <typename TMax, typename Leaf>
  bool walk_instances(const Vec3& origin, const Vec3& dir, float t_min, TMax t_max, Leaf leaf) const {
    return walk(inst_bvh, origin, dir, t_min, t_max, [&](int i) {
      if (!reference::hits_box(inst_boxes[std::size_t(i)], origin, dir, t_min, t_max())) return false;
      const std::array<float, 12>& m = scene.instances[std::size_t(i)].to_object;
      return leaf(i, apply_point(m, origin), apply_vector(m, dir));
    });
  }

  const Model& model_of(int inst) const {
    return models[std::size_t(scene.instances[std::size_t(inst)].prototype)];
  }
  // The hit's triangle: hit.tri indexes the scene's, or for an instance
  // hit its prototype's.
  const Tri& tri_of(const Hit& hit) const {
    return hit.inst < 0 ? tris[std::size_t(hit.tri)] : model_of(hit.inst).tris[std::size_t(hit.tri)];
  }
  const Triangle& source_of(const Hit& hit) const {
    if (hit.inst < 0) return scene.triangles[std::size_t(hit.tri)];
    const int p = scene.instances[std::size_t(hit.inst)].prototype;
    return scene.prototypes[std::size_t(p)].triangles[std::size_t(hit.tri)];
  }

  // The hit order's key of a hit (hit_order.h).
  HitKey key_of(const Hit& hit) const {
    const Tri& tri = tri_of(hit);
    return hit_key(hit.t, hit.inst, tri.facet_id, tri.fan);
  }

  // Nearest hit with t > t_min before `best` among `set`'s triangles (the
  // scene's own, inst = -1, or instance inst's model, the ray in its frame).
  static void nearest_in(const std::vector<Tri>& set, const Bvh& tree, int inst, const Vec3& origin,
                         const Vec3& dir, float t_min, HitKey& best, Hit& hit) {
    walk(tree, origin, dir, t_min, [&] { return hit_limit(best.t); }, [&](int index) {
      float t, b1, b2;
      const Tri& tri = set[std::size_t(index)];
      if (reference::intersect(tri, origin, dir, t, &b1, &b2) && t > t_min &&
          hit_before(t, inst, tri.facet_id, tri.fan, best)) {
        best = hit_key(t, inst, tri.facet_id, tri.fan);
        hit.t = t;
        hit.tri = index;
        hit.inst = inst;
        hit.b1 = b1;
        hit.b2 = b2;
      }
      return false;
    });
  }

  // Nearest hit with t > t_min: the least in the one hit order (hit_order.h),
  // whatever order the BVHs visit the triangles and instances in. Boxes are
  // culled only beyond the end of the best hit's grid cell (widened in hits_box).
  bool own_nearest(const Vec3& origin, const Vec3& dir, float t_min, Hit& hit) const {
    HitKey best = hit.tri < 0 ? hit_none() : key_of(hit);
    nearest_in(tris, bvh, -1, origin, dir, t_min, best, hit);
    walk_instances(origin, dir, t_min, [&] { return hit_limit(best.t); }, [&](int i, const Vec3& o, const Vec3& d) {
      const Model& m = model_of(i);
      nearest_in(m.tris, m.bvh, i, o, d, t_min, best, hit);
      return false;
    });
    return hit.tri >= 0;
  }

  bool nearest(const Vec3& origin, const Vec3& dir, float t_min, Hit& hit) const {
    if (queries) return queries->nearest(origin, dir, t_min, hit);
    return own_nearest(origin, dir, t_min, hit);
  }

  // Is any of `set`'s triangles hit with t in (t_min, t_max)?
  static bool any_in(const std::vector<Tri>& set, const Bvh& tree, const Vec3& origin, const Vec3& dir,
                     float t_min, float t_max) {
    return walk(tree, origin, dir, t_min, [&] { return t_max; }, [&](int index) {
      float t;
      return reference::intersect(set[std::size_t(index)], origin, dir, t) && t > t_min && t < t_max;
    });
  }

  // Shadow test: is any triangle (the scene's own or an instance's) hit
  // with t in (t_min, t_max)?
  bool occluded(const Vec3& origin, const Vec3& dir, float t_min, float t_max) const {
    if (queries) return queries->occluded(origin, dir, t_min, t_max);
    if (any_in(tris, bvh, origin, dir, t_min, t_max)) return true;
    return walk_instances(origin, dir, t_min, [&] { return t_max; }, [&](int i, const Vec3& o, const Vec3& d) {
      const Model& m = model_of(i);
      return any_in(m.tris, m.bvh, o, d, t_min, t_max);
    });
  }

  // The item buffer's (object, facet) of a hit (CONTRACT "Item buffer"):
  // instance i is object num_objects + i, with its model's facet ids.
  void item_ids(const Hit& hit, std::int32_t* out) const {
    if (hit.tri < 0) {
      out[0] = out[1] = -1;
      return;
    }
    const Tri& tri = tri_of(hit);
    out[0] = hit.inst >= 0 ? scene.num_objects + hit.inst : tri.object_id;
    out[1] = tri.facet_id;
  }

  // CONTRACT "Smooth shading": the interpolated vertex normal (an instance's
  // through `to_object` to the world, not normalised before the length
  // test), turned to the side n_facing (the facet normal facing the ray) is
  // on; n_facing itself without vertex normals (or when they cancel out).
  Vec3 shading_normal(const Triangle& t, const Hit& hit, const Vec3& n_facing,
                      const std::array<float, 12>* to_object) const {
    if (!scene.smooth || t.attributes < 0) return n_facing;
    const VertexAttributes& a = scene.attributes[t.attributes];
    if (!a.has_normals) return n_facing;
    const float b0 = 1.0f - hit.b1 - hit.b2;
    Vec3 ns = b0 * a.normal[0] + hit.b1 * a.normal[1] + hit.b2 * a.normal[2];
    if (to_object) ns = instance_normal(*to_object, ns);
    const float len = length(ns);
    if (!(len > 0.0f) || !std::isfinite(len)) return n_facing;
    const Vec3 unit = ns / len;
    return dot(unit, n_facing) < 0.0f ? -unit : unit;
  }

  // CONTRACT "Texture maps": the material's colour times its map at the hit's
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

  // CONTRACT "Shading": the shadow ray from P (shading normal n) to `light`,
  // cast only where the light term can be non-zero (n.Lv > 0): false when
  // there is none.
  static bool shadow_ray(const Vec3& p, const Vec3& n, const LightDesc& light, Vec3& lv, float& distance,
                         float& n_dot_l) {
    const Vec3 to_light = light.position - p;
    distance = length(to_light);
    if (!(distance > 0.0f)) return false;  // light at P: no direction to it
    lv = to_light / distance;
    n_dot_l = dot(n, lv);
    return n_dot_l > 0.0f;  // CONTRACT: else the whole light term is 0
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

  // What a ray meets at its hit (CONTRACT "Shading"): the point, the side and
  // the shading normal there.
  struct Surface {
    Vec3 p, n;
    bool entering;
    const MaterialDesc* m;
    const Triangle* source;
  };
  // An instance's hit: Ng of its model-frame triangle taken to the world
  // and renormalised; the barycentrics are the model-frame ray's.
  Surface surface(const Vec3& origin, const Vec3& d, const Hit& hit) const {
    const Tri& tri = tri_of(hit);
    const std::array<float, 12>* to_object =
        hit.inst >= 0 ? &scene.instances[std::size_t(hit.inst)].to_object : nullptr;
    const Vec3 ng = to_object ? normalize(instance_normal(*to_object, tri.normal)) : tri.normal;
    Surface s;
    s.m = &materials[tri.material];
    s.p = origin + hit.t * d;
    s.entering = dot(ng, d) < 0.0f;
    s.source = &source_of(hit);
    s.n = shading_normal(*s.source, hit, s.entering ? ng : -ng, to_object);
    return s;
  }

  // CONTRACT "Materials": the reflected direction, renormalised (CONTRACT treats
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
  // Returns the ray's hit (for the item buffer; tri = -1: none).
  Hit trace(const Vec3& origin, const Vec3& d, float t_min, int level, const Vec3& weight,
            Vec3& pixel, RayCounts& counts) const {
    Hit hit;
    if (!nearest(origin, d, t_min, hit)) {
      add_contribution(pixel, weight * scene.background);
      return hit;
    }
    const Surface s = surface(origin, d, hit);
    const MaterialDesc& m = *s.m;
    const Vec3 ka = mapped(*s.source, hit, m.ka, m.map_ka), kd = mapped(*s.source, hit, m.kd, m.map_kd);
    add_contribution(pixel, weight * local_intensity(s.p, s.n, d, m, ka, kd, counts));

    if (level + 1 >= scene.max_depth) return hit;
    // CONTRACT "Materials": kr = Ks for illum 3..7, kt = Tf for illum 4, 6, 7.
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
    return hit;
  }

  // The sample's key of a hit's (facet, fan), after the distance's cell
  // and the instance: the rest of the hit order (sample_rays joins holders
  // on each).
  std::uint64_t sample_key(const Hit& hit) const {
    const Tri& t = tri_of(hit);
    return std::uint64_t(std::uint32_t(t.facet_id)) << 32 | std::uint32_t(t.fan);
  }
};

}  // namespace opsila
