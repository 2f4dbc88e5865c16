/* The bank BVH's walks: nearest hit (radiance rays, the item buffer, the
 * megakernel) and any hit (shadow rays), both on the traversal skeleton of
 * lib/walk.cl. The nearest-hit walk pushes the children it meets farthest
 * first, so the nearest is popped next, and skips a popped entry that lies
 * beyond the best hit found since it was pushed. The any-hit walk needs no
 * order and tests a leaf as soon as its box is met. */
#include "walk.cl"

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

/* Children met in [tmin, tmax], with slack: relative, OPSILA_CULL_SLACK (a
 * box is never culled while a facet on its face could still win), and
 * absolute, `slack` (FrameParams.box_slack). The facet test
 * computes t from vertices taken relative to the origin, so its rounding is
 * of the order of the coordinates' ulp, not of t's: near the origin (a
 * glass block standing on a floor, a ray leaving one face towards the
 * other) a facet's t can fall below its own box's slab entry, or above the
 * box's exit below tmin, by more than any relative slack. Culling such a box
 * would change which facet wins with the bank's shape, hence with the PE
 * count. Returns the mask; *enter gets the clamped entry distances. */
OPSILA_INLINE intW node_hits(const RayPre *r, __global const WalkNode *nd, float tmin, float tmax, float slack,
                             floatW *enter) {
  floatW lo, hi;
  walk_node_spans(r, nd, tmin, tmax, &lo, &hi);
  hi = hi + fabs(hi) * OPSILA_CULL_SLACK + slack; /* cull_exit, lane-wise */
  *enter = lo;
  /* An empty slot's inverted box gives lo = +inf and hi = -inf, then NaN
   * from the slack (-inf + inf): never met, so the count is not read. */
  return lo <= hi;
}

/* A walk of one bank's BVH: the ray, its segment, and (nearest hit) the
 * best hit so far; the tests are counted as they are made. */
typedef struct {
  const RayPre *r; /* in the frame of what is walked: the world's, or an instance's model's */
  __global const BankTriangle *tris;
  __global const WalkNode *nodes;
  __global const Instance *insts; /* the instance table (OPSILA_INSTANCES) */
  int inst;                       /* the instance being walked, -1: the scene's own facets */
  float tmin, tmax, slack; /* nearest hit: tmax is the best hit's limit, set at each pop */
  HitKey best;
  int best_tri;
  uint *tri_tests, *box_tests;
  const CostProbe *probe;
  /* Nearest hit: the best hit's limit (hit_limit) and the entry beyond
   * which a popped child is skipped, made when the best changes, not at
   * every pop. */
  float limit, cull;
} BankWalk;

OPSILA_INLINE void nearest_bounds(BankWalk *w) {
  w->limit = hit_limit(w->best.t);
  w->cull = cull_exit(w->limit, w->slack);
}

/* Every child box in use is a test, met or not. The slots in use are told
 * by their boxes (an empty slot's is inverted), not by the counts: a vector
 * load of the counts here would make the compiler take the walk's count[k]
 * from it, through a store to the stack and a load of one lane, for every
 * child met, a load that waits for the store (docs/BENCHMARKS.md, Levers). */
OPSILA_INLINE uint bank_node(BankWalk *w, __global const WalkNode *nd, float *te) {
  floatW enter;
  intW hit = node_hits(w->r, nd, w->tmin, w->tmax, w->slack, &enter);
  vstoreW(enter, 0, te);
  if (OPSILA_COUNT_WORK) *w->box_tests += popcount(WALK_NODE_SLOTS(nd));
#ifdef OPSILA_MEASURE_COST
  for (int k = 0; k < OPSILA_BVH_WIDTH; ++k)
    if (nd->count[k] >= 0) COST_CHILD(w->probe, nd, k);
#endif
  return lane_mask(hit);
}

OPSILA_INLINE bool bank_child(BankWalk *w, __global const WalkNode *nd, int k, int cnt, float entry) { return true; }

/* A popped entry beyond the limit of the best hit found since it was
 * pushed cannot hold a winner; the limit bounds the node's test too. */
OPSILA_INLINE bool nearest_pop(BankWalk *w, float entry) {
  w->tmax = w->limit;
  return !(entry > w->cull);
}

/* Facet i, met at t (< w->limit when tested), against the best hit: the
 * ids are read only when the distances share a cell (hit_before). A limit
 * lowered by a facet tested alongside only prunes: the order decides. */
