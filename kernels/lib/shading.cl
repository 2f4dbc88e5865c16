/* Whitted shading pieces (CONTRACT "Shading"), shared by the SPMD phase and the
 * replicated megakernel so that both shade from one definition. */
#include "texture.cl"

typedef struct {
  float3 p;      /* hit point */
  float3 n;      /* shading normal, facing the ray's side of the facet */
  bool entering; /* dot(Ng, D) < 0 */
  float3 ka, kd; /* the material's, times its texture maps at the hit */
} SurfacePoint;

/* What the bank holds for shading besides facets and materials: vertex
 * attributes, texture copies, texels and the sRGB decode table. */
#define SURFACE_PARAMS                                                                                 \
  __global const BankAttributes *attrs, __global const BankTexture *textures, __global const uint *texels, \
      __global const float *srgb
#define SURFACE_ARGS attrs, textures, texels, srgb

#if OPSILA_INSTANCES
/* A model-frame normal in the world: (A^-1)^T n for a model placed by
 * x = A^-1 (x' - b), i.e. A^T n with A the instance's to_object; not
 * normalised. */
inline float3 instance_normal(__global const Instance *in, float3 n) {
  __global const float *m = in->to_object;
  return (float3)(m[0] * n.x + m[4] * n.y + m[8] * n.z, m[1] * n.x + m[5] * n.y + m[9] * n.z,
                  m[2] * n.x + m[6] * n.y + m[10] * n.z);
}
#define WORLD_VECTOR(insts, inst, n) ((inst) >= 0 ? instance_normal(&(insts)[inst], (n)) : (n))
#else
#define WORLD_VECTOR(insts, inst, n) (n)
#endif

/* The surface at the hit of ray (org, d) at distance t on bank triangle
 * tri_index (of instance inst's model, in its frame, or -1: the scene's
 * own): CONTRACT's Ng, and where the triangle carries attributes, the smooth
 * normal and texture-mapped Ka, Kd at the hit's barycentrics. */
inline SurfacePoint surface_point(FrameParams fp, __global const BankTriangle *tris, __global const Instance *insts,
                                  int tri_index, int inst, __global const Material *m, SURFACE_PARAMS, float3 org,
                                  float3 d, float t) {
  __global const BankTriangle *tri = &tris[tri_index];
  float3 v0 = load3g(tri->v0), v1 = load3g(tri->v1), v2 = load3g(tri->v2);
  float3 ng = unit3(cross3(v1 - v0, v2 - v0));
  if (OPSILA_INSTANCES && inst >= 0) ng = unit3(WORLD_VECTOR(insts, inst, ng));
  SurfacePoint sp;
  sp.p = org + t * d;
  sp.entering = dot3(ng, d) < 0.0f;
  sp.n = sp.entering ? ng : -ng;
  sp.ka = load3g(m->ka);
  sp.kd = load3g(m->kd);
  if (!fp.has_attributes) return sp;
  __global const BankAttributes *at = &attrs[tri_index];
  if (at->flags == 0) return sp;
  RayPre r = make_ray(org, d);
#if OPSILA_INSTANCES
  if (inst >= 0) r = instance_ray(&r, &insts[inst]);
#endif
  float2 b = hit_barycentrics(&r, tri);
  float b0 = 1.0f - b.x - b.y;
  if (at->flags & OPSILA_ATTR_NORMALS) {
    float3 ns = b0 * load3g(at->n0) + b.x * load3g(at->n1) + b.y * load3g(at->n2);
    ns = WORLD_VECTOR(insts, inst, ns);
    float len = len3(ns);
    /* Normals that cancel out leave the facet normal. */
    if (len > 0.0f && isfinite(len)) {
      ns = ns / len;
      sp.n = dot3(ns, sp.n) < 0.0f ? -ns : ns;
    }
  }
  if (at->flags & OPSILA_ATTR_UV) {
    float u = b0 * at->uv[0] + b.x * at->uv[2] + b.y * at->uv[4];
    float v = b0 * at->uv[1] + b.x * at->uv[3] + b.y * at->uv[5];
    if (at->map_kd >= 0) sp.kd = sp.kd * sample_texture(&textures[at->map_kd], texels, srgb, u, v);
    if (at->map_ka >= 0) sp.ka = sp.ka * sample_texture(&textures[at->map_ka], texels, srgb, u, v);
  }
  return sp;
}

/* x^y for the specular term: x = max(0, Rl.(-D)) > 0, y = Ns >= 0.
 * OPSILA_POW_FP64 (the host's choice, on CPUs with doubles): exp2(y log2 x)
 * in doubles, whose error before the final rounding is far below half a
 * float ulp, so the float is the correctly rounded power but in rare
 * near-halfway cases; about five times faster than PoCL's float pow, which
 * is 1 ulp off in about 9% of calls. x = 0 and an infinite y keep pow's
 * special cases (pow(+0, 0) = 1). */
#ifndef OPSILA_POW_FP64
#define OPSILA_POW_FP64 0
#endif
#if OPSILA_POW_FP64
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#endif
inline float specular_pow(float x, float y) {
#if OPSILA_POW_FP64
  if (x > 0.0f && isfinite(x) && isfinite(y)) return (float)exp2((double)y * log2((double)x));
#endif
  return pow(x, y);
}

/* weight * Il * (Kd max(0, n.Lv) + Ks max(0, Rl.(-D))^Ns), zero when
 * n.Lv <= 0; also the unit direction and distance to the light. */
inline float3 light_term(__global const Material *m, __global const Light *light, SurfacePoint sp, float3 d,
                         float3 weight, float3 *lv, float *dist) {
  float3 to_light = load3g(light->position) - sp.p;
  *dist = len3(to_light);
  *lv = to_light / *dist;
  float ndl = dot3(sp.n, *lv);
  if (!(ndl > 0.0f)) return (float3)(0.0f);
  float3 rl = 2.0f * ndl * sp.n - *lv;
  float spec = fmax(0.0f, dot3(rl, -d));
  /* pow (a log and an exp) only where Ks is not zero and spec is: spec^Ns
   * is finite (spec in [0, 1]), so the term is exactly zero without it,
   * and pow(+0, Ns) is exactly +0 for Ns > 0 (C99 F.9.4.4; the light
   * points away from the mirror direction about half the time). */
  float3 ks = load3g(m->ks);
  float3 term = sp.kd * ndl;
  if (any(ks != (float3)(0.0f)) && (spec > 0.0f || !(m->ns > 0.0f))) term = term + ks * specular_pow(spec, m->ns);
  return weight * load3g(light->intensity) * term;
}

inline float3 reflected_direction(SurfacePoint sp, float3 d) { return unit3(d - 2.0f * dot3(d, sp.n) * sp.n); }

/* Refracted direction; false on total internal reflection. */
inline bool transmitted_direction(__global const Material *m, SurfacePoint sp, float3 d, float3 *out) {
  float eta = sp.entering ? 1.0f / m->ni : m->ni;
  float c = -dot3(sp.n, d);
  float k = 1.0f - eta * eta * (1.0f - c * c);
  if (k < 0.0f) return false;
  *out = unit3(eta * d + (eta * c - sqrt(k)) * sp.n);
  return true;
}
