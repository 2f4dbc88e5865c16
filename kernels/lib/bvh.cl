/* Wide-BVH traversal: nearest hit (radiance rays, the item buffer, the
 * megakernel) and any hit (shadow rays).
 *
 * Node layout (BankNode, kernels/opsila_shared.h; built by
 * host/machine/bank_bvh.cpp): OPSILA_BVH_WIDTH children per node, their
 * boxes stored per plane (lo_x[W], hi_x[W], lo_y[W], ... ), then child[W]
 * and count[W]:
 *   count == 0: inner node, child = node index;
 *   count >  0: leaf, facets child .. child + count - 1;
 *   count <  0: empty slot.
 * A root has no box of its own: a walk starts by testing its children.
 *
 * PoCL does not vectorise these loops across work-items (divergent control
 * flow), so the width is used inside one work-item: the W child boxes of a
 * node are tested together, one floatW per plane. The nearest-hit walk pushes
 * the children it meets farthest first, so the nearest is popped next, and
 * skips a popped entry that lies beyond the best hit found since it was
 * pushed. The any-hit walk needs no order and tests a leaf as soon as its
 * box is met. The host builder bounds every path so that the private stack
 * of OPSILA_BVH_STACK entries is enough. */
#include "geometry.cl"

#if OPSILA_BVH_WIDTH == 8
typedef float8 floatW;
typedef int8 intW;
#define vloadW vload8
#define vstoreW vstore8
#else
typedef float4 floatW;
typedef int4 intW;
#define vloadW vload4
#define vstoreW vstore4
#endif

/* Pilot frames (--balance measured) build the program with
 * OPSILA_MEASURE_COST: every ray-box and ray-facet test of the SPMD phase is
 * also counted for the cluster it belongs to, at the ray's level, so that
 * the partition can share the measured work among the PEs. A child box's
 * test belongs to the child's cluster, also in a bank's own top nodes above
 * the cluster roots (a ray pays them on every visit to the PE, and a cluster
 * that many rays reach makes them paid often). Other builds carry an empty
 * probe and count nothing. */
typedef struct {
#ifdef OPSILA_MEASURE_COST
  __global const int *node_cluster; /* bank node -> its cluster, -1 above the cluster roots */
  __global const int *tri_cluster;  /* bank facet -> its cluster */
  volatile __global uint *cost;     /* cost[cluster] at the ray's level; 0: not counted */
#else
  int none;
#endif
} CostProbe;
#ifdef OPSILA_MEASURE_COST
#define COST_CHILD(pr, nd, k)                                                                                \
  if ((pr)->cost) {                                                                                          \
    int cc_ = (nd)->count[k] == 0 ? (pr)->node_cluster[(nd)->child[k]] : (pr)->tri_cluster[(nd)->child[k]]; \
    if (cc_ >= 0) atomic_inc(&(pr)->cost[cc_]);                                                              \
  }
#define COST_TRI(pr, tri) \
  if ((pr)->cost) atomic_inc(&(pr)->cost[(pr)->tri_cluster[tri]])
#else
#define COST_CHILD(pr, nd, k)
#define COST_TRI(pr, tri)
#endif

/* The probe of rays whose tests are not counted (item buffer, megakernel). */
inline CostProbe no_cost_probe(void) {
  CostProbe p;
#ifdef OPSILA_MEASURE_COST
  p.node_cluster = 0;
  p.tri_cluster = 0;
  p.cost = 0;
#else
  p.none = 0;
#endif
  return p;
}

/* Raw slab distances of a node's child boxes: the largest plane entry and
 * the smallest plane exit, per child. Planes are taken near/far by the sign
 * of the direction, so one subtraction and one product per plane; a NaN (a
 * ray in a slab's boundary plane) is ignored by fmax/fmin, i.e. that slab
 * counts as containing the ray, as in ray_box_span. */
OPSILA_INLINE void node_spans(const RayPre *r, __global const BankNode *nd, floatW *enter, floatW *leave) {
  __global const float *nx = r->neg.x ? nd->hi_x : nd->lo_x, *fx = r->neg.x ? nd->lo_x : nd->hi_x;
  __global const float *ny = r->neg.y ? nd->hi_y : nd->lo_y, *fy = r->neg.y ? nd->lo_y : nd->hi_y;
  __global const float *nz = r->neg.z ? nd->hi_z : nd->lo_z, *fz = r->neg.z ? nd->lo_z : nd->hi_z;
  floatW ox = (floatW)(r->org.x), oy = (floatW)(r->org.y), oz = (floatW)(r->org.z);
  floatW ix = (floatW)(r->inv_dir.x), iy = (floatW)(r->inv_dir.y), iz = (floatW)(r->inv_dir.z);
  floatW tnx = (vloadW(0, nx) - ox) * ix, tny = (vloadW(0, ny) - oy) * iy, tnz = (vloadW(0, nz) - oz) * iz;
  floatW tfx = (vloadW(0, fx) - ox) * ix, tfy = (vloadW(0, fy) - oy) * iy, tfz = (vloadW(0, fz) - oz) * iz;
  *enter = fmax(fmax(tnx, tny), tnz);
  *leave = fmin(fmin(tfx, tfy), tfz);
}

