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
#include "../lib/stage_cycles.cl"

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
#define MEGA_LOG(ms, o, dir, tmin, tmax)                       \
  if ((ms)->ray_log) {                                         \
    (ms)->ray_log[2 * (ms)->log_at] = (float4)((o), (tmin));     \
    (ms)->ray_log[2 * (ms)->log_at + 1] = (float4)((dir), (tmax)); \
    ++(ms)->log_at;                                            \
  }

/* The whole scene as one bank, the tests counted over the pixel's rays,
 * and the pixel's ray log (MEGA_LOG). */
typedef struct {
  __global const WalkNode *nodes;
  __global const BankTriangle *tris;
  __global const Instance *insts;
  int root, inst_root; /* the scene's own facets' BVH, its instances' (-1: none) */
  float3 lo, hi; /* the union of the root's child boxes (scene_nearest) */
  float slack;
  uint tri_tests, box_tests;
  __global float4 *ray_log;
  uint log_at;
#ifdef OPSILA_STAGE_CYCLES
  CycleClock *clock; /* megakernel_stages */
#endif
} MegaScene;

/* Pending rays of one pixel's tree, depth-first. */
typedef struct {
  float3 org[MEGA_STACK], dir[MEGA_STACK], w[MEGA_STACK];
  int level[MEGA_STACK];
  int sp;
} MegaStack;

inline bool mega_push(MegaStack *s, float3 org, float3 dir, float3 w, int level) {
  if (s->sp >= MEGA_STACK) return false;
  s->org[s->sp] = org;
  s->dir[s->sp] = dir;
  s->w[s->sp] = w;
  s->level[s->sp] = level;
  ++s->sp;
  return true;
}

/* The nearest hit of a ray (its triangle, -1 for none), its distance and
 * its instance (-1: a facet of the scene's own). */
inline int mega_nearest(MegaScene *ms, const RayPre *r, float tmin, float *t, int *inst) {
  CostProbe no_probe = no_cost_probe();
  HitKey best = hit_none();
  int hit = -1;
  STAGE(ms->clock, OPSILA_STAGE_BANK_WALK, {
    scene_nearest(r, ms->nodes, ms->tris, ms->insts, ms->root, ms->lo, ms->hi, tmin, ms->slack, &best, &hit,
                  &ms->tri_tests, &ms->box_tests, &no_probe);
    if (OPSILA_INSTANCES && ms->inst_root >= 0)
      traverse_nearest(r, ms->nodes, ms->tris, ms->insts, ms->inst_root, tmin, ms->slack, &best, &hit,
                       &ms->tri_tests, &ms->box_tests, &no_probe);
  });
  *inst = best.inst;
  *t = best.t;
  return hit;
}

/* The lights' terms at a hit, each where its shadow ray is not blocked
 * (shade() of spmd_phase.cl, with the shadow ray traced here). */
inline long3 mega_direct(FrameParams fp, MegaScene *ms, __global const Light *lights, __global const Material *m,
                         SurfacePoint surf, float3 d, float3 weight, long3 sum, uint *shadow) {
  CostProbe no_probe = no_cost_probe();
  for (int l = 0; l < fp.num_lights; ++l) {
    float3 lv;
    float dist;
    float3 contrib = light_term(m, &lights[l], surf, d, weight, &lv, &dist);
    if (all(contrib == (float3)(0.0f))) continue;
    ++*shadow;
    MEGA_LOG(ms, surf.p, lv, fp.epsilon, dist);
    RayPre sr = make_ray(surf.p, lv);
    bool blocked;
    STAGE(ms->clock, OPSILA_STAGE_BANK_WALK, {
      blocked = scene_any(&sr, ms->nodes, ms->tris, ms->insts, ms->root, ms->lo, ms->hi, fp.epsilon, dist, ms->slack,
                          &ms->tri_tests, &ms->box_tests, &no_probe);
      if (OPSILA_INSTANCES && !blocked && ms->inst_root >= 0)
        blocked = traverse_any(&sr, ms->nodes, ms->tris, ms->insts, ms->inst_root, fp.epsilon, dist, ms->slack,
                               &ms->tri_tests, &ms->box_tests, &no_probe);
    });
    if (!blocked)
      STAGE(ms->clock, OPSILA_STAGE_PIXEL_SUMS, sum = add_sat(sum, fixed3(contrib))); /* >= 0: saturates as add_fixed does */
  }
  return sum;
}

