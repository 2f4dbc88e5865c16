/* Whitted shading rules and the SPEC camera, shared by the SPMD phase,
 * the item buffer and the replicated megakernel. */
#include "geometry.cl"

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

/* SPEC camera: direction of the ray through image point (px, py); pixel
 * (x, y)'s centre is (x + 0.5, y + 0.5), its sample (i, j) is
 * (x + (i+0.5)/k, y + (j+0.5)/k) with the offsets computed on the host. */
inline float3 primary_direction_at(FrameParams fp, float px, float py) {
  float sx = (2.0f * px / (float)fp.width - 1.0f) * fp.tan_half_fov * fp.aspect;
  float sy = (1.0f - 2.0f * py / (float)fp.height) * fp.tan_half_fov;
  return normalize(load3(fp.forward) + sx * load3(fp.right) + sy * load3(fp.up));
}

/* Primary (centre) ray direction of pixel (x, y). */
inline float3 primary_direction(FrameParams fp, int x, int y) {
  return primary_direction_at(fp, (float)x + 0.5f, (float)y + 0.5f);
}
