/* Routing: which PE a descriptor goes to next (destination choice). */
#include "geometry.cl"

/* Destination choice (ordered forwarding). A ray visits the PEs whose
 * bounding spheres it meets in increasing order of (entry distance, PE id),
 * strictly after the cursor (cursor_t, cursor_pe), and only while the entry
 * is below t_max (its best hit so far, or the light distance). A facet hit
 * at distance t lies inside its cluster's sphere, so a PE whose spheres are
 * all entered at or beyond t_max cannot hold a nearer hit: when no PE is
 * left, the nearest hit over all banks is known. Returns -1 then. */
inline int next_destination(const RayPre *r, __global const PeInfo *pes, __global const Cluster *clusters, int num_pes,
                            float tmin, float tmax, float cursor_t, int cursor_pe, float *entry_out,
                            uint *sphere_tests) {
  int best_pe = -1;
  float best_entry = OPSILA_INF;
  for (int q = 0; q < num_pes; ++q) {
    __global const PeInfo *pe = &pes[q];
    if (pe->cluster_begin == pe->cluster_end) continue;
    if (q == cursor_pe) continue; /* (entry, q) == cursor: visited */
    float te, tl;
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

/* Shadow rays need no order (any occluder ends them): they visit the PEs
 * whose spheres meet the segment (tmin, tmax) in PE order. Returns the first
 * such PE after `after_pe`, or -1. */
inline int next_shadow_destination(const RayPre *r, __global const PeInfo *pes, __global const Cluster *clusters,
                                   int num_pes, float tmin, float tmax, int after_pe, uint *sphere_tests) {
  for (int q = after_pe + 1; q < num_pes; ++q) {
    __global const PeInfo *pe = &pes[q];
    if (pe->cluster_begin == pe->cluster_end) continue;
    float te;
    if (!ray_box(r, load3g(pe->bmin), load3g(pe->bmax), tmin, tmax, &te)) continue;
    for (int c = pe->cluster_begin; c < pe->cluster_end; ++c) {
      ++*sphere_tests;
      if (sphere_entry(r, &clusters[c], tmin, tmax) < OPSILA_INF) return q;
    }
  }
  return -1;
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
