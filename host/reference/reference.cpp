// SPEC.md in code, for one processor. Sections below follow SPEC's order:
// camera, geometry (intersection + a BVH that only speeds up the search),
// shading. Arithmetic is single precision, like the OpenCL kernels.
#include "reference/reference.h"

#include "core/progress.h"
#include "core/fixed_point.h"
#include "core/texture.h"
#include "hit_order.h"
#include "opsila_shared.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <exception>
#include <stdexcept>
#include <type_traits>
#include <limits>
#include <thread>


namespace opsila {

namespace {

// ---------------------------------------------------------------- geometry

// A triangle as the tracer needs it: the vertices' edges for the
// intersection test, Ng from the vertices (SPEC "Geometry"), and the ids.
struct Tri {
  Vec3 v0, e1, e2;
  Vec3 normal;   // Ng = normalize(cross(v1 - v0, v2 - v0))
  bool degenerate;  // zero area: no well-defined Ng, never hit
  int material, object_id, facet_id;
  int fan;  // the triangle's index in its facet's fan: the hit order's last key
};

// Möller–Trumbore. Edges and vertices count as inside. Returns the ray
// parameter t (distance along a unit direction), or nothing; u and v are
// SPEC's barycentrics b1, b2 of the hit.
bool intersect(const Tri& tri, const Vec3& origin, const Vec3& dir, float& t_out, float* b1 = nullptr,
               float* b2 = nullptr) {
  const Vec3 p = cross(dir, tri.e2);
  const float det = dot(tri.e1, p);
  if (det == 0.0f) return false;  // ray parallel to the plane
  const float inv_det = 1.0f / det;
  const Vec3 s = origin - tri.v0;
  const float u = dot(s, p) * inv_det;
  if (!(u >= 0.0f && u <= 1.0f)) return false;
  const Vec3 q = cross(s, tri.e1);
  const float v = dot(dir, q) * inv_det;
  if (!(v >= 0.0f && u + v <= 1.0f)) return false;
  t_out = dot(tri.e2, q) * inv_det;
  if (b1) *b1 = u;
  if (b2) *b2 = v;
  return std::isfinite(t_out);
}

// A plain BVH (median split on the longest centroid axis). It only decides
// which triangles get tested; the nearest-hit rule below does not depend on
// the order in which they are visited.
struct Node {
  Box box;
  int first = 0;  // leaf: first index into `order`; inner: left child
  int count = 0;  // leaf: number of triangles; inner: 0 (right child = left + 1)
};

struct Bvh {
  std::vector<Node> nodes;
  std::vector<int> order;  // triangle indices, grouped by leaf
};

constexpr int kLeafSize = 4;

// Subtrees of at least this many triangles are built on a thread of their
// own while threads are left (build_node's `threads`).
constexpr int kParallelBuild = 1 << 16;

// Node `node_index` of `nodes` over bvh.order[begin, end): its box, and a
// leaf, or two children appended and built. Children are appended in
// depth-first order (a node's pair, then all of the left child's subtree,
// then the right's), so a subtree built into a vector of its own, its root
// at 0, is the same subtree shifted: the halves of a big node are built at
// once on `threads` threads and spliced, giving the tree one thread builds
// (8.4 M facets: 2.9 s -> 1.6 s on 2 threads).
void build_node(std::vector<Node>& nodes, std::vector<int>& order, int node_index, int begin, int end,
                const std::vector<Vec3>& lo_of, const std::vector<Vec3>& hi_of, float pad, int threads) {
  Vec3 lo = splat(std::numeric_limits<float>::max()), hi = splat(-std::numeric_limits<float>::max());
  Vec3 clo = lo, chi = hi;
  for (int i = begin; i < end; ++i) {
    const int t = order[i];
    lo = min(lo, lo_of[t]);
    hi = max(hi, hi_of[t]);
    const Vec3 c = (lo_of[t] + hi_of[t]) * 0.5f;
    clo = min(clo, c);
    chi = max(chi, c);
  }
  // Padding keeps boxes conservative against rounding in the slab test.
  nodes[node_index].box.lo = lo - splat(pad);
  nodes[node_index].box.hi = hi + splat(pad);

  const Vec3 extent = chi - clo;
  int axis = 0;
  if (extent[1] > extent[axis]) axis = 1;
  if (extent[2] > extent[axis]) axis = 2;
  if (end - begin <= kLeafSize || !(extent[axis] > 0.0f)) {
    nodes[node_index].first = begin;
    nodes[node_index].count = end - begin;
    return;
  }
  const int mid = begin + (end - begin) / 2;
  auto centroid_less = [&](int a, int b) {
    const float ca = lo_of[a][axis] + hi_of[a][axis], cb = lo_of[b][axis] + hi_of[b][axis];
    return ca < cb || (ca == cb && a < b);
  };
  std::nth_element(order.begin() + begin, order.begin() + mid, order.begin() + end, centroid_less);
  const int left = static_cast<int>(nodes.size());
  nodes.emplace_back();
  nodes.emplace_back();
  nodes[node_index].first = left;
  nodes[node_index].count = 0;
  if (threads < 2 || end - begin < 2 * kParallelBuild) {
    build_node(nodes, order, left, begin, mid, lo_of, hi_of, pad, 1);
    build_node(nodes, order, left + 1, mid, end, lo_of, hi_of, pad, 1);
    return;
  }
  // The halves touch disjoint ranges of `order`. The lower one is built in
  // place by a helper thread (it is the next to append to `nodes`), the
  // upper one meanwhile into nodes of its own, appended after it.
  std::vector<Node> upper(1);
  std::exception_ptr failed;
  std::thread helper([&] {
    try {
      build_node(nodes, order, left, begin, mid, lo_of, hi_of, pad, threads / 2);
    } catch (...) {
      failed = std::current_exception();
    }
  });
  try {
    build_node(upper, order, 0, mid, end, lo_of, hi_of, pad, threads - threads / 2);
  } catch (...) {
    helper.join();
    throw;
  }
  helper.join();
  if (failed) std::rethrow_exception(failed);
  // Its node i > 0 lands at i + shift, its root at left + 1; an inner
  // node's children move with it (a leaf's first indexes `order`).
  const int shift = static_cast<int>(nodes.size()) - 1;
  const auto moved = [shift](Node n) {
    if (n.count == 0) n.first += shift;
    return n;
  };
  nodes[std::size_t(left) + 1] = moved(upper[0]);
  for (std::size_t i = 1; i < upper.size(); ++i) nodes.push_back(moved(upper[i]));
}

Bvh build_bvh(const std::vector<Tri>& tris, const std::vector<Triangle>& source, float pad, int threads) {
  Bvh bvh;
  std::vector<Vec3> lo_of, hi_of;
  for (std::size_t i = 0; i < tris.size(); ++i) {
    if (tris[i].degenerate) continue;
    bvh.order.push_back(static_cast<int>(i));
  }
  lo_of.resize(tris.size());
  hi_of.resize(tris.size());
  for (std::size_t i = 0; i < tris.size(); ++i) {
    const Vec3 a = source[i].v0, b = source[i].v1, c = source[i].v2;
    lo_of[i] = min(a, min(b, c));
    hi_of[i] = max(a, max(b, c));
  }
  if (bvh.order.empty()) return bvh;
  bvh.nodes.reserve(2 * bvh.order.size());
  bvh.nodes.emplace_back();
  if (threads <= 0) threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  build_node(bvh.nodes, bvh.order, 0, 0, static_cast<int>(bvh.order.size()), lo_of, hi_of, pad, threads);
  return bvh;
}

// A node's box met within [t_min, t_max]; the exit widened by the hit
// order's culling slack, so that rounding never culls a box holding a hit
// before the best (hit_order.h).
bool hits_box(const Node& node, const Vec3& origin, const Vec3& dir, float t_min, float t_max) {
  return slab_test(node.box, origin, dir, t_min, t_max, OPSILA_CULL_SLACK);
}

using Hit = FacetHit;

}  // namespace

// ------------------------------------------------------------------ tracer

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
      if (!hits_box(node, origin, dir, t_min, t_max())) continue;
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
    return hit_key(t, tri.facet_id, tri.fan);
  }

  // Nearest hit with t > t_min: the least in the one hit order (hit_order.h),
  // whatever order the BVH visits the triangles in. Boxes are culled only
  // beyond the end of the best hit's grid cell (widened in hits_box).
  bool own_nearest(const Vec3& origin, const Vec3& dir, float t_min, Hit& hit) const {
    HitKey best = hit.tri < 0 ? hit_none() : key_of(hit.t, hit.tri);
    walk(origin, dir, t_min, [&] { return hit_limit(best.t); }, [&](int index) {
      float t, b1, b2;
      const Tri& tri = tris[std::size_t(index)];
      if (intersect(tri, origin, dir, t, &b1, &b2) && t > t_min && hit_before(t, tri.facet_id, tri.fan, best)) {
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
      blocked = intersect(tris[index], origin, dir, t) && t > t_min && t < t_max;
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

ReferenceTracer::ReferenceTracer(const Scene& scene, const FacetQueries* queries, int build_threads)
    : scene_(scene), impl_(new Impl(scene)) {
  // SPEC: epsilon = 1e-4 x the diagonal of the bounding box of the facets.
  epsilon_ = scene.epsilon();
  impl_->epsilon = epsilon_;

  impl_->materials = scene.materials;
  // SPEC "a face with no material".
  if (impl_->materials.empty()) impl_->materials.push_back(MaterialDesc::default_material());
  check_hit_order_ids(scene);
  impl_->tris.reserve(scene.triangles.size());
  for (const Triangle& t : scene.triangles) {
    Tri tri;
    tri.v0 = t.v0;
    tri.e1 = t.v1 - tri.v0;
    tri.e2 = t.v2 - tri.v0;
    const Vec3 c = cross(tri.e1, tri.e2);
    const float len = length(c);
    tri.degenerate = !(len > 0.0f) || !std::isfinite(len);
    tri.normal = tri.degenerate ? splat(0.0f) : c / len;
    tri.material = t.material >= 0 && t.material < static_cast<int>(impl_->materials.size()) ? t.material : 0;
    tri.object_id = t.object_id;
    tri.facet_id = t.facet_id;
    tri.fan = t.fan;
    impl_->tris.push_back(tri);
  }
  impl_->queries = queries;
  const float pad = static_cast<float>(1e-5 * scene.diagonal()) + 1e-30f;
  if (!queries) impl_->bvh = build_bvh(impl_->tris, scene.triangles, pad, build_threads);
  impl_->frame = camera_frame(scene.camera, scene.width, scene.height);
}

ReferenceTracer::~ReferenceTracer() = default;

Vec3 ReferenceTracer::render_pixel(int x, int y, std::int32_t* object_facet,
                                   RayCounts& counts) const {
  const Scene& scene = scene_;
  const Vec3 eye = scene.camera.eye;
  // SPEC "Camera": a k x k grid of samples; the pixel is their mean.
  const int k = spp_side(scene.spp);
  double sum[3] = {0.0, 0.0, 0.0};
  int centre_tri = -1;
  for (int j = 0; j < k; ++j) {
    for (int i = 0; i < k; ++i) {
      const float px = static_cast<float>(x) + spp_offset(i, k), py = static_cast<float>(y) + spp_offset(j, k);
      const Vec3 dir = primary_direction_at(impl_->frame, scene.width, scene.height, px, py);
      ++counts.primary;
      Vec3 sample = splat(0.0f);
      // Primary rays accept any t > 0 (only secondary and shadow rays skip t <= epsilon).
      const int tri = impl_->trace(eye, dir, 0.0f, 0, splat(1.0f), sample, counts);
      if (tri >= 0) ++counts.primary_hits;
      if (2 * i + 1 == k && 2 * j + 1 == k) centre_tri = tri;  // odd k: this sample is the centre ray
      for (int c = 0; c < 3; ++c) sum[c] += double(sample[c]);
    }
  }
  if (object_facet) {
    if (k % 2 == 0) {  // even k: the centre ray is not a sample; find its hit alone
      Hit hit;
      const Vec3 dir = primary_direction(impl_->frame, scene.width, scene.height, x, y);
      centre_tri = impl_->nearest(eye, dir, 0.0f, hit) ? hit.tri : -1;
    }
    object_facet[0] = centre_tri >= 0 ? impl_->tris[centre_tri].object_id : -1;
    object_facet[1] = centre_tri >= 0 ? impl_->tris[centre_tri].facet_id : -1;
  }
  // Saturated as the fixed-point sums of the other renderers are.
  for (int c = 0; c < 3; ++c) sum[c] = saturate_sum(sum[c]);
  Vec3 mean;
  for (int c = 0; c < 3; ++c) mean[c] = static_cast<float>(sum[c] / static_cast<double>(scene.spp));
  return mean;
}

namespace {

// A ray of the sample, waiting to be traced.
struct SampleRay {
  Vec3 origin, direction;
  float t_min;
};

// What the holder of a ray's hit adds for it: a shadow segment (slot: the
// light's index; t: the light's distance), or a reflected (slot: lights)
// or transmitted (lights + 1) ray of the next level (t: its t_min).
struct SampleSpawn {
  std::uint32_t ray, slot;
  Vec3 origin, direction;
  float t;
};
static_assert(std::is_trivially_copyable<SampleSpawn>::value, "sent as bytes");

constexpr std::uint64_t kNoHit = ~std::uint64_t(0);
// Rays of a level traced, joined and spawned at once (sample_rays).
constexpr std::size_t kSampleChunk = std::size_t(1) << 14;

float float_of(std::uint64_t bits) {
  const std::uint32_t b = static_cast<std::uint32_t>(bits);
  float t;
  std::memcpy(&t, &b, sizeof t);
  return t;
}

}  // namespace

RaySample ReferenceTracer::sample_rays(int target_primary, const SampleJoin* join) const {
  if (impl_->queries) throw std::logic_error("sample_rays: the sample is traced through the tracer's own BVH");
  const Scene& scene = scene_;
  const Impl& im = *impl_;
  RaySample out;
  const double pixels = double(scene.width) * double(scene.height);
  out.stride = std::max(1, static_cast<int>(std::sqrt(pixels / std::max(1, target_primary))));
  std::vector<SampleRay> level;
  for (int y = out.stride / 2; y < scene.height; y += out.stride)
    for (int x = out.stride / 2; x < scene.width && level.size() < kMaxSampleRays; x += out.stride)
      level.push_back({scene.camera.eye, primary_direction(im.frame, scene.width, scene.height, x, y), 0.0f});
  const std::uint32_t lights = static_cast<std::uint32_t>(scene.lights.size());
  const std::uint64_t me = join ? std::uint64_t(join->holder()) : 0;
  std::vector<SampleRay> next;
  for (int depth = 0; !level.empty(); ++depth) {
    // Each ray adds a segment: rays beyond the room left are not traced.
    level.resize(std::min(level.size(), kMaxSampleRays - out.rays.size()));
    const bool children = depth + 1 < scene.max_depth;
    next.clear();
    // A chunk of the level at a time, so what a holder spawns (a shadow
    // segment per light, up to 64, and two rays per hit) stays bounded.
    for (std::size_t c0 = 0; c0 < level.size() && out.rays.size() < kMaxSampleRays; c0 += kSampleChunk) {
      const SampleRay* rays = level.data() + c0;
      const std::size_t n = std::min(level.size() - c0, kSampleChunk);
      std::vector<Hit> hits(n);
      for (std::size_t i = 0; i < n; ++i) im.own_nearest(rays[i].origin, rays[i].direction, rays[i].t_min, hits[i]);
      // The least hit over every holder, in the hit order: the least cell
      // of t, then the least (facet, fan) key in it, then (should two
      // holders share a facet) the lowest holder.
      std::vector<std::uint64_t> t_bits(n, kNoHit), key(n, kNoHit), holder(n, kNoHit);
      for (std::size_t i = 0; i < n; ++i)
        if (hits[i].tri >= 0) t_bits[i] = hit_grid(hits[i].t);
      if (join) join->min(t_bits);
      const auto least_t = [&](std::size_t i) { return hits[i].tri >= 0 && hit_grid(hits[i].t) == t_bits[i]; };
      for (std::size_t i = 0; i < n; ++i)
        if (least_t(i)) key[i] = im.sample_key(hits[i].tri);
      if (join) join->min(key);
      for (std::size_t i = 0; i < n; ++i)
        if (least_t(i) && im.sample_key(hits[i].tri) == key[i]) holder[i] = me;
      if (join) join->min(holder);

      // The segments and rays the hits this holder won spawn, then everyone's.
      std::vector<SampleSpawn> spawned;
      for (std::size_t i = 0; i < n; ++i) {
        if (holder[i] != me || hits[i].tri < 0) continue;
        const SampleRay& r = rays[i];
        const Impl::Surface s = im.surface(r.origin, r.direction, hits[i]);
        const std::uint32_t ray = static_cast<std::uint32_t>(i);
        for (std::uint32_t l = 0; l < lights; ++l) {
          SampleSpawn shadow{ray, l, s.p, {}, 0.0f};
          float n_dot_l;
          if (Impl::shadow_ray(s.p, s.n, scene.lights[l], shadow.direction, shadow.t, n_dot_l))
            spawned.push_back(shadow);
        }
        if (!children) continue;
        if (any_nonzero(s.m->kr()))
          spawned.push_back({ray, lights, s.p, Impl::reflected(r.direction, s.n), im.epsilon});
        SampleSpawn through{ray, lights + 1, s.p, {}, im.epsilon};
        if (any_nonzero(s.m->kt()) && Impl::transmitted(r.direction, s.n, s.entering, s.m->ni, through.direction))
          spawned.push_back(through);
      }
      if (join) {
        std::vector<unsigned char> mine(spawned.size() * sizeof(SampleSpawn));
        if (!mine.empty()) std::memcpy(mine.data(), spawned.data(), mine.size());
        const std::vector<unsigned char> all = join->all_gather(mine);
        spawned.resize(all.size() / sizeof(SampleSpawn));
        if (!spawned.empty()) std::memcpy(spawned.data(), all.data(), spawned.size() * sizeof(SampleSpawn));
        std::stable_sort(spawned.begin(), spawned.end(), [](const SampleSpawn& a, const SampleSpawn& b) {
          return a.ray < b.ray || (a.ray == b.ray && a.slot < b.slot);
        });
      }

      // The chunk's segments in its rays' order, each ray's shadow segments
      // after it; the next level's rays in the same order.
      std::size_t k = 0;
      for (std::size_t i = 0; i < n && out.rays.size() < kMaxSampleRays; ++i) {
        // The hit's cell (its start): the segment ends there, within 2^-19.
        const float t = t_bits[i] == kNoHit ? std::numeric_limits<float>::infinity() : float_of(t_bits[i]);
        out.rays.push_back({rays[i].origin, rays[i].direction, t});
        for (; k < spawned.size() && spawned[k].ray == i; ++k) {
          const SampleSpawn& sp = spawned[k];
          if (sp.slot >= lights)
            next.push_back({sp.origin, sp.direction, sp.t});
          else if (out.rays.size() < kMaxSampleRays)
            out.rays.push_back({sp.origin, sp.direction, sp.t});
        }
      }
    }
    level.swap(next);
  }
  return out;
}

void ReferenceTracer::render_rows(int y0, int y1, ImageResult& out, RayCounts& counts) const {
  const int w = scene_.width;
  y0 = std::max(y0, 0);
  y1 = std::min(y1, scene_.height);
  for (int y = y0; y < y1; ++y) {
    for (int x = 0; x < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      const Vec3 c = render_pixel(x, y, &out.item_buffer[2 * i], counts);
      out.rgb[3 * i + 0] = c[0];
      out.rgb[3 * i + 1] = c[1];
      out.rgb[3 * i + 2] = c[2];
    }
  }
}

void ReferenceTracer::render_image(ImageResult& image, int threads, Progress* progress) const {
  const Scene& scene = scene_;
  threads = std::max(1, std::min(threads, scene.height));
  if (threads == 1 && !progress) {
    render_rows(0, scene.height, image, image.rays);
    return;
  }
  // Interleaved bands of rows balance cheap and expensive parts of the image.
  constexpr int kBand = 4;
  std::vector<RayCounts> counts(threads);
  std::atomic<int> rows_done{0};
  std::atomic<std::uint64_t> rays_done{0};
  if (progress) progress->start();
  std::vector<std::thread> workers;
  for (int w = 0; w < threads; ++w) {
    workers.emplace_back([&, w] {
      for (int y = w * kBand; y < scene.height; y += threads * kBand) {
        const std::uint64_t before = counts[w].total();
        render_rows(y, y + kBand, image, counts[w]);
        rays_done += counts[w].total() - before;
        rows_done += std::min(kBand, scene.height - y);
      }
    });
  }
  // The calling thread only watches: rows finished out of all rows.
  while (progress && rows_done.load() < scene.height) {
    if (progress->due()) progress->report(double(rows_done.load()) / scene.height, rays_done.load());
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  for (std::thread& t : workers) t.join();
  for (const RayCounts& c : counts) image.rays += c;
  if (progress && progress->due()) progress->report(1.0, image.rays.total());
}

ImageResult render_reference(const Scene& scene, int threads, Progress* progress) {
  ImageResult image = blank_image(scene.width, scene.height);
  const ReferenceTracer tracer(scene);
  tracer.render_image(image, threads, progress);
  return image;
}

void render_reference_rows(const Scene& scene, int y0, int y1, ImageResult& out) {
  const ReferenceTracer tracer(scene);
  tracer.render_rows(y0, y1, out, out.rays);
}

}  // namespace opsila