OPSILA_INLINE void nearest_candidate(BankWalk *w, int i, float t) {
  __global const BankTriangle *tri = &w->tris[i];
  if (hit_cell_before(t, w->best) ||
      (hit_cell_same(t, w->best) && hit_ids_before(w->inst, tri->facet_id, OPSILA_TRI_FAN(*tri), w->best))) {
    w->best = hit_key(t, w->inst, tri->facet_id, OPSILA_TRI_FAN(*tri));
    w->best_tri = i;
    nearest_bounds(w);
  }
}

/* A leaf's facets, each met at t < tmax handed to ON_HIT(w, i, t).
 * OPSILA_FACET_LANES (the host sets it where a work-item's vectors are the
 * device's own: host/device/cl_runtime.cpp): in vector lanes, four at a
 * time while three or more are left (a group of three repeats its last
 * facet in lane 3, whose answer is not used), then two, then one; each lane
 * gives the single test's bits (geometry.cl). Otherwise one at a time.
 * Leaves hold up to kFacetsPerLeaf facets (host/partition/bank_bvh.cpp),
 * more only at the builder's depth bound. */
#ifndef OPSILA_FACET_LANES
#define OPSILA_FACET_LANES 0
#endif
/* Facet i alone; n facets from `base` whose results are lanes[0 .. n-1]. */
#define FACET_ONE(w, i, tmax, ON_HIT)                                          \
  {                                                                            \
    COUNT_TEST((w)->tri_tests);                                                \
    COST_TRI((w)->probe, (i));                                                 \
    float t1_ = intersect_triangle((w)->r, &(w)->tris[i], (w)->tmin, (tmax));  \
    if (t1_ < OPSILA_INF) ON_HIT(w, (i), t1_);                                 \
  }
#define FACET_LANES(w, base, lanes, n, ON_HIT)                                 \
  for (int k_ = 0; k_ < (n); ++k_) {                                           \
    COUNT_TEST((w)->tri_tests);                                                \
    COST_TRI((w)->probe, (base) + k_);                                         \
    if (lanes[k_] < OPSILA_INF) ON_HIT(w, (base) + k_, lanes[k_]);             \
  }
#if !OPSILA_FACET_LANES
#define LEAF_FACETS(w, first, count, tmax, ON_HIT) \
  for (int i_ = (first); i_ < (first) + (count); ++i_) FACET_ONE(w, i_, tmax, ON_HIT)
#else
#define LEAF_FACETS(w, first, count, tmax, ON_HIT)                                                            \
  {                                                                                                          \
    __global const BankTriangle *tr_ = (w)->tris;                                                            \
    int i_ = (first), end_ = (first) + (count);                                                              \
    for (; end_ - i_ > 2; i_ += 4) {                                                                         \
      int n_ = min(end_ - i_, 4);                                                                            \
      float4 t4_ = intersect_triangle4((w)->r, &tr_[i_], &tr_[i_ + 1], &tr_[i_ + 2], &tr_[i_ + n_ - 1],      \
                                       (w)->tmin, (tmax));                                                   \
      float lane4_[4] = {t4_.x, t4_.y, t4_.z, t4_.w};                                                        \
      FACET_LANES(w, i_, lane4_, n_, ON_HIT)                                                                 \
    }                                                                                                        \
    if (end_ - i_ == 2) {                                                                                    \
      float2 t2_ = intersect_triangle2((w)->r, &tr_[i_], &tr_[i_ + 1], (w)->tmin, (tmax));                   \
      float lane2_[2] = {t2_.x, t2_.y};                                                                      \
      FACET_LANES(w, i_, lane2_, 2, ON_HIT)                                                                  \
    } else if (end_ - i_ == 1)                                                                               \
      FACET_ONE(w, i_, tmax, ON_HIT)                                                                         \
  }
#endif

/* A leaf's facets for the nearest hit, in the frame of w->r. */
OPSILA_INLINE void nearest_facets(BankWalk *w, int first, int count) {
  LEAF_FACETS(w, first, count, w->limit, nearest_candidate)
}

/* A leaf's facets for any hit in the segment: true at the first group
 * with a hit. */
#define ANY_HIT_FOUND(w, i, t) return true
OPSILA_INLINE bool any_facets(BankWalk *w, int first, int count) {
  LEAF_FACETS(w, first, count, w->tmax, ANY_HIT_FOUND)
  return false;
}
#undef ANY_HIT_FOUND

