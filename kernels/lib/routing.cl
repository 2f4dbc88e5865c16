/* Routing: which PE a descriptor goes to next (destination choice).
 *
 * Every PE knows, for every cluster, a bounding volume: its sphere (the
 * paper's scheme, OPSILA_ROUTING_SPHERES: a linear scan of each PE's
 * spheres, behind the box around them) or its box (OPSILA_ROUTING_BOXES: the
 * cluster boxes of each PE under a small wide BVH, BankNode with one cluster
 * per leaf, built by host/partition/bank_bvh.cpp; PE q's root is route[q],
 * and route[P + i] holds the boxes of PEs i*W .. i*W + W-1, the top level
 * the walks start from).
 * The boxes are padded on the host so that rounding never puts a facet's
 * hit point outside its cluster's box. Both volumes give the same
 * destinations rule below, hence the same image. */
#include "walk.cl"

typedef struct {
  __global const PeInfo *pes;
  __global const Cluster *clusters;
  __global const BankNode *route; /* routing BVH roots first, one per PE */
  int num_pes;
  int mode; /* OPSILA_ROUTING_* */
} Routing;

/* Destination choice (ordered forwarding). A ray visits the PEs whose
 * bounding spheres it meets in increasing order of (entry distance, PE id),
 * strictly after the cursor (cursor_t, cursor_pe), and only while the entry
 * is below t_max (its best hit so far, or the light distance). A facet hit
 * at distance t lies inside its cluster's sphere, so a PE whose spheres are
 * all entered at or beyond t_max cannot hold a nearer hit: when no PE is
 * left, the nearest hit over all banks is known. Returns -1 then. */
inline int next_destination_spheres(const RayPre *r, __global const PeInfo *pes, __global const Cluster *clusters,
                                    int num_pes, float tmin, float tmax, float cursor_t, int cursor_pe,
                                    float *entry_out, uint *sphere_tests, uint *route_tests) {
  int best_pe = -1;
  float best_entry = OPSILA_INF;
  for (int q = 0; q < num_pes; ++q) {
    __global const PeInfo *pe = &pes[q];
    if (pe->cluster_begin == pe->cluster_end) continue;
    if (q == cursor_pe) continue; /* (entry, q) == cursor: visited */
    float te, tl;
    COUNT_TEST(route_tests);
    if (!ray_box_span(r, load3g(pe->bmin), load3g(pe->bmax), tmin, tmax, &te, &tl)) continue;
    /* The box holds every sphere of the PE, so its entry bounds theirs from
     * below and its exit from above: a PE that cannot beat the current
     * candidate, or that the ray left before the cursor, is not opened. */
    if (te > tmin && te > best_entry) continue;
    if (tl < cursor_t) continue;
    float entry = OPSILA_INF;
    for (int c = pe->cluster_begin; c < pe->cluster_end; ++c) {
      COUNT_TEST(sphere_tests);
      entry = fmin(entry, sphere_entry(r, &clusters[c], tmin, tmax));
    }
    if (!(entry < tmax)) continue;
    bool after_cursor = entry > cursor_t || (entry == cursor_t && q > cursor_pe);
    if (after_cursor && (entry < best_entry || (entry == best_entry && q < best_pe))) {
      best_entry = entry;
      best_pe = q;
    }
  }
  *entry_out = best_entry;
  return best_pe;
}

/* Shadow rays need no order (any occluder ends them): the PE that spawns
 * one tests its own bank first (its `home`), then the ray visits the other
 * PEs whose spheres meet the segment (tmin, tmax) in PE order. Returns the
 * first such PE after `after_pe`, never `home`, or -1. */
inline int next_shadow_destination_spheres(const RayPre *r, __global const PeInfo *pes,
                                           __global const Cluster *clusters, int num_pes, float tmin, float tmax,
                                           int after_pe, int home, uint *sphere_tests, uint *route_tests) {
  for (int q = after_pe + 1; q < num_pes; ++q) {
    __global const PeInfo *pe = &pes[q];
    if (pe->cluster_begin == pe->cluster_end || q == home) continue;
    float te;
    COUNT_TEST(route_tests);
    if (!ray_box(r, load3g(pe->bmin), load3g(pe->bmax), tmin, tmax, &te)) continue;
    for (int c = pe->cluster_begin; c < pe->cluster_end; ++c) {
      COUNT_TEST(sphere_tests);
      if (sphere_entry(r, &clusters[c], tmin, tmax) < OPSILA_INF) return q;
    }
  }
  return -1;
}

