/* SPMD phase: one work-group = one PE, working only on its own bank: its
 * descriptors (slots p*n .. p*n + count) and its facets. Every PE also knows
 * the bounding volumes of all clusters (small, global), which name the
 * destination PEs of the rays it sends on.
 *
 * Each processed descriptor owns S = OPSILA_SPAWN_SLOTS(lights) output
 * slots (fixed places, so the output is deterministic; see opsila_shared.h);
 * unused slots are NIL holes that the scatter skips. */
#include "lib/bvh.cl"
#include "lib/routing.cl"
#include "lib/shading.cl"
#include "lib/accum.cl"

typedef struct {
  uint v[OPSILA_STAT_COUNT];
} PrivStats;

inline void emit(DESC_PARAMS(o), int slot, float4 org, float4 dir, float4 wgt, int4 ids, int dest) {
  o_org[slot] = org;
  o_dir[slot] = dir;
  o_wgt[slot] = wgt;
  o_ids[slot] = ids;
  o_dest[slot] = dest;
}

/* A new ray leaving a surface (or going to a light): first destination in
 * entry order, or none. */
inline int first_destination(const Routing *rt, const RayPre *r, float eps, float tmax, float *entry, PrivStats *st) {
  return next_destination(rt, r, eps, tmax, -1.0f, -1, entry, &st->v[OPSILA_STAT_SPHERE_TESTS],
                          &st->v[OPSILA_STAT_ROUTE_TESTS]);
}

/* Whitted shading of a resolved hit at its owner PE: ambient now, one shadow
 * descriptor per light that can contribute, reflected and transmitted
 * descriptors for the next level. */
inline void shade(FrameParams fp, const Routing *rt, __global const BankTriangle *tris, __global const Material *materials,
                  __global const Light *lights, float3 org, float3 d, float t, int tri_index, float3 weight,
                  int pixel, int level, int out_base, DESC_PARAMS(o), volatile __global uint *accum, PrivStats *st) {
  __global const BankTriangle *tri = &tris[tri_index];
  SurfacePoint sp = surface_point(tri, org, d, t);
  float3 p = sp.p;
  __global const Material *m = &materials[tri->material];
  float eps = fp.epsilon;

  accumulate(accum, pixel, weight * load3(fp.ambient) * load3g(m->ka));

  for (int l = 0; l < fp.num_lights; ++l) {
    float3 lv;
    float dist;
    float3 contrib = light_term(m, &lights[l], sp, d, weight, &lv, &dist);
    if (all(contrib == (float3)(0.0f))) continue;
    ++st->v[OPSILA_STAT_SPAWN_SHADOW];
    RayPre sr = make_ray(p, lv);
    float entry = 0.0f;
    int dest = next_shadow_destination(rt, &sr, eps, dist, -1, &st->v[OPSILA_STAT_SPHERE_TESTS],
                                       &st->v[OPSILA_STAT_ROUTE_TESTS]);
    if (dest < 0) { /* no sphere on the way: lit without leaving this PE */
      ++st->v[OPSILA_STAT_LIT];
      accumulate(accum, pixel, contrib);
    } else {
      emit(o_org, o_dir, o_wgt, o_ids, o_dest, out_base + OPSILA_SLOT_SHADOW(l), (float4)(p, dist),
           (float4)(lv, entry), (float4)(contrib, 0.0f),
           (int4)(pixel, OPSILA_META(OPSILA_KIND_SHADOW, level), -1, dest), dest);
    }
  }

  if (level + 1 >= fp.max_depth) return;
  float3 kr = load3g(m->kr), kt = load3g(m->kt);
  float3 child_d[2];
  float3 child_w[2];
  bool child_ok[2] = {false, false};
  if (any(kr != (float3)(0.0f))) {
    child_d[0] = reflected_direction(sp, d);
    child_w[0] = weight * kr;
    child_ok[0] = true;
  }
  /* Total internal reflection: no transmitted ray. */
  if (any(kt != (float3)(0.0f)) && transmitted_direction(m, sp, d, &child_d[1])) {
    child_w[1] = weight * kt;
    child_ok[1] = true;
  }
  for (int j = 0; j < 2; ++j) {
    if (!child_ok[j]) continue;
    ++st->v[OPSILA_STAT_SPAWN_RADIANCE];
    RayPre cr = make_ray(p, child_d[j]);
    float entry;
    int dest = first_destination(rt, &cr, eps, OPSILA_INF, &entry, st);
    if (dest < 0) { /* meets no sphere: a miss, finished here (counted at its own level) */
      accumulate(accum, pixel, child_w[j] * load3(fp.background));
      ++st->v[OPSILA_STAT_MISS + 0]; /* attributed below to level + 1 */
    } else {
      const int slot = j == 0 ? OPSILA_SLOT_FORWARD : OPSILA_SLOT_TRANSMITTED; /* reflected, transmitted */
      emit(o_org, o_dir, o_wgt, o_ids, o_dest, out_base + slot, (float4)(p, OPSILA_INF), (float4)(child_d[j], entry),
           (float4)(child_w[j], 0.0f), (int4)(pixel, OPSILA_META(OPSILA_KIND_TRACE, level + 1), -1, dest), dest);
    }
  }
}

