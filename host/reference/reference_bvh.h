// The reference tracer's geometry (docs/CONTRACT.md "Geometry and ids"):
// its triangle, the ray-triangle test, and a plain BVH that only decides
// which triangles a ray tests (the nearest hit is the hit order's,
// kernels/hit_order.h, whatever the visit order).
#pragma once

#include <vector>

#include "scene/scene.h"
#include "core/vec.h"

namespace opsila::reference {

// A triangle as the tracer needs it: the vertices' edges for the
// intersection test, Ng from the vertices (CONTRACT "Geometry and ids"), and the ids.
struct Tri {
  Vec3 v0, e1, e2;
  Vec3 normal;   // Ng = normalize(cross(v1 - v0, v2 - v0))
  bool degenerate;  // zero area: no well-defined Ng, never hit
  int material, object_id, facet_id;
  int fan;  // the triangle's index in its facet's fan: the hit order's last key
};

// Möller–Trumbore. Edges and vertices count as inside. Returns the ray
// parameter t (distance along a unit direction), or nothing; b1 and b2 get
// the contract's barycentrics of the hit.
bool intersect(const Tri& tri, const Vec3& origin, const Vec3& dir, float& t_out, float* b1 = nullptr,
               float* b2 = nullptr);

// A plain BVH (median split on the longest centroid axis). It only decides
// which triangles get tested; the hit order does not depend on the order in
// which they are visited.
struct Node {
  Box box;
  int first = 0;  // leaf: first index into `order`; inner: left child
  int count = 0;  // leaf: number of triangles; inner: 0 (right child = left + 1)
};

struct Bvh {
  std::vector<Node> nodes;
  std::vector<int> order;  // triangle indices, grouped by leaf
};

// The tracer's triangles of `source`: materials outside [0, materials)
// become 0 (CONTRACT "a face with no material").
std::vector<Tri> make_tris(const std::vector<Triangle>& source, int materials);

// The BVH over the non-degenerate triangles of `tris` (boxes from
// `source`, padded by `pad`), built on `threads` threads (0: all).
Bvh build_bvh(const std::vector<Tri>& tris, const std::vector<Triangle>& source, float pad, int threads);
// The same over items 0 .. lo_of.size() - 1 with boxes [lo_of[i], hi_of[i]]
// (the instances' world boxes), leaving out those not `kept`.
Bvh build_bvh(const std::vector<Vec3>& lo_of, const std::vector<Vec3>& hi_of, const std::vector<bool>& kept,
              float pad, int threads);

// A box (a node's, an instance's) met within [t_min, t_max]; the exit
// widened by the hit order's culling slack, so that rounding never culls a
// box holding a hit before the best (hit_order.h).
bool hits_box(const Box& box, const Vec3& origin, const Vec3& dir, float t_min, float t_max);

}  // namespace opsila::reference
