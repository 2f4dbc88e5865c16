/* Device code shared by every phase: ray-facet and ray-volume tests, bank
 * BVH traversal, destination choice, fixed-point pixel accumulation. */
#include "opsila_shared.h"

/* Every PE must compute bit-identical sphere entry distances for the same ray
 * (they order the visit of candidate PEs), so no silent fma contraction. */
#pragma OPENCL FP_CONTRACT OFF

#define OPSILA_INF INFINITY

/* Descriptor structure-of-arrays: one buffer per field (the paper's vectors).
 *   org:  xyz origin, w = t_best (radiance) or t_max (shadow)
 *   dir:  xyz unit direction, w = entry distance of the PE named by cursor
 *   wgt:  xyz weight product (radiance) or light contribution (shadow)
 *   ids:  x = pixel, y = meta (kind | level << 2), z = best hit (global
 *         triangle, -1 none), w = cursor PE (last PE visited in entry order)
 *   dest: destination PE, -1 = NIL hole */
#define DESC_PARAMS(p) \
  __global float4 *p##_org, __global float4 *p##_dir, __global float4 *p##_wgt, __global int4 *p##_ids, \
      __global int *p##_dest

inline float3 load3(const float a[3]) { return (float3)(a[0], a[1], a[2]); }
inline float3 load3g(__global const float *a) { return (float3)(a[0], a[1], a[2]); }

/* Per-ray constants of the watertight test (Woop, Benthin, Wald 2013). */
typedef struct {
  float3 org;
  float3 dir;
  float3 inv_dir;
  int kx, ky, kz;
  float sx, sy, sz;
} RayPre;

inline float comp(float3 v, int k) { return k == 0 ? v.x : (k == 1 ? v.y : v.z); }

inline RayPre make_ray(float3 org, float3 dir) {
  RayPre r;
  r.org = org;
  r.dir = dir;
  r.inv_dir = (float3)(1.0f / dir.x, 1.0f / dir.y, 1.0f / dir.z);
  float3 a = fabs(dir);
  r.kz = (a.x > a.y) ? (a.x > a.z ? 0 : 2) : (a.y > a.z ? 1 : 2);
  r.kx = r.kz + 1 == 3 ? 0 : r.kz + 1;
  r.ky = r.kx + 1 == 3 ? 0 : r.kx + 1;
  if (comp(dir, r.kz) < 0.0f) {
    int t = r.kx;
    r.kx = r.ky;
    r.ky = t;
  }
  float dz = comp(dir, r.kz);
  r.sx = comp(dir, r.kx) / dz;
  r.sy = comp(dir, r.ky) / dz;
  r.sz = 1.0f / dz;
  return r;
}

/* Watertight ray-triangle test: an edge shared by two facets is hit by
 * exactly one side or both, never by neither (no cracks). Returns the hit
 * distance if it lies in (tmin, tmax), else INFINITY. */
inline float intersect_triangle(const RayPre *r, __global const BankTriangle *tri, float tmin, float tmax) {
  float3 a = load3g(tri->v0) - r->org;
  float3 b = load3g(tri->v1) - r->org;
  float3 c = load3g(tri->v2) - r->org;
  float az = comp(a, r->kz), bz = comp(b, r->kz), cz = comp(c, r->kz);
  float ax = comp(a, r->kx) - r->sx * az, ay = comp(a, r->ky) - r->sy * az;
  float bx = comp(b, r->kx) - r->sx * bz, by = comp(b, r->ky) - r->sy * bz;
  float cx = comp(c, r->kx) - r->sx * cz, cy = comp(c, r->ky) - r->sy * cz;
  float u = cx * by - cy * bx;
  float v = ax * cy - ay * cx;
  float w = bx * ay - by * ax;
  if ((u < 0.0f || v < 0.0f || w < 0.0f) && (u > 0.0f || v > 0.0f || w > 0.0f)) return OPSILA_INF;
  float det = u + v + w;
  if (det == 0.0f) return OPSILA_INF;
  /* Barycentrics first: u*az is of the order of the scene size cubed and
   * overflows float beyond ~1e12 units; u/det is at most 1. */
  float inv_det = 1.0f / det;
  float t = (u * inv_det) * (r->sz * az) + (v * inv_det) * (r->sz * bz) + (w * inv_det) * (r->sz * cz);
  return (t > tmin && t < tmax) ? t : OPSILA_INF;
}