#if OPSILA_INSTANCES
OPSILA_INLINE bool model_nearest_leaf(BankWalk *w, int first, int count, float entry) {
  nearest_facets(w, first, count);
  return false;
}
OPSILA_INLINE bool model_any_leaf(BankWalk *w, int first, int count, float entry) {
  return any_facets(w, first, count);
}
/* The walks of a model's BVH, in its frame (instances are not nested). */
OPSILA_DEFINE_WALK(walk_model_nearest, BankWalk, WalkNode, bank_node, bank_child, model_nearest_leaf, nearest_pop, 1)
OPSILA_DEFINE_WALK(walk_model_any, BankWalk, WalkNode, bank_node, bank_child, model_any_leaf, WALK_NO_POP, 0)

/* Instance i met by the walk: its model's BVH with the ray in its frame. */
OPSILA_INLINE bool instance_walk(BankWalk *w, int i, bool any) {
  __global const Instance *in = &w->insts[i];
  RayPre ro = instance_ray(w->r, in);
  /* A placement extreme enough to overflow the ray in the model's frame
   * meets nothing: a NaN ray would meet every box, empty slots too, and
   * the walk would never end. An infinite inv_dir is not such a ray: a
   * direction component of zero (an axis-aligned ray) gives it, and the
   * slab test handles it as in the world's frame. */
  if (!all(isfinite(ro.org)) || !all(isfinite(ro.dir)) || isnan(ro.sx) || isnan(ro.sy) || isnan(ro.sz))
    return false;
  const RayPre *world = w->r;
  w->r = &ro;
  w->inst = i;
  bool blocked = any ? walk_model_any(w, w->nodes, in->root) : (walk_model_nearest(w, w->nodes, in->root), false);
  w->r = world;
  w->inst = -1;
  w->tmax = any ? w->tmax : w->limit;
  return blocked;
}
#define INSTANCE_LEAF(w, first, count, any) \
  if ((count) == OPSILA_INSTANCE_LEAF) return instance_walk(w, first, any)
#else
#define INSTANCE_LEAF(w, first, count, any)
#endif

OPSILA_INLINE bool nearest_leaf(BankWalk *w, int first, int count, float entry) {
  INSTANCE_LEAF(w, first, count, false);
  nearest_facets(w, first, count);
  return false;
}

OPSILA_INLINE bool any_leaf(BankWalk *w, int first, int count, float entry) {
  INSTANCE_LEAF(w, first, count, true);
  return any_facets(w, first, count);
}

OPSILA_DEFINE_WALK(walk_nearest, BankWalk, WalkNode, bank_node, bank_child, nearest_leaf, nearest_pop, 1)
OPSILA_DEFINE_WALK(walk_any, BankWalk, WalkNode, bank_node, bank_child, any_leaf, WALK_NO_POP, 0)

/* Nearest hit below `root` (a bank, one cluster of it, or a whole scene),
 * after the best one so far (*best and *best_tri, updated: the least in
 * hit_order.h's order, whoever found the others); slack:
 * FrameParams.box_slack (node_hits). */
OPSILA_INLINE void traverse_nearest(const RayPre *r, __global const WalkNode *nodes,
                                    __global const BankTriangle *tris, __global const Instance *insts, int root,
                                    float tmin, float slack, HitKey *best, int *best_tri, uint *tri_tests,
                                    uint *box_tests, const CostProbe *probe) {
  BankWalk w = {r,        tris,      nodes,     insts, -1,    tmin, OPSILA_INF, slack, *best,
                *best_tri, tri_tests, box_tests, probe, 0.0f, 0.0f};
  nearest_bounds(&w);
  walk_nearest(&w, nodes, root);
  *best = w.best;
  *best_tri = w.best_tri;
}

/* Nearest hit from a cluster's root (Cluster.root): a node, or for an
 * instance's cluster -2 - the instance (its model's BVH in its frame). */