/* Cluster boxes of a routing node met by the ray: the line meets the box,
 * and the box meets (tmin, tmax). *entry gets the entry clamped at 0, as
 * sphere_entry clamps it. Node boxes contain their clusters' boxes, and the
 * rounded slab distances are monotonic in the planes, so a node's entry is
 * never above its clusters' and its exit never below. */
OPSILA_INLINE intW route_hits(const RayPre *r, __global const BankNode *nd, float tmin, float tmax, floatW *entry) {
  floatW lo, hi;
  /* Unclamped: from -inf and +inf. A NaN slab is ignored as fmax ignores it;
   * all three NaN would need a zero direction. lo is never NaN, so the
   * clamp at 0 needs no NaN test either. */
  node_spans(r, nd, -INFINITY, INFINITY, &lo, &hi);
  *entry = MAX_A_OR_B(lo, (floatW)(0.0f));
  /* An empty slot's inverted box (empty_node) gives lo = +inf, hi = -inf. */
  return (lo <= hi) & (hi > (floatW)(tmin)) & (lo < (floatW)(tmax));
}

/* A walk of one PE's routing BVH (or of the top level): the ray and its
 * segment, one routing test counted per node; the nearest-entry walk also
 * carries the cursor, the candidate to beat and the PE's entry so far. */
typedef struct {
  const RayPre *r;
  float tmin, tmax;
  uint *route_tests;
  float cursor_t, best_entry, entry;
  int cursor_pe, q;
  float bound; /* an entry at or beyond it cannot change the answer */
} RouteWalk;

/* route_hits: the entries into te, the mask of the children met. */
OPSILA_INLINE uint route_node(RouteWalk *w, __global const BankNode *nd, float *te) {
  COUNT_TEST(w->route_tests);
  floatW ent;
  intW met = route_hits(w->r, nd, w->tmin, w->tmax, &ent);
  vstoreW(ent, 0, te);
  return lane_mask(met);
}

/* Nearest entry: only a box entered below both the bound (the candidate's
 * entry, or the runner-up's when both are kept) and this PE's entry so far
 * can change the answer. Node boxes contain their children's, so a subtree
 * entered at or beyond the bound holds no box entered below it. */
OPSILA_INLINE bool entry_child(RouteWalk *w, __global const BankNode *nd, int k, int cnt, float entry) {
  return entry < fmin(w->bound, w->entry);
}

/* A cluster box entered at or before the cursor: the PE was already visited
 * (ends the walk); otherwise the PE's entry so far. */
OPSILA_INLINE bool entry_leaf(RouteWalk *w, int first, int count, float entry) {
  if (entry < w->cursor_t || (entry == w->cursor_t && w->q < w->cursor_pe)) return true;
  w->entry = entry;
  return false;
}

OPSILA_INLINE bool segment_child(RouteWalk *w, __global const BankNode *nd, int k, int cnt, float entry) {
  return true;
}

/* Any cluster box met by the segment: the shadow ray goes to this PE. */
OPSILA_INLINE bool segment_leaf(RouteWalk *w, int first, int count, float entry) { return true; }

OPSILA_DEFINE_WALK(walk_route_entry, RouteWalk, BankNode, route_node, entry_child, entry_leaf, WALK_NO_POP, 0)
OPSILA_DEFINE_WALK(walk_route_segment, RouteWalk, BankNode, route_node, segment_child, segment_leaf, WALK_NO_POP, 0)

/* next_destination_spheres with cluster boxes: the entry of PE q is the
 * smallest entry over its boxes that meet (tmin, tmax). Only an entry below
 * the current candidate's can change the answer, so subtrees entered at or
 * beyond it are skipped; a box entered at or before the cursor means the PE
 * was already visited, which ends its walk. */
