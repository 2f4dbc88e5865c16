/* Bank BVH traversal: nearest hit (radiance rays) and any hit (shadow rays).
 * The node layout is BankNode in opsila_shared.h. */
#include "geometry.cl"

/* Nearest hit in one BVH subtree (a bank, or one cluster of it). */
inline void traverse_nearest(const RayPre *r, __global const BankNode *nodes, __global const BankTriangle *tris,
                             int root, float tmin, float *best_t, int *best_tri, int *best_facet,
                             uint *tri_tests, uint *box_tests) {
  int stack[OPSILA_BVH_STACK];
  int sp = 0;
  stack[sp++] = root;
  while (sp > 0) {
    __global const BankNode *nd = &nodes[stack[--sp]];
    float te;
    ++*box_tests;
    if (!ray_box(r, load3g(nd->bmin), load3g(nd->bmax), tmin, tie_limit(*best_t), &te)) continue;
    if (nd->count > 0) {
      for (int i = nd->first; i < nd->first + nd->count; ++i) {
        ++*tri_tests;
        float t = intersect_triangle(r, &tris[i], tmin, OPSILA_INF);
        if (t < OPSILA_INF && closer(t, tris[i].facet_id, *best_t, *best_facet)) {
          *best_t = t;
          *best_tri = i;
          *best_facet = tris[i].facet_id;
        }
      }
    } else if (sp + 2 <= OPSILA_BVH_STACK) {
      stack[sp++] = nd->first + 1;
      stack[sp++] = nd->first;
    }
  }
}

/* Any hit in (tmin, tmax): shadow rays. */
inline bool traverse_any(const RayPre *r, __global const BankNode *nodes, __global const BankTriangle *tris, int root,
                         float tmin, float tmax, uint *tri_tests, uint *box_tests) {
  int stack[OPSILA_BVH_STACK];
  int sp = 0;
  stack[sp++] = root;
  while (sp > 0) {
    __global const BankNode *nd = &nodes[stack[--sp]];
    float te;
    ++*box_tests;
    if (!ray_box(r, load3g(nd->bmin), load3g(nd->bmax), tmin, tmax, &te)) continue;
    if (nd->count > 0) {
      for (int i = nd->first; i < nd->first + nd->count; ++i) {
        ++*tri_tests;
        if (intersect_triangle(r, &tris[i], tmin, tmax) < OPSILA_INF) return true;
      }
    } else if (sp + 2 <= OPSILA_BVH_STACK) {
      stack[sp++] = nd->first + 1;
      stack[sp++] = nd->first;
    }
  }
  return false;
}
