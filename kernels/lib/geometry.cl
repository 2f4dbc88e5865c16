/* Ray-facet and ray-volume tests (the order of their hits: ../hit_order.h). */
#include "descriptor.cl"
#include "../hit_order.h"

/* Every PE must compute bit-identical sphere entry distances for the same ray
 * (they order the visit of candidate PEs), so no silent fma contraction. */
#pragma OPENCL FP_CONTRACT OFF

#define OPSILA_INF INFINITY

/* PoCL leaves the hot functions (the facet test, the traversals) out of line
 * when their cost passes its inlining threshold; they are called per ray and
 * per facet, so inlining is forced. */
#define OPSILA_INLINE inline __attribute__((always_inline))


/* The host's vector arithmetic (host/core/vec.h), operation for operation:
 * the built-ins may round otherwise on another OpenCL implementation. */
inline float dot3(float3 a, float3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline float3 cross3(float3 a, float3 b) {
  return (float3)(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
/* Where v.v leaves the float range (a cross product of edges 2^40 long) or
 * its normal range, v is first scaled by a power of two, exactly, so that
 * its largest component lies in [1, 2), as the built-ins do; elsewhere the
 * plain formula. *e gets the power (0 unscaled). */
inline float3 in_range3(float3 a, int *e) {
  float d = dot3(a, a), m = fmax(fmax(fabs(a.x), fabs(a.y)), fabs(a.z));
  *e = 0;
  if ((d < INFINITY && d >= FLT_MIN) || !(m > 0.0f) || isinf(m)) return a;
  *e = ilogb(m);
  return ldexp(a, -*e);
}
inline float len3(float3 a) {
  int e;
  float3 s = in_range3(a, &e);
  return e == 0 ? sqrt(dot3(s, s)) : ldexp(sqrt(dot3(s, s)), e);
}
inline float3 unit3(float3 a) {
  int e;
  float3 s = in_range3(a, &e);
  return s * (1.0f / sqrt(dot3(s, s)));
}

inline float3 load3(const float a[3]) { return (float3)(a[0], a[1], a[2]); }
inline float3 load3g(__global const float *a) { return (float3)(a[0], a[1], a[2]); }

/* Per-ray constants of the watertight test (Woop, Benthin, Wald 2013). */
typedef struct {
  float3 org;
  float3 dir;
  float3 inv_dir;
  int3 neg; /* sign bits of the direction (-0 included): far planes first */
  int kx, ky, kz;
  float sx, sy, sz;
  float3 org_k; /* the origin's kx, ky, kz components: the facet test reads
                   each vertex at these indices, one load each, not a whole
                   vertex and a choice among its components */
} RayPre;

inline float comp(float3 v, int k) { return k == 0 ? v.x : (k == 1 ? v.y : v.z); }

inline RayPre make_ray(float3 org, float3 dir) {
  RayPre r;
  r.org = org;
  r.dir = dir;
  r.inv_dir = (float3)(1.0f / dir.x, 1.0f / dir.y, 1.0f / dir.z);
  r.neg = (int3)(signbit(r.inv_dir.x) != 0, signbit(r.inv_dir.y) != 0, signbit(r.inv_dir.z) != 0);
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
  r.org_k = (float3)(comp(org, r.kx), comp(org, r.ky), comp(org, r.kz));
  return r;
}

#if OPSILA_INSTANCES
/* The ray in an instance's model frame: to_object applied to the origin
 * (a point) and the direction (a vector, not normalised: a distance t is
 * the same point in both frames), each sum taken left to right, the same
 * float operations as the host's (host/scene/instances.h). */
inline RayPre instance_ray(const RayPre *r, __global const Instance *in) {
  __global const float *m = in->to_object;
  float3 o = r->org, d = r->dir;
  float3 oo = (float3)(m[0] * o.x + m[1] * o.y + m[2] * o.z + m[3], m[4] * o.x + m[5] * o.y + m[6] * o.z + m[7],
                       m[8] * o.x + m[9] * o.y + m[10] * o.z + m[11]);
  float3 dd = (float3)(m[0] * d.x + m[1] * d.y + m[2] * d.z, m[4] * d.x + m[5] * d.y + m[6] * d.z,
                       m[8] * d.x + m[9] * d.y + m[10] * d.z);
  return make_ray(oo, dd);
}
#endif

/* The watertight test's edge functions (u, v, w) of the triangle's
 * vertices v0, v1, v2 as seen along the ray, and their depths along kz. */
OPSILA_INLINE float3 edge_functions(const RayPre *r, __global const BankTriangle *tri, float3 *depths) {
  /* The vertices relative to the origin, taken in the ray's kx, ky, kz
   * order: the values of (v - org) picked by comp, with indexed loads. */
  __global const float *p0 = tri->v0, *p1 = tri->v1, *p2 = tri->v2;
  int kx = r->kx, ky = r->ky, kz = r->kz;
  float3 o = r->org_k;
  float az = p0[kz] - o.z, bz = p1[kz] - o.z, cz = p2[kz] - o.z;
  float ax = (p0[kx] - o.x) - r->sx * az, ay = (p0[ky] - o.y) - r->sy * az;
  float bx = (p1[kx] - o.x) - r->sx * bz, by = (p1[ky] - o.y) - r->sy * bz;
  float cx = (p2[kx] - o.x) - r->sx * cz, cy = (p2[ky] - o.y) - r->sy * cz;
  *depths = (float3)(az, bz, cz);
  return (float3)(cx * by - cy * bx, ax * cy - ay * cx, bx * ay - by * ax);
}

/* Watertight ray-triangle test: an edge shared by two facets is hit by
 * exactly one side or both, never by neither (no cracks). Returns the hit
 * distance if it lies in (tmin, tmax), else INFINITY. */
OPSILA_INLINE float intersect_triangle(const RayPre *r, __global const BankTriangle *tri, float tmin, float tmax) {
  float3 z;
  float3 e = edge_functions(r, tri, &z);
  float u = e.x, v = e.y, w = e.z;
  if ((u < 0.0f || v < 0.0f || w < 0.0f) && (u > 0.0f || v > 0.0f || w > 0.0f)) return OPSILA_INF;
  float det = u + v + w;
  if (det == 0.0f) return OPSILA_INF;
  /* Barycentrics first: u*az is of the order of the scene size cubed and
   * overflows float beyond ~1e12 units; u/det is at most 1. */
  float inv_det = 1.0f / det;
  float t = (u * inv_det) * (r->sz * z.x) + (v * inv_det) * (r->sz * z.y) + (w * inv_det) * (r->sz * z.z);
  return (t > tmin && t < tmax) ? t : OPSILA_INF;
}

/* intersect_triangle on two facets (a, b) or four (a .. d) at once, lane k
 * the k-th facet's: the same operations lane by lane, so the same bits as
 * one call per facet (no contraction, and a vector divide is rounded as
 * the scalar one). A leaf's facets cost one test's arithmetic; the loads
 * stay one per value (the vertices are stored facet by facet). */
#define LOAD2(pa, pb, k) ((float2)((pa)[k], (pb)[k]))
#define LOAD4(pa, pb, pc, pd, k) ((float4)((pa)[k], (pb)[k], (pc)[k], (pd)[k]))
#define TRI_TEST_LANES(floatN, intN, LOAD_V0, LOAD_V1, LOAD_V2)                                              \
  int kx = r->kx, ky = r->ky, kz = r->kz;                                                                     \
  floatN ox = (floatN)(r->org_k.x), oy = (floatN)(r->org_k.y), oz = (floatN)(r->org_k.z);                   \
  floatN sx = (floatN)(r->sx), sy = (floatN)(r->sy);                                                          \
  floatN az = LOAD_V0(kz) - oz, bz = LOAD_V1(kz) - oz, cz = LOAD_V2(kz) - oz;                                 \
  floatN ax = (LOAD_V0(kx) - ox) - sx * az, ay = (LOAD_V0(ky) - oy) - sy * az;                                \
  floatN bx = (LOAD_V1(kx) - ox) - sx * bz, by = (LOAD_V1(ky) - oy) - sy * bz;                                \
  floatN cx = (LOAD_V2(kx) - ox) - sx * cz, cy = (LOAD_V2(ky) - oy) - sy * cz;                                \
  floatN u = cx * by - cy * bx, v = ax * cy - ay * cx, w = bx * ay - by * ax;                                 \
  const floatN zero = (floatN)(0.0f);                                                                         \
  intN mixed = ((u < zero) | (v < zero) | (w < zero)) & ((u > zero) | (v > zero) | (w > zero));               \
  floatN det = u + v + w;                                                                                     \
  floatN inv_det = (floatN)(1.0f) / det;                                                                      \
  floatN sz = (floatN)(r->sz);                                                                                \
  floatN t = (u * inv_det) * (sz * az) + (v * inv_det) * (sz * bz) + (w * inv_det) * (sz * cz);               \
  intN in = (t > (floatN)(tmin)) & (t < (floatN)(tmax)) & ~mixed & (det != zero);                             \
  return select((floatN)(OPSILA_INF), t, in)
OPSILA_INLINE float2 intersect_triangle2(const RayPre *r, __global const BankTriangle *a,
                                         __global const BankTriangle *b, float tmin, float tmax) {
#define V0(k) LOAD2(a->v0, b->v0, k)
#define V1(k) LOAD2(a->v1, b->v1, k)
#define V2(k) LOAD2(a->v2, b->v2, k)
  TRI_TEST_LANES(float2, int2, V0, V1, V2);
#undef V0
#undef V1
#undef V2
}
OPSILA_INLINE float4 intersect_triangle4(const RayPre *r, __global const BankTriangle *a,
                                         __global const BankTriangle *b, __global const BankTriangle *c,
                                         __global const BankTriangle *d, float tmin, float tmax) {
#define V0(k) LOAD4(a->v0, b->v0, c->v0, d->v0, k)
#define V1(k) LOAD4(a->v1, b->v1, c->v1, d->v1, k)
#define V2(k) LOAD4(a->v2, b->v2, c->v2, d->v2, k)
  TRI_TEST_LANES(float4, int4, V0, V1, V2);
#undef V0
#undef V1
#undef V2
}
#undef LOAD2
#undef LOAD4

/* CONTRACT's barycentrics (b1, b2) of the ray's hit on a triangle it is known
 * to hit: P = (1 - b1 - b2) v0 + b1 v1 + b2 v2. */
inline float2 hit_barycentrics(const RayPre *r, __global const BankTriangle *tri) {
  float3 z;
  float3 e = edge_functions(r, tri, &z);
  float det = e.x + e.y + e.z;
  if (det == 0.0f) return (float2)(0.0f, 0.0f);
  float inv_det = 1.0f / det;
  return (float2)(e.y * inv_det, e.z * inv_det);
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
  /* Never culled by rounding while a facet on its face could still win. */
  leave = cull_exit(leave, 1e-30f);
  *t_enter = enter;
  *t_leave = leave;
  return enter <= leave;
}

/* Entry distance of a ray into a sphere, clamped at 0; INFINITY when the
 * sphere does not meet (tmin, tmax). */
inline float sphere_entry(const RayPre *r, __global const Cluster *cl, float tmin, float tmax) {
  float3 oc = r->org - load3g(cl->center);
  float b = dot3(oc, r->dir);
  float c = dot3(oc, oc) - cl->radius * cl->radius;
  float disc = b * b - c;
  if (disc < 0.0f) return OPSILA_INF;
  float s = sqrt(disc);
  float t_near = -b - s, t_far = -b + s;
  if (t_far <= tmin || t_near >= tmax) return OPSILA_INF;
  return fmax(t_near, 0.0f);
}