inline int next_destination_boxes(const RayPre *r, __global const BankNode *route, int num_pes, float tmin,
                                  float tmax, float cursor_t, int cursor_pe, float *entry_out, uint *route_tests) {
  int best_pe = -1;
  RouteWalk w = {r, tmin, tmax, route_tests, cursor_t, OPSILA_INF, OPSILA_INF, cursor_pe, -1, OPSILA_INF};
  /* PEs in increasing order, as the ties want, W at a time through the top
   * level: a PE whose box is missed, or entered at or beyond the current
   * candidate, has no cluster box that could change the answer. */
  int top_nodes = (num_pes + OPSILA_BVH_WIDTH - 1) / OPSILA_BVH_WIDTH;
  for (int n = 0; n < top_nodes; ++n) {
    __global const BankNode *tn = &route[num_pes + n];
    float pe_entry[OPSILA_BVH_WIDTH];
    for (uint met = route_node(&w, tn, pe_entry); met != 0u; met &= met - 1u) {
      int kq = lowest_bit(met); /* PEs in increasing order */
      if (!(pe_entry[kq] < w.best_entry)) continue;
      int q = tn->child[kq];
      if (q == cursor_pe) continue; /* (entry, q) == cursor: visited */
      w.q = q;
      w.entry = OPSILA_INF;
      w.bound = w.best_entry;
      bool visited = walk_route_entry(&w, route, q);
      float entry = w.entry;
      if (visited || !(entry < tmax)) continue;
      bool after_cursor = entry > cursor_t || (entry == cursor_t && q > cursor_pe);
      if (after_cursor && entry < w.best_entry) {
        w.best_entry = entry;
        best_pe = q;
      }
    }
  }
  *entry_out = w.best_entry;
  return best_pe;
}

/* next_shadow_destination_spheres with cluster boxes, through the top
 * level: PEs whose box the segment misses are not walked. */
inline int next_shadow_destination_boxes(const RayPre *r, __global const BankNode *route, int num_pes, float tmin,
                                         float tmax, int after_pe, int home, uint *route_tests) {
  RouteWalk w = {r, tmin, tmax, route_tests, -1.0f, OPSILA_INF, OPSILA_INF, -1, -1, OPSILA_INF};
  int first = after_pe + 1;
  int top_nodes = (num_pes + OPSILA_BVH_WIDTH - 1) / OPSILA_BVH_WIDTH;
  for (int n = first / OPSILA_BVH_WIDTH; n < top_nodes; ++n) {
    __global const BankNode *tn = &route[num_pes + n];
    float pe_entry[OPSILA_BVH_WIDTH];
    for (uint met = route_node(&w, tn, pe_entry); met != 0u; met &= met - 1u) {
      int q = n * OPSILA_BVH_WIDTH + lowest_bit(met);
      if (q < first || q == home) continue;
      if (walk_route_segment(&w, route, q)) return q;
    }
  }
  return -1;
}

/* The choice after the first, when the first is known in advance (pe -1:
 * none; known false: not computed, the visit chooses as usual). */
typedef struct {
  bool known;
  int pe;
  float entry;
} NextPe;

/* next_destination_boxes for a new ray (no cursor, tmax = inf) that keeps
 * the runner-up too: the least (entry, PE) after the first, in *after. A
 * visit to the first PE would choose exactly it, or none when it is entered
 * at or beyond that visit's limit. Its choice, from the cursor (first's
 * entry, first), is the least (entry, PE) after the cursor entered below the
 * limit T: a PE's entry is the least over its boxes that meet the segment,
 * and the box that gives the least entry here (below T) meets (tmin, T) as
 * well, while a PE with every box entered at or beyond T has none meeting it.
 * Entries come from the same unclamped slab spans, whatever tmax, so they
 * are the same floats; a PE is visited exactly when its entry is at or
 * before the cursor. So the ray's first visit needs no second walk. */