/* Slab test, closed boxes (a ray along a face is inside). */
inline bool ray_box_span(const RayPre *r, float3 bmin, float3 bmax, float tmin, float tmax, float *t_enter,
                         float *t_leave);
inline bool ray_box(const RayPre *r, float3 bmin, float3 bmax, float tmin, float tmax, float *t_enter) {
  float leave;
  return ray_box_span(r, bmin, bmax, tmin, tmax, t_enter, &leave);
}
inline bool ray_box_span(const RayPre *r, float3 bmin, float3 bmax, float tmin, float tmax, float *t_enter,
                         float *t_leave) {
  float3 t0 = (bmin - r->org) * r->inv_dir;
  float3 t1 = (bmax - r->org) * r->inv_dir;
  /* 0 * inf = NaN where the ray runs in a slab's boundary plane (a zero
   * direction component, the origin on the plane): the ray is inside that
   * slab, so a NaN counts as -inf for the entry and +inf for the exit. */
  const float3 ninf = (float3)(-INFINITY), pinf = (float3)(INFINITY);
  float3 lo = fmin(select(t0, ninf, isnan(t0)), select(t1, ninf, isnan(t1)));
  float3 hi = fmax(select(t0, pinf, isnan(t0)), select(t1, pinf, isnan(t1)));
  float enter = fmax(fmax(lo.x, lo.y), fmax(lo.z, tmin));
  float leave = fmin(fmin(hi.x, hi.y), fmin(hi.z, tmax));
  /* Relative slack above the tie tolerance: a box is never culled by rounding
   * when a facet on its face could still win a tie. */
  leave = leave + fabs(leave) * (4.0f * OPSILA_TIE_TOLERANCE) + 1e-30f;
  *t_enter = enter;
  *t_leave = leave;
  return enter <= leave;
}

/* Entry distance of a ray into a sphere, clamped at 0; INFINITY when the
 * sphere does not meet (tmin, tmax). */
inline float sphere_entry(const RayPre *r, __global const Cluster *cl, float tmin, float tmax) {
  float3 oc = r->org - load3g(cl->center);
  float b = dot(oc, r->dir);
  float c = dot(oc, oc) - cl->radius * cl->radius;
  float disc = b * b - c;
  if (disc < 0.0f) return OPSILA_INF;
  float s = sqrt(disc);
  float t_near = -b - s, t_far = -b + s;
  if (t_far <= tmin || t_near >= tmax) return OPSILA_INF;
  return fmax(t_near, 0.0f);
}

/* Hit ordering: nearer first; distances equal within OPSILA_TIE_TOLERANCE go
 * to the lower facet id, so the answer does not depend on which PE or BVH
 * leaf saw a facet first, nor on rounding between coplanar facets. */
inline bool closer(float t, int facet, float best_t, int best_facet) {
  if (best_t == OPSILA_INF) return t < OPSILA_INF;
  float tol = OPSILA_TIE_TOLERANCE * best_t;
  if (t < best_t - tol) return true;
  return t <= best_t + tol && facet < best_facet;
}

/* Farthest distance at which a hit could still win against best_t. */
inline float tie_limit(float best_t) { return best_t + best_t * (2.0f * OPSILA_TIE_TOLERANCE); }

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

/* 64-bit fixed-point add from two 32-bit atomics: the carry out of the low
 * word goes to the high word. Integer sums are order-independent, so the
 * image is identical however the work-items are scheduled. */