__kernel void spmd_phase(FrameParams fp, __global const PeInfo *pes, __global const Cluster *clusters,
                         __global const BankNode *route, int routing, __global const BankNode *nodes, __global const BankTriangle *tris,
                         __global const Material *materials, __global const Light *lights, DESC_PARAMS(b),
                         __global const int *bank_count, __global int *processed_count, DESC_PARAMS(o),
                         volatile __global uint *accum, volatile __global uint *stats) {
  __local uint lstats[OPSILA_MAX_DEPTH * OPSILA_STAT_COUNT];
  int pe = get_group_id(0);
  int lid = get_local_id(0), lsz = get_local_size(0);
  for (int i = lid; i < OPSILA_MAX_DEPTH * OPSILA_STAT_COUNT; i += lsz) lstats[i] = 0u;
  barrier(CLK_LOCAL_MEM_FENCE);

  int n = fp.bank_capacity, S = fp.spawn_slots;
  int count = bank_count[pe];
  if (lid == 0) processed_count[pe] = count;
  __global const PeInfo *me = &pes[pe];
  int root = me->node_begin;
  bool bank_empty = me->node_begin == me->node_end;
  float eps = fp.epsilon;
  Routing rt;
  rt.pes = pes;
  rt.clusters = clusters;
  rt.route = route;
  rt.num_pes = fp.num_pes;
  rt.mode = routing;

  for (int i = lid; i < count; i += lsz) {
    int slot = pe * n + i;
    int out_base = slot * S;
    for (int j = 0; j < S; ++j) o_dest[out_base + j] = -1;
    float4 org4 = b_org[slot], dir4 = b_dir[slot], wgt4 = b_wgt[slot];
    int4 ids = b_ids[slot];
    int kind = OPSILA_META_KIND(ids.y), level = OPSILA_META_LEVEL(ids.y);
    float3 org = org4.xyz, d = dir4.xyz, w = wgt4.xyz;
    PrivStats st;
    for (int s = 0; s < OPSILA_STAT_COUNT; ++s) st.v[s] = 0u;
    uint child_misses = 0u;
    ++st.v[OPSILA_STAT_TRACED];
    RayPre r = make_ray(org, d);

    if (kind == OPSILA_KIND_SHADOW) {
      ++st.v[OPSILA_STAT_SHADOW];
      float tmax = org4.w;
      bool blocked = !bank_empty && traverse_any(&r, nodes, tris, root, eps, tmax, &st.v[OPSILA_STAT_TRI_TESTS],
                                                 &st.v[OPSILA_STAT_BOX_TESTS]);
      if (blocked) {
        ++st.v[OPSILA_STAT_OCCLUDED];
      } else {
        int dest = next_shadow_destination(&rt, &r, eps, tmax, pe, &st.v[OPSILA_STAT_SPHERE_TESTS],
                                           &st.v[OPSILA_STAT_ROUTE_TESTS]);
        if (dest < 0) {
          ++st.v[OPSILA_STAT_LIT];
          accumulate(accum, ids.x, w);
        } else {
          ++st.v[OPSILA_STAT_FORWARD];
          emit(o_org, o_dir, o_wgt, o_ids, o_dest, out_base + OPSILA_SLOT_FORWARD, org4, dir4, wgt4,
               (int4)(ids.x, ids.y, -1, dest), dest);
        }
      }
    } else {
      float t_best = org4.w;
      int hit = ids.z;
      if (kind == OPSILA_KIND_TRACE) {
        ++st.v[OPSILA_STAT_RADIANCE];
        int best_facet = hit >= 0 ? tris[hit].facet_id : INT_MAX;
        if (!bank_empty)
          traverse_nearest(&r, nodes, tris, root, eps, &t_best, &hit, &best_facet, &st.v[OPSILA_STAT_TRI_TESTS],
                           &st.v[OPSILA_STAT_BOX_TESTS]);
        float entry;
        int dest = next_destination(&rt, &r, eps, tie_limit(t_best), dir4.w, pe, &entry,
                                    &st.v[OPSILA_STAT_SPHERE_TESTS], &st.v[OPSILA_STAT_ROUTE_TESTS]);
        if (dest >= 0) { /* a nearer hit (or a tie with a lower facet id) may wait in another bank */
          ++st.v[OPSILA_STAT_FORWARD];
          emit(o_org, o_dir, o_wgt, o_ids, o_dest, out_base + OPSILA_SLOT_FORWARD, (float4)(org, t_best),
               (float4)(d, entry), wgt4, (int4)(ids.x, ids.y, hit, dest), dest);
          kind = OPSILA_KIND_NIL;
        } else if (hit < 0) {
          ++st.v[OPSILA_STAT_MISS];
          accumulate(accum, ids.x, w * load3(fp.background));
          kind = OPSILA_KIND_NIL;
        } else {
          int owner = owner_pe(pes, fp.num_pes, hit);
          if (owner != pe) { /* nearest hit known; its facet lives in another bank */
            ++st.v[OPSILA_STAT_FORWARD];
            emit(o_org, o_dir, o_wgt, o_ids, o_dest, out_base + OPSILA_SLOT_FORWARD, (float4)(org, t_best),
                 (float4)(d, 0.0f), wgt4, (int4)(ids.x, OPSILA_META(OPSILA_KIND_RESOLVED, level), hit, owner), owner);
            kind = OPSILA_KIND_NIL;
          } else {
            kind = OPSILA_KIND_RESOLVED;
          }
        }
      }
      if (kind == OPSILA_KIND_RESOLVED) {
        ++st.v[OPSILA_STAT_RESOLVED];
        uint misses_before = st.v[OPSILA_STAT_MISS];
        shade(fp, &rt, tris, materials, lights, org, d, t_best, hit, w, ids.x, level, out_base, o_org,
              o_dir, o_wgt, o_ids, o_dest, accum, &st);
        child_misses = st.v[OPSILA_STAT_MISS] - misses_before;
        st.v[OPSILA_STAT_MISS] = misses_before;
      }
    }
    for (int s = 0; s < OPSILA_STAT_COUNT; ++s)
      if (st.v[s] != 0u) atomic_add(&lstats[level * OPSILA_STAT_COUNT + s], st.v[s]);
    if (child_misses != 0u && level + 1 < OPSILA_MAX_DEPTH)
      atomic_add(&lstats[(level + 1) * OPSILA_STAT_COUNT + OPSILA_STAT_MISS], child_misses);
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  for (int i = lid; i < fp.max_depth * OPSILA_STAT_COUNT; i += lsz) {
    uint v = lstats[i];
    if (v != 0u) count_stat(stats, fp.num_pes, i / OPSILA_STAT_COUNT, pe, i % OPSILA_STAT_COUNT, v);
  }
}