/* The transmitted and reflected rays of a hit (total internal reflection:
 * no transmitted ray), pushed for the next level; returns how many. */
inline uint mega_children(MegaStack *s, __global const Material *m, SurfacePoint surf, float3 d, float3 weight,
                          int level) {
  float3 kr = load3g(m->kr), kt = load3g(m->kt);
  float3 t_dir;
  uint pushed = 0u;
  if (any(kt != (float3)(0.0f)) && transmitted_direction(m, surf, d, &t_dir))
    pushed += mega_push(s, surf.p, t_dir, weight * kt, level + 1);
  if (any(kr != (float3)(0.0f))) pushed += mega_push(s, surf.p, reflected_direction(surf, d), weight * kr, level + 1);
  return pushed;
}

/* The (object, facet) of a hit: an instance's object, its model's facet. */
inline int2 mega_item(MegaScene *ms, int hit, int inst) {
  return (int2)(inst >= 0 ? ms->insts[inst].object_id : ms->tris[hit].object_id, ms->tris[hit].facet_id);
}

/* One pixel's samples, each sample's ray tree traced depth-first. */
inline void mega_pixel(FrameParams fp, MegaScene *ms, __global const Material *materials, __global const Light *lights,
                       SURFACE_PARAMS, int spp_k, __global const float *offsets, int pixel, __global long *accum,
                       __global uint4 *ray_counts, int write_items, __global int2 *items) {
  int x = pixel % fp.width, y = pixel / fp.width;
  MegaStack s;
  long3 sum = (long3)(0);
  uint secondary = 0u, shadow = 0u;
  int2 item = (int2)(-1, -1);
  float t;
  int inst;
  /* Even k: the centre ray is not a sample; its hit is looked up alone. */
  if (spp_k % 2 == 0 && write_items) {
    RayPre cr = make_ray(load3(fp.eye), primary_direction(fp, x, y));
    int hit = mega_nearest(ms, &cr, 0.0f, &t, &inst);
    if (hit >= 0) item = mega_item(ms, hit, inst);
  }
  for (int sample = 0; sample < spp_k * spp_k; ++sample) {
    int si = sample % spp_k, sj = sample / spp_k;
    bool centre = 2 * si + 1 == spp_k && 2 * sj + 1 == spp_k;
    s.sp = 0;
    mega_push(&s, load3(fp.eye), primary_direction_at(fp, (float)x + offsets[si], (float)y + offsets[sj]),
              (float3)(1.0f, 1.0f, 1.0f), 0);
    while (s.sp > 0) {
      --s.sp;
      float3 org = s.org[s.sp], d = s.dir[s.sp], weight = s.w[s.sp];
      int level = s.level[s.sp];
      /* Primary rays accept any t > 0 (the item buffer's rule); others t > eps. */
      float tmin = level == 0 ? 0.0f : fp.epsilon;
      MEGA_LOG(ms, org, d, tmin, -1.0f);
      RayPre r = make_ray(org, d);
      int hit = mega_nearest(ms, &r, tmin, &t, &inst);
      if (hit < 0) {
        STAGE(ms->clock, OPSILA_STAGE_PIXEL_SUMS, sum = add_sat(sum, fixed3(weight * load3(fp.background))));
        continue;
      }
      __global const BankTriangle *tri = &ms->tris[hit];
      if (level == 0 && centre) item = mega_item(ms, hit, inst);
      STAGE(ms->clock, OPSILA_STAGE_SHADING, {
        __global const Material *m = &materials[OPSILA_TRI_MATERIAL(*tri)];
        SurfacePoint surf = surface_point(fp, ms->tris, ms->insts, hit, inst, m, SURFACE_ARGS, org, d, t);
        STAGE(ms->clock, OPSILA_STAGE_PIXEL_SUMS, sum = add_sat(sum, fixed3(weight * load3(fp.ambient) * surf.ka)));
        sum = mega_direct(fp, ms, lights, m, surf, d, weight, sum, &shadow);
        if (level + 1 < fp.max_depth) secondary += mega_children(&s, m, surf, d, weight, level);
      });
    }
  } /* samples */
  STAGE(ms->clock, OPSILA_STAGE_PIXEL_SUMS, {
    accum[pixel * 3 + 0] = sum.x;
    accum[pixel * 3 + 1] = sum.y;
    accum[pixel * 3 + 2] = sum.z;
  });
  ray_counts[pixel] = (uint4)(secondary, shadow, ms->tri_tests, ms->box_tests);
  if (write_items) items[pixel] = item;
}