/* Children met in [tmin, tmax], with slack: relative, above the tie
 * tolerance (a box is never culled while a facet on its face could still
 * win a tie), and absolute, `slack` (FrameParams.box_slack). The facet test
 * computes t from vertices taken relative to the origin, so its rounding is
 * of the order of the coordinates' ulp, not of t's: near the origin (a
 * glass block standing on a floor, a ray leaving one face towards the
 * other) a facet's t can fall below its own box's slab entry, or above the
 * box's exit below tmin, by more than any relative slack. Culling such a box
 * would change which facet wins with the bank's shape, hence with the PE
 * count. Returns the mask; *enter gets the clamped entry distances. */
OPSILA_INLINE intW node_hits(const RayPre *r, __global const BankNode *nd, float tmin, float tmax, float slack,
                             floatW *enter) {
  floatW lo, hi;
  node_spans(r, nd, &lo, &hi);
  lo = fmax(lo, (floatW)(tmin));
  hi = fmin(hi, (floatW)(tmax));
  hi = hi + fabs(hi) * (4.0f * OPSILA_TIE_TOLERANCE) + slack;
  *enter = lo;
  return (lo <= hi) & (vloadW(0, nd->count) >= (intW)(0));
}

/* Nearest hit below `root` (a bank, one cluster of it, or a whole scene);
 * slack: FrameParams.box_slack (node_hits). */
OPSILA_INLINE void traverse_nearest(const RayPre *r, __global const BankNode *nodes,
                                    __global const BankTriangle *tris, int root, float tmin, float slack, float *best_t,
                                    int *best_tri, int *best_facet, uint *tri_tests, uint *box_tests,
                                    const CostProbe *probe) {
  int s_child[OPSILA_BVH_STACK], s_count[OPSILA_BVH_STACK];
  float s_t[OPSILA_BVH_STACK];
  int sp = 1;
  s_child[0] = root;
  s_count[0] = 0;
  s_t[0] = -INFINITY;
  while (sp > 0) {
    --sp;
    float limit = tie_limit(*best_t);
    if (s_t[sp] > limit + fabs(limit) * (4.0f * OPSILA_TIE_TOLERANCE) + slack) continue;
    int child = s_child[sp], count = s_count[sp];
    if (count > 0) {
      for (int i = child; i < child + count; ++i) {
        ++*tri_tests;
        COST_TRI(probe, i);
        float t = intersect_triangle(r, &tris[i], tmin, OPSILA_INF);
        if (t < OPSILA_INF && closer(t, tris[i].facet_id, *best_t, *best_facet)) {
          *best_t = t;
          *best_tri = i;
          *best_facet = tris[i].facet_id;
        }
      }
      continue;
    }
    __global const BankNode *nd = &nodes[child];
    floatW enter;
    intW hit = node_hits(r, nd, tmin, limit, slack, &enter);
    float te[OPSILA_BVH_WIDTH];
    int hm[OPSILA_BVH_WIDTH];
    vstoreW(enter, 0, te);
    vstoreW(hit, 0, hm);
    int base = sp;
    for (int k = 0; k < OPSILA_BVH_WIDTH; ++k) {
      int cnt = nd->count[k];
      if (cnt < 0) continue;
      ++*box_tests;
      COST_CHILD(probe, nd, k);
      if (!hm[k] || sp >= OPSILA_BVH_STACK) continue;
      /* Insert, keeping this node's entries farthest first. */
      float t = te[k];
      int j = sp++;
      while (j > base && s_t[j - 1] < t) {
        s_t[j] = s_t[j - 1];
        s_child[j] = s_child[j - 1];
        s_count[j] = s_count[j - 1];
        --j;
      }
      s_t[j] = t;
      s_child[j] = nd->child[k];
      s_count[j] = cnt;
    }
  }
}

/* Any hit in (tmin, tmax): shadow rays. */
OPSILA_INLINE bool traverse_any(const RayPre *r, __global const BankNode *nodes, __global const BankTriangle *tris,
                                int root, float tmin, float tmax, float slack, uint *tri_tests, uint *box_tests,
                                const CostProbe *probe) {
  int stack[OPSILA_BVH_STACK];
  int sp = 1;
  stack[0] = root;
  while (sp > 0) {
    __global const BankNode *nd = &nodes[stack[--sp]];
    floatW enter;
    intW hit = node_hits(r, nd, tmin, tmax, slack, &enter);
    int hm[OPSILA_BVH_WIDTH];
    vstoreW(hit, 0, hm);
    for (int k = 0; k < OPSILA_BVH_WIDTH; ++k) {
      int cnt = nd->count[k];
      if (cnt < 0) continue;
      ++*box_tests;
      COST_CHILD(probe, nd, k);
      if (!hm[k]) continue;
      int child = nd->child[k];
      if (cnt == 0) {
        if (sp < OPSILA_BVH_STACK) stack[sp++] = child;
        continue;
      }
      for (int i = child; i < child + cnt; ++i) {
        ++*tri_tests;
        COST_TRI(probe, i);
        if (intersect_triangle(r, &tris[i], tmin, tmax) < OPSILA_INF) return true;
      }
    }
  }
  return false;
}
