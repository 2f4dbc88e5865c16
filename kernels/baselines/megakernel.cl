/* Baseline for the benchmarks: the replicated-scene megakernel. One
 * work-item per pixel sees the whole scene (one BVH over all facets, i.e. the
 * scene partitioned for a single PE) and traces its pixel's Whitted ray tree
 * on its own, with a small explicit stack of pending rays: no banks, no
 * descriptors, no exchange. This is what OPSILA avoids (every PE holding the
 * whole scene), measured on the same device.
 *
 * Shading is kernels/spmd_phase.cl's, expression for expression, and every
 * contribution is quantised to fixed point exactly as accumulate() does, so
 * the sums (and the image) equal the OPSILA renderer's up to float ties. */
#include "../lib/bvh.cl"
#include "../lib/camera.cl"
#include "../lib/shading.cl"
#include "../lib/accum.cl"

/* Pending rays: a node pops one ray and pushes at most two (depth-first), so
 * at most max_depth + 1 rays ever wait. */
#define MEGA_STACK (OPSILA_MAX_DEPTH + 2)

/* accum: 3 x 64-bit fixed-point sums per pixel, over its spp_k x spp_k
 * samples (the renderer's pixel sums; the host divides by the sample count).
 * offsets[i] = (i + 0.5) / spp_k, from the host.
 * ray_counts: per pixel (secondary rays spawned, shadow rays spawned, as
 * RenderStats counts them; ray-facet tests, ray-box tests).
 * items: (object, facet) of the centre ray's primary hit, written when
 * write_items is set (the bench's frames compare images only). */
/* ray_log: 0, or where this pixel's rays go, from ray_log[2 * log_at] on
 * (megakernel_rays below): each ray traced, in the order traced (the centre
 * ray of an even sample grid apart, which is not counted as a ray), as
 * (origin, tmin) and (direction, tmax), tmax < 0 for a nearest-hit ray. */
#define MEGA_LOG(o, dir, tmin, tmax)                  \
  if (ray_log) {                                      \
    ray_log[2 * log_at] = (float4)((o), (tmin));      \
    ray_log[2 * log_at + 1] = (float4)((dir), (tmax)); \
    ++log_at;                                         \
  }