__kernel void megakernel(FrameParams fp, __global const WalkNode *nodes, __global const BankTriangle *tris,
                         __global const Instance *insts, __global const Material *materials, __global const Light *lights, SURFACE_PARAMS, int root,
                         float4 root_lo, float4 root_hi, int inst_root, int spp_k, __global const float *offsets, int pixel_begin,
                         int pixel_count, __global long *accum, __global uint4 *ray_counts, int write_items,
                         __global int2 *items) {
  int k = get_global_id(0);
  if (k >= pixel_count) return;
  MegaScene ms = {nodes, tris, insts, root, inst_root, root_lo.xyz, root_hi.xyz, fp.box_slack, 0u, 0u, 0, 0u};
  mega_pixel(fp, &ms, materials, lights, SURFACE_ARGS, spp_k, offsets, pixel_begin + k, accum, ray_counts,
             write_items, items);
}

/* The same frame, every ray also written to ray_log from ray_log[2 *
 * log_first[pixel]] on (the prefix sums of the rays counted by a megakernel
 * run), for the bench's traversal-alone figure (baselines/traversal.cl). */
__kernel void megakernel_rays(FrameParams fp, __global const WalkNode *nodes, __global const BankTriangle *tris,
                              __global const Instance *insts, __global const Material *materials, __global const Light *lights, SURFACE_PARAMS,
                              int root, float4 root_lo, float4 root_hi, int inst_root, int spp_k, __global const float *offsets,
                              int pixel_begin, int pixel_count, __global long *accum, __global uint4 *ray_counts,
                              int write_items, __global int2 *items, __global const uint *log_first,
                              __global float4 *ray_log) {
  int k = get_global_id(0);
  if (k >= pixel_count) return;
  MegaScene ms = {nodes, tris, insts, root, inst_root, root_lo.xyz, root_hi.xyz, fp.box_slack, 0u, 0u, ray_log,
                  log_first[pixel_begin + k]};
  mega_pixel(fp, &ms, materials, lights, SURFACE_ARGS, spp_k, offsets, pixel_begin + k, accum, ray_counts,
             write_items, items);
}

#ifdef OPSILA_STAGE_CYCLES
/* The megakernel with its stage clocks (the bench's breakdown frame): the
 * same frame; every work-item's cycles per stage are added to
 * stage_cycles (OPSILA_STAGE_COUNT counters of OPSILA_COUNTER_WORDS words). */
__kernel void megakernel_stages(FrameParams fp, __global const WalkNode *nodes, __global const BankTriangle *tris,
                                __global const Instance *insts, __global const Material *materials, __global const Light *lights, SURFACE_PARAMS,
                                int root, float4 root_lo, float4 root_hi, int inst_root, int spp_k, __global const float *offsets,
                                int pixel_begin, int pixel_count, __global long *accum, __global uint4 *ray_counts,
                                int write_items, __global int2 *items, volatile __global uint *stage_cycles) {
  int k = get_global_id(0);
  if (k >= pixel_count) return;
  CycleClock clock;
  stage_clear(&clock);
  stage_start(&clock, OPSILA_STAGE_CAMERA);
  MegaScene ms = {nodes, tris, insts, root, inst_root, root_lo.xyz, root_hi.xyz, fp.box_slack, 0u, 0u, 0, 0u, &clock};
  mega_pixel(fp, &ms, materials, lights, SURFACE_ARGS, spp_k, offsets, pixel_begin + k, accum, ray_counts,
             write_items, items);
  stage_enter(&clock, OPSILA_STAGE_CAMERA);
  stage_flush(&clock, stage_cycles);
}
#endif