inline int first_two_destinations_boxes(const RayPre *r, __global const BankNode *route, int num_pes, float tmin,
                                        float *entry_out, NextPe *after, uint *route_tests) {
  int best_pe = -1, next_pe = -1;
  float next_entry = OPSILA_INF;
  RouteWalk w = {r, tmin, OPSILA_INF, route_tests, -1.0f, OPSILA_INF, OPSILA_INF, -1, -1, OPSILA_INF};
  int top_nodes = (num_pes + OPSILA_BVH_WIDTH - 1) / OPSILA_BVH_WIDTH;
  for (int n = 0; n < top_nodes; ++n) {
    __global const BankNode *tn = &route[num_pes + n];
    float pe_entry[OPSILA_BVH_WIDTH];
    for (uint met = route_node(&w, tn, pe_entry); met != 0u; met &= met - 1u) {
      int kq = lowest_bit(met); /* PEs in increasing order: of equal entries, the lower PE first */
      if (!(pe_entry[kq] < next_entry)) continue;
      int q = tn->child[kq];
      w.q = q;
      w.entry = OPSILA_INF;
      w.bound = next_entry;
      walk_route_entry(&w, route, q); /* no cursor: nothing is visited */
      float entry = w.entry;
      if (entry < w.best_entry) {
        next_pe = best_pe, next_entry = w.best_entry;
        best_pe = q, w.best_entry = entry;
      } else if (entry < next_entry) {
        next_pe = q, next_entry = entry;
      }
    }
  }
  after->known = true;
  after->pe = next_pe;
  after->entry = next_entry;
  *entry_out = w.best_entry;
  return best_pe;
}

/* The first destination of a new ray (next_destination from no cursor, tmax
 * inf); with cluster boxes, the one after it too. Not with spheres: there a
 * PE is skipped when its box, not its spheres, is entered beyond a bound,
 * and the box's rounded entry may exceed a tangent sphere's, so a choice
 * made with another bound (the runner-up's, another limit) could differ
 * from the visit's in such a case. */
inline int first_destination(const Routing *rt, const RayPre *r, float tmin, float *entry_out, NextPe *after,
                             uint *sphere_tests, uint *route_tests) {
  if (rt->mode == OPSILA_ROUTING_BOXES)
    return first_two_destinations_boxes(r, rt->route, rt->num_pes, tmin, entry_out, after, route_tests);
  after->known = false;
  return next_destination_spheres(r, rt->pes, rt->clusters, rt->num_pes, tmin, OPSILA_INF, -1.0f, -1, entry_out,
                                  sphere_tests, route_tests);
}

inline int next_destination(const Routing *rt, const RayPre *r, float tmin, float tmax, float cursor_t,
                            int cursor_pe, float *entry_out, uint *sphere_tests, uint *route_tests) {
  if (rt->mode == OPSILA_ROUTING_BOXES)
    return next_destination_boxes(r, rt->route, rt->num_pes, tmin, tmax, cursor_t, cursor_pe, entry_out,
                                  route_tests);
  return next_destination_spheres(r, rt->pes, rt->clusters, rt->num_pes, tmin, tmax, cursor_t, cursor_pe, entry_out,
                                  sphere_tests, route_tests);
}

inline int next_shadow_destination(const Routing *rt, const RayPre *r, float tmin, float tmax, int after_pe,
                                   int home, uint *sphere_tests, uint *route_tests) {
  if (rt->mode == OPSILA_ROUTING_BOXES)
    return next_shadow_destination_boxes(r, rt->route, rt->num_pes, tmin, tmax, after_pe, home, route_tests);
  return next_shadow_destination_spheres(r, rt->pes, rt->clusters, rt->num_pes, tmin, tmax, after_pe, home,
                                         sphere_tests, route_tests);
}

/* Owner PE of a global triangle index (banks are contiguous). */
inline int owner_pe(__global const PeInfo *pes, int num_pes, int tri) {
  int lo = 0, hi = num_pes - 1;
  while (lo < hi) {
    int mid = (lo + hi + 1) >> 1;
    if (pes[mid].tri_begin <= tri) lo = mid; else hi = mid - 1;
  }
  /* Skip empty banks that share the same tri_begin. */
  while (lo > 0 && pes[lo].tri_begin == pes[lo].tri_end && pes[lo - 1].tri_begin <= tri) --lo;
  while (lo < num_pes - 1 && tri >= pes[lo].tri_end) ++lo;
  return lo;
}