inline void mega_pixel(FrameParams fp, __global const BankNode *nodes, __global const BankTriangle *tris,
                       __global const Material *materials, __global const Light *lights, SURFACE_PARAMS, int root,
                       float3 lo, float3 hi, int spp_k, __global const float *offsets, int pixel, __global long *accum,
                       __global uint4 *ray_counts, int write_items, __global int2 *items, __global float4 *ray_log,
                       uint log_at) {
  int x = pixel % fp.width, y = pixel / fp.width;
  float eps = fp.epsilon;

  float3 s_org[MEGA_STACK], s_dir[MEGA_STACK], s_w[MEGA_STACK];
  int s_level[MEGA_STACK];
  int sp = 0;

  long3 sum = (long3)(0);
  uint secondary = 0u, shadow = 0u;
  uint tri_tests = 0u, box_tests = 0u;
  CostProbe no_probe = no_cost_probe();
  int2 item = (int2)(-1, -1);
  /* Even k: the centre ray is not a sample; its hit is looked up alone. */
  if (spp_k % 2 == 0 && write_items) {
    RayPre cr = make_ray(load3(fp.eye), primary_direction(fp, x, y));
    HitKey best = hit_none();
    int hit = -1;
    scene_nearest(&cr, nodes, tris, root, lo, hi, 0.0f, fp.box_slack, &best, &hit, &tri_tests, &box_tests, &no_probe);
    if (hit >= 0) item = (int2)(tris[hit].object_id, tris[hit].facet_id);
  }

  for (int sample = 0; sample < spp_k * spp_k; ++sample) {
    int si = sample % spp_k, sj = sample / spp_k;
    bool centre = 2 * si + 1 == spp_k && 2 * sj + 1 == spp_k;
    s_org[0] = load3(fp.eye);
    s_dir[0] = primary_direction_at(fp, (float)x + offsets[si], (float)y + offsets[sj]);
    s_w[0] = (float3)(1.0f, 1.0f, 1.0f);
    s_level[0] = 0;
    sp = 1;

    while (sp > 0) {
      --sp;
      float3 org = s_org[sp], d = s_dir[sp], weight = s_w[sp];
      int level = s_level[sp];
      /* Primary rays accept any t > 0 (the item buffer's rule); others t > eps. */
      float tmin = level == 0 ? 0.0f : eps;
      MEGA_LOG(org, d, tmin, -1.0f);
      RayPre r = make_ray(org, d);
      HitKey best = hit_none();
      int hit = -1;
      scene_nearest(&r, nodes, tris, root, lo, hi, tmin, fp.box_slack, &best, &hit, &tri_tests, &box_tests,
                    &no_probe);
      float t = best.t;
      if (hit < 0) {
        sum = add_sat(sum, fixed3(weight * load3(fp.background)));
        continue;
      }
      __global const BankTriangle *tri = &tris[hit];
      if (level == 0 && centre) item = (int2)(tri->object_id, tri->facet_id);

      /* shade() of spmd_phase.cl, with the shadow ray traced here. */
      __global const Material *m = &materials[OPSILA_TRI_MATERIAL(*tri)];
      SurfacePoint surf = surface_point(fp, tris, hit, m, SURFACE_ARGS, org, d, t);
      float3 p = surf.p;

      sum = add_sat(sum, fixed3(weight * load3(fp.ambient) * surf.ka));

      for (int l = 0; l < fp.num_lights; ++l) {
        float3 lv;
        float dist;
        float3 contrib = light_term(m, &lights[l], surf, d, weight, &lv, &dist);
        if (all(contrib == (float3)(0.0f))) continue;
        ++shadow;
        MEGA_LOG(p, lv, eps, dist);
        RayPre sr = make_ray(p, lv);
        if (!scene_any(&sr, nodes, tris, root, lo, hi, eps, dist, fp.box_slack, &tri_tests, &box_tests, &no_probe))
          sum = add_sat(sum, fixed3(contrib)); /* >= 0: saturates as add_fixed does */
      }

      if (level + 1 >= fp.max_depth) continue;
      float3 kr = load3g(m->kr), kt = load3g(m->kt);
      float3 t_dir;
      /* Total internal reflection: no transmitted ray. */
      if (any(kt != (float3)(0.0f)) && transmitted_direction(m, surf, d, &t_dir) && sp < MEGA_STACK) {
        ++secondary;
        s_org[sp] = p;
        s_dir[sp] = t_dir;
        s_w[sp] = weight * kt;
        s_level[sp] = level + 1;
        ++sp;
      }
      if (any(kr != (float3)(0.0f)) && sp < MEGA_STACK) {
        ++secondary;
        s_org[sp] = p;
        s_dir[sp] = reflected_direction(surf, d);
        s_w[sp] = weight * kr;
        s_level[sp] = level + 1;
        ++sp;
      }
    }
  } /* samples */
  accum[pixel * 3 + 0] = sum.x;
  accum[pixel * 3 + 1] = sum.y;
  accum[pixel * 3 + 2] = sum.z;
  ray_counts[pixel] = (uint4)(secondary, shadow, tri_tests, box_tests);
  if (write_items) items[pixel] = item;
}

__kernel void megakernel(FrameParams fp, __global const BankNode *nodes, __global const BankTriangle *tris,
                         __global const Material *materials, __global const Light *lights, SURFACE_PARAMS, int root,
                         float4 root_lo, float4 root_hi, int spp_k, __global const float *offsets, int pixel_begin,
                         int pixel_count, __global long *accum, __global uint4 *ray_counts, int write_items,
                         __global int2 *items) {
  int k = get_global_id(0);
  if (k >= pixel_count) return;
  mega_pixel(fp, nodes, tris, materials, lights, SURFACE_ARGS, root, root_lo.xyz, root_hi.xyz, spp_k, offsets,
             pixel_begin + k, accum, ray_counts, write_items, items, 0, 0u);
}

/* The same frame, every ray also written to ray_log from ray_log[2 *
 * log_first[pixel]] on (the prefix sums of the rays counted by a megakernel
 * run), for the bench's traversal-alone figure (baselines/traversal.cl). */
__kernel void megakernel_rays(FrameParams fp, __global const BankNode *nodes, __global const BankTriangle *tris,
                              __global const Material *materials, __global const Light *lights, SURFACE_PARAMS,
                              int root, float4 root_lo, float4 root_hi, int spp_k, __global const float *offsets,
                              int pixel_begin, int pixel_count, __global long *accum, __global uint4 *ray_counts,
                              int write_items, __global int2 *items, __global const uint *log_first,
                              __global float4 *ray_log) {
  int k = get_global_id(0);
  if (k >= pixel_count) return;
  mega_pixel(fp, nodes, tris, materials, lights, SURFACE_ARGS, root, root_lo.xyz, root_hi.xyz, spp_k, offsets,
             pixel_begin + k, accum, ray_counts, write_items, items, ray_log, log_first[pixel_begin + k]);
}
