/* Routing: which PE a descriptor goes to next (destination choice).
 *
 * Every PE knows, for every cluster, a bounding volume: its sphere (the
 * paper's scheme, OPSILA_ROUTING_SPHERES: a linear scan of each PE's
 * spheres, behind the box around them) or its box (OPSILA_ROUTING_BOXES: the
 * cluster boxes of each PE under a small wide BVH, BankNode with one cluster
 * per leaf, built by host/machine/bank_bvh.cpp; PE q's root is route[q],
 * and route[P + i] holds the boxes of PEs i*W .. i*W + W-1, the top level
 * the walks start from).
 * The boxes are padded on the host so that rounding never puts a facet's
 * hit point outside its cluster's box. Both volumes give the same
 * destinations rule below, hence the same image. */
#include "bvh.cl"

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
    ++*route_tests;
    if (!ray_box_span(r, load3g(pe->bmin), load3g(pe->bmax), tmin, tmax, &te, &tl)) continue;
    /* The box holds every sphere of the PE, so its entry bounds theirs from
     * below and its exit from above: a PE that cannot beat the current
     * candidate, or that the ray left before the cursor, is not opened. */
    if (te > tmin && te > best_entry) continue;
    if (tl < cursor_t) continue;
    float entry = OPSILA_INF;
    for (int c = pe->cluster_begin; c < pe->cluster_end; ++c) {
      ++*sphere_tests;
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
    ++*route_tests;
    if (!ray_box(r, load3g(pe->bmin), load3g(pe->bmax), tmin, tmax, &te)) continue;
    for (int c = pe->cluster_begin; c < pe->cluster_end; ++c) {
      ++*sphere_tests;
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
  node_spans(r, nd, &lo, &hi);
  *entry = fmax(lo, (floatW)(0.0f));
  return (lo <= hi) & (hi > (floatW)(tmin)) & (lo < (floatW)(tmax)) & (vloadW(0, nd->count) >= (intW)(0));
}

/* next_destination_spheres with cluster boxes: the entry of PE q is the
 * smallest entry over its boxes that meet (tmin, tmax). Only an entry below
 * the current candidate's can change the answer, so subtrees entered at or
 * beyond it are skipped; a box entered at or before the cursor means the PE
 * was already visited, which ends its walk. */
/* route_hits into per-child arrays: entries and whether each child is met. */
OPSILA_INLINE void route_node(const RayPre *r, __global const BankNode *nd, float tmin, float tmax, float *te,
                              int *hm) {
  floatW ent;
  intW met = route_hits(r, nd, tmin, tmax, &ent);
  vstoreW(ent, 0, te);
  vstoreW(met, 0, hm);
}

inline int next_destination_boxes(const RayPre *r, __global const BankNode *route, int num_pes, float tmin,
                                  float tmax, float cursor_t, int cursor_pe, float *entry_out, uint *route_tests) {
  int best_pe = -1;
  float best_entry = OPSILA_INF;
  /* PEs in increasing order, as the ties want, W at a time through the top
   * level: a PE whose box is missed, or entered at or beyond the current
   * candidate, has no cluster box that could change the answer. */
  int top_nodes = (num_pes + OPSILA_BVH_WIDTH - 1) / OPSILA_BVH_WIDTH;
  for (int n = 0; n < top_nodes; ++n) {
    __global const BankNode *tn = &route[num_pes + n];
    ++*route_tests;
    float pe_entry[OPSILA_BVH_WIDTH];
    int pe_met[OPSILA_BVH_WIDTH];
    route_node(r, tn, tmin, tmax, pe_entry, pe_met);
    for (int kq = 0; kq < OPSILA_BVH_WIDTH; ++kq) {
      if (!pe_met[kq] || !(pe_entry[kq] < best_entry)) continue;
      int q = tn->child[kq];
      if (q == cursor_pe) continue; /* (entry, q) == cursor: visited */
      float entry = OPSILA_INF;
      bool visited = false;
      int stack[OPSILA_BVH_STACK];
      int sp = 1;
      stack[0] = q;
      while (sp > 0 && !visited) {
        __global const BankNode *nd = &route[stack[--sp]];
        ++*route_tests;
        float te[OPSILA_BVH_WIDTH];
        int hm[OPSILA_BVH_WIDTH];
        route_node(r, nd, tmin, tmax, te, hm);
        for (int k = 0; k < OPSILA_BVH_WIDTH; ++k) {
          if (!hm[k]) continue;
          float e = te[k];
          if (!(e < fmin(best_entry, entry))) continue;
          if (nd->count[k] == 0) {
            if (sp < OPSILA_BVH_STACK) stack[sp++] = nd->child[k];
            continue;
          }
          if (e < cursor_t || (e == cursor_t && q < cursor_pe)) {
            visited = true;
            break;
          }
          entry = e;
        }
      }
      if (visited || !(entry < tmax)) continue;
      bool after_cursor = entry > cursor_t || (entry == cursor_t && q > cursor_pe);
      if (after_cursor && entry < best_entry) {
        best_entry = entry;
        best_pe = q;
      }
    }
  }
  *entry_out = best_entry;
  return best_pe;
}

/* next_shadow_destination_spheres with cluster boxes, through the top
 * level: PEs whose box the segment misses are not walked. */
inline int next_shadow_destination_boxes(const RayPre *r, __global const BankNode *route, int num_pes, float tmin,
                                         float tmax, int after_pe, int home, uint *route_tests) {
  int first = after_pe + 1;
  int top_nodes = (num_pes + OPSILA_BVH_WIDTH - 1) / OPSILA_BVH_WIDTH;
  for (int n = first / OPSILA_BVH_WIDTH; n < top_nodes; ++n) {
    __global const BankNode *tn = &route[num_pes + n];
    ++*route_tests;
    float pe_entry[OPSILA_BVH_WIDTH];
    int pe_met[OPSILA_BVH_WIDTH];
    route_node(r, tn, tmin, tmax, pe_entry, pe_met);
    for (int kq = 0; kq < OPSILA_BVH_WIDTH; ++kq) {
      int q = n * OPSILA_BVH_WIDTH + kq;
      if (q < first || q == home || !pe_met[kq]) continue;
      int stack[OPSILA_BVH_STACK];
      int sp = 1;
      stack[0] = q;
      while (sp > 0) {
        __global const BankNode *nd = &route[stack[--sp]];
        ++*route_tests;
        float te[OPSILA_BVH_WIDTH];
        int hm[OPSILA_BVH_WIDTH];
        route_node(r, nd, tmin, tmax, te, hm);
        for (int k = 0; k < OPSILA_BVH_WIDTH; ++k) {
          if (!hm[k]) continue;
          if (nd->count[k] > 0) return q;
          if (sp < OPSILA_BVH_STACK) stack[sp++] = nd->child[k];
        }
      }
    }
  }
  return -1;
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