inline void add_fixed(volatile __global uint *cell, long value) {
  uint lo = (uint)value;
  uint hi = (uint)(value >> 32);
  uint old = atomic_add(&cell[0], lo);
  if (old + lo < old) hi += 1u;
  if (hi != 0u) atomic_add(&cell[1], hi);
}

inline void accumulate(volatile __global uint *accum, int pixel, float3 value) {
  long3 q = convert_long3_sat_rte(value * OPSILA_FIXED_SCALE);
  if (q.x != 0) add_fixed(&accum[pixel * 6 + 0], q.x);
  if (q.y != 0) add_fixed(&accum[pixel * 6 + 2], q.y);
  if (q.z != 0) add_fixed(&accum[pixel * 6 + 4], q.z);
}

inline void count_stat(volatile __global uint *stats, int num_pes, int level, int pe, int which, uint amount) {
  if (amount != 0u) add_fixed(&stats[((level * num_pes + pe) * OPSILA_STAT_COUNT + which) * 2], (long)amount);
}

/* Whitted shading pieces (SPEC "Shading"), shared by the SPMD phase and the
 * replicated megakernel so that both shade from one definition. */
typedef struct {
  float3 p;      /* hit point */
  float3 n;      /* shading normal: the geometric normal facing the ray */
  bool entering; /* dot(Ng, D) < 0 */
} SurfacePoint;

inline SurfacePoint surface_point(__global const BankTriangle *tri, float3 org, float3 d, float t) {
  float3 v0 = load3g(tri->v0), v1 = load3g(tri->v1), v2 = load3g(tri->v2);
  float3 ng = normalize(cross(v1 - v0, v2 - v0));
  SurfacePoint sp;
  sp.p = org + t * d;
  sp.entering = dot(ng, d) < 0.0f;
  sp.n = sp.entering ? ng : -ng;
  return sp;
}

/* weight * Il * (Kd max(0, n.Lv) + Ks max(0, Rl.(-D))^Ns), zero when
 * n.Lv <= 0; also the unit direction and distance to the light. */
inline float3 light_term(__global const Material *m, __global const Light *light, SurfacePoint sp, float3 d,
                         float3 weight, float3 *lv, float *dist) {
  float3 to_light = load3g(light->position) - sp.p;
  *dist = length(to_light);
  *lv = to_light / *dist;
  float ndl = dot(sp.n, *lv);
  if (!(ndl > 0.0f)) return (float3)(0.0f);
  float3 rl = 2.0f * ndl * sp.n - *lv;
  float spec = fmax(0.0f, dot(rl, -d));
  float3 term = load3g(m->kd) * ndl + load3g(m->ks) * pow(spec, m->ns);
  return weight * load3g(light->intensity) * term;
}

inline float3 reflected_direction(SurfacePoint sp, float3 d) { return normalize(d - 2.0f * dot(d, sp.n) * sp.n); }

/* Refracted direction; false on total internal reflection. */
inline bool transmitted_direction(__global const Material *m, SurfacePoint sp, float3 d, float3 *out) {
  float eta = sp.entering ? 1.0f / m->ni : m->ni;
  float c = -dot(sp.n, d);
  float k = 1.0f - eta * eta * (1.0f - c * c);
  if (k < 0.0f) return false;
  *out = normalize(eta * d + (eta * c - sqrt(k)) * sp.n);
  return true;
}

/* SPEC camera: primary ray direction of pixel (x, y). */
inline float3 primary_direction(FrameParams fp, int x, int y) {
  float sx = (2.0f * ((float)x + 0.5f) / (float)fp.width - 1.0f) * fp.tan_half_fov * fp.aspect;
  float sy = (1.0f - 2.0f * ((float)y + 0.5f) / (float)fp.height) * fp.tan_half_fov;
  return normalize(load3(fp.forward) + sx * load3(fp.right) + sy * load3(fp.up));
}