OPSILA_INLINE void cluster_nearest(const RayPre *r, __global const WalkNode *nodes, __global const BankTriangle *tris,
                                   __global const Instance *insts, int root, float tmin, float slack, HitKey *best,
                                   int *best_tri, uint *tri_tests, uint *box_tests, const CostProbe *probe) {
#if OPSILA_INSTANCES
  if (root < -1) {
    BankWalk w = {r,        tris,      nodes,     insts, -1,   tmin, OPSILA_INF, slack, *best,
                  *best_tri, tri_tests, box_tests, probe, 0.0f, 0.0f};
    nearest_bounds(&w);
    instance_walk(&w, -2 - root, false);
    *best = w.best;
    *best_tri = w.best_tri;
    return;
  }
#endif
  traverse_nearest(r, nodes, tris, insts, root, tmin, slack, best, best_tri, tri_tests, box_tests, probe);
}

/* Any hit in (tmin, tmax): shadow rays. */
OPSILA_INLINE bool traverse_any(const RayPre *r, __global const WalkNode *nodes, __global const BankTriangle *tris,
                                __global const Instance *insts, int root, float tmin, float tmax, float slack,
                                uint *tri_tests, uint *box_tests, const CostProbe *probe) {
  BankWalk w = {r, tris, nodes, insts, -1, tmin, tmax, slack, hit_none(), -1, tri_tests, box_tests, probe, 0.0f, 0.0f};
  return walk_any(&w, nodes, root);
}

/* Miss-cheap root: one test of the union of the root's child boxes (lo, hi,
 * from the host) before the root. Every child box lies inside it and the
 * rounded slab distances are monotonic in the planes (no contraction,
 * geometry.cl), so with node_hits' clamps and slack a ray that misses it
 * misses every child; the root's tests are then counted as the walk counts
 * them (one per slot in use), so the work counters do not see the shortcut.
 * tmax: the root's bound. Returns whether the root must be walked. */
OPSILA_INLINE bool root_box_met(const RayPre *r, __global const WalkNode *nodes, int root, float3 lo, float3 hi,
                                float tmin, float tmax, float slack, uint *box_tests, const CostProbe *probe) {
  float3 near = (float3)(r->neg.x ? hi.x : lo.x, r->neg.y ? hi.y : lo.y, r->neg.z ? hi.z : lo.z);
  float3 far = (float3)(r->neg.x ? lo.x : hi.x, r->neg.y ? lo.y : hi.y, r->neg.z ? lo.z : hi.z);
  float3 tn = (near - r->org) * r->inv_dir, tf = (far - r->org) * r->inv_dir;
  float enter = fmax(fmax(fmax(tn.x, tn.y), tn.z), tmin);
  float leave = fmin(fmin(fmin(tf.x, tf.y), tf.z), tmax);
  leave = cull_exit(leave, slack);
  if (enter <= leave) return true;
  __global const WalkNode *nd = &nodes[root];
  for (int k = 0; k < OPSILA_BVH_WIDTH; ++k) {
    if (nd->count[k] < 0) continue;
    COUNT_TEST(box_tests);
    COST_CHILD(probe, nd, k);
  }
  return false;
}

/* The walks of the baselines (megakernel, traversal alone) from the whole
 * scene's root, behind root_box_met: a camera ray that misses the scene pays
 * one box test. Not used where it does not pay (docs/BENCHMARKS.md, "Levers"):
 * the SPMD phase's rays reach a bank because they meet one of its cluster
 * boxes, and the item buffer tests a cluster only inside its projected
 * rectangle. */
OPSILA_INLINE void scene_nearest(const RayPre *r, __global const WalkNode *nodes, __global const BankTriangle *tris,
                                 __global const Instance *insts, int root, float3 lo, float3 hi, float tmin, float slack, HitKey *best, int *best_tri,
                                 uint *tri_tests, uint *box_tests, const CostProbe *probe) {
  if (root_box_met(r, nodes, root, lo, hi, tmin, hit_limit(best->t), slack, box_tests, probe))
    traverse_nearest(r, nodes, tris, insts, root, tmin, slack, best, best_tri, tri_tests, box_tests, probe);
}

OPSILA_INLINE bool scene_any(const RayPre *r, __global const WalkNode *nodes, __global const BankTriangle *tris,
                             __global const Instance *insts, int root, float3 lo, float3 hi, float tmin, float tmax, float slack, uint *tri_tests,
                             uint *box_tests, const CostProbe *probe) {
  return root_box_met(r, nodes, root, lo, hi, tmin, tmax, slack, box_tests, probe) &&
         traverse_any(r, nodes, tris, insts, root, tmin, tmax, slack, tri_tests, box_tests, probe);
}
