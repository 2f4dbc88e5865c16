/* SPMD phase: each PE works only on its own bank: its descriptors and its
 * facets. Every PE also knows the bounding volumes of all clusters (small,
 * global), which name the destination PEs of the rays it sends on.
 *
 * Work-items follow descriptors: one descriptor per work-item. A PE's bank
 * is served by as many work-groups as its count needs this round; the
 * exchange's plan (kernels/scatter.cl) lists them: work-group g serves PE
 * group_pe[g], bank slots group_first[g] .. + local size (up to the bank's
 * end). No work-group mixes two banks.
 *
 * Each work-item owns S = lights + 2 output records (fixed places, so the
 * output is deterministic) and fills them from the front: the reflected or
 * forwarded ray, the transmitted ray, then one shadow ray per light that
 * needs one. out_item_count says how many, so the exchange never reads an
 * empty slot. */
#include "lib/bvh.cl"
#include "lib/routing.cl"
#include "lib/shading.cl"
#include "lib/accum.cl"

typedef struct {
  uint v[OPSILA_STAT_COUNT];
} PrivStats;

/* Output records of one work-item: its S places, filled from the front,
 * and the PE x PE traffic of its work-group (local, flushed once). */
typedef struct {
  __global float4 *v; /* the output records and their destinations (DESC_PARAMS) */
  __global int *v_dest;
  int base, count;
  int num_pes, traffic_levels; /* traffic_levels = 0: not counted */
  __local uint *traffic;       /* [level][destination PE] from this work-group's PE */
} Outputs;

inline void emit(Outputs *o, Descriptor d) {
  desc_store(o->v, o->v_dest, o->base + o->count, d);
  ++o->count;
  int level = OPSILA_META_LEVEL(DESC_META(d));
  if (level < o->traffic_levels) atomic_inc(&o->traffic[level * o->num_pes + DESC_DEST(d)]);
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
inline void shade(FrameParams fp, const Routing *rt, __global const BankTriangle *tris,
                  __global const Material *materials, __global const Light *lights, SURFACE_PARAMS, float3 org, float3 d,
                  float t, int tri_index, float3 weight, int pixel, int level, Outputs *out, volatile __global uint *accum,
                  PrivStats *st) {
  __global const Material *m = &materials[tris[tri_index].material];
  SurfacePoint sp = surface_point(fp, tris, tri_index, m, SURFACE_ARGS, org, d, t);
  float3 p = sp.p;
  float eps = fp.epsilon;

  accumulate(accum, pixel, weight * load3(fp.ambient) * sp.ka);

  for (int l = 0; l < fp.num_lights; ++l) {
    float3 lv;
    float dist;
    float3 contrib = light_term(m, &lights[l], sp, d, weight, &lv, &dist);
    if (all(contrib == (float3)(0.0f))) continue;
    ++st->v[OPSILA_STAT_SPAWN_SHADOW];
    RayPre sr = make_ray(p, lv);
    int dest = next_shadow_destination(rt, &sr, eps, dist, -1, &st->v[OPSILA_STAT_SPHERE_TESTS],
                                       &st->v[OPSILA_STAT_ROUTE_TESTS]);
    if (dest < 0) { /* no sphere on the way: lit without leaving this PE */
      ++st->v[OPSILA_STAT_LIT];
      accumulate(accum, pixel, contrib);
    } else {
      emit(out, make_descriptor(p, dist, lv, 0.0f, contrib, pixel, OPSILA_META(OPSILA_KIND_SHADOW, level), -1, dest));
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
      emit(out, make_descriptor(p, OPSILA_INF, child_d[j], entry, child_w[j], pixel,
                                OPSILA_META(OPSILA_KIND_TRACE, level + 1), -1, dest));
    }
  }
}

/* One descriptor at its PE: a shadow ray tests its segment in the bank; a
 * radiance ray looks for its nearest hit here and is sent on, finished as a
 * miss, or (its nearest hit known) shaded by the PE that owns the facet. */
inline void process(FrameParams fp, int pe, const Routing *rt, __global const BankNode *nodes, __global const BankTriangle *tris,
                    __global const Material *materials, __global const Light *lights, SURFACE_PARAMS, Descriptor ds,
                    Outputs *out,
                    volatile __global uint *accum, PrivStats *st) {
  __global const PeInfo *me = &rt->pes[pe];
  int root = me->node_begin;
  bool bank_empty = me->node_begin == me->node_end;
  float eps = fp.epsilon;
  int kind = OPSILA_META_KIND(DESC_META(ds)), level = OPSILA_META_LEVEL(DESC_META(ds));
  int pixel = DESC_PIXEL(ds);
  float3 org = DESC_ORIGIN(ds), d = DESC_DIRECTION(ds), w = DESC_WEIGHT(ds);
  ++st->v[OPSILA_STAT_TRACED];
  RayPre r = make_ray(org, d);

  if (kind == OPSILA_KIND_SHADOW) {
    ++st->v[OPSILA_STAT_SHADOW];
    float tmax = DESC_T_MAX(ds);
    bool blocked = !bank_empty && traverse_any(&r, nodes, tris, root, eps, tmax, &st->v[OPSILA_STAT_TRI_TESTS],
                                               &st->v[OPSILA_STAT_BOX_TESTS]);
    if (blocked) {
      ++st->v[OPSILA_STAT_OCCLUDED];
      return;
    }
    int dest = next_shadow_destination(rt, &r, eps, tmax, pe, &st->v[OPSILA_STAT_SPHERE_TESTS],
                                       &st->v[OPSILA_STAT_ROUTE_TESTS]);
    if (dest < 0) {
      ++st->v[OPSILA_STAT_LIT];
      accumulate(accum, pixel, w);
    } else {
      ++st->v[OPSILA_STAT_FORWARD];
      DESC_HIT(ds) = -1;
      DESC_DEST(ds) = dest;
      emit(out, ds);
    }
    return;
  }
  float t_best = DESC_T_BEST(ds);
  int hit = DESC_HIT(ds);
  if (kind == OPSILA_KIND_TRACE) {
    ++st->v[OPSILA_STAT_RADIANCE];
    int best_facet = hit >= 0 ? as_int(DESC_BEST_FACET(ds)) : INT_MAX;
    int found = -1; /* local index of a facet of this bank that won */
    if (!bank_empty)
      traverse_nearest(&r, nodes, tris, root, eps, &t_best, &found, &best_facet, &st->v[OPSILA_STAT_TRI_TESTS],
                       &st->v[OPSILA_STAT_BOX_TESTS]);
    if (found >= 0) hit = fp.tri_base + found;
    float entry;
    int dest = next_destination(rt, &r, eps, tie_limit(t_best), DESC_CURSOR_ENTRY(ds), pe, &entry,
                                &st->v[OPSILA_STAT_SPHERE_TESTS], &st->v[OPSILA_STAT_ROUTE_TESTS]);
    if (dest >= 0) { /* a nearer hit (or a tie with a lower facet id) may wait in another bank */
      ++st->v[OPSILA_STAT_FORWARD];
      Descriptor sent = make_descriptor(org, t_best, d, entry, w, pixel, DESC_META(ds), hit, dest);
      DESC_BEST_FACET(sent) = as_float(best_facet);
      emit(out, sent);
      return;
    }
    if (hit < 0) {
      ++st->v[OPSILA_STAT_MISS];
      accumulate(accum, pixel, w * load3(fp.background));
      return;
    }
    int owner = owner_pe(rt->pes, fp.num_pes, hit);
    if (owner != pe) { /* nearest hit known; its facet lives in another bank */
      ++st->v[OPSILA_STAT_FORWARD];
      emit(out, make_descriptor(org, t_best, d, 0.0f, w, pixel, OPSILA_META(OPSILA_KIND_RESOLVED, level), hit, owner));
      return;
    }
  }
  ++st->v[OPSILA_STAT_RESOLVED];
  shade(fp, rt, tris, materials, lights, SURFACE_ARGS, org, d, t_best, hit - fp.tri_base, w, pixel, level, out, accum, st);
}

__kernel void spmd_phase(FrameParams fp, __global const PeInfo *pes, __global const Cluster *clusters,
                         __global const BankNode *route, int routing, __global const BankNode *nodes, __global const BankTriangle *tris,
                         __global const Material *materials, __global const Light *lights, SURFACE_PARAMS,
                         DESC_PARAMS(b), __global const int *group_pe, __global const int *group_first,
                         __global const int *bank_begin, __global const int *bank_count, DESC_PARAMS(o),
                         __global int *out_item_count, volatile __global uint *accum, volatile __global uint *stats,
                         volatile __global uint *traffic, int traffic_levels) {
  __local uint lstats[OPSILA_MAX_DEPTH * OPSILA_STAT_COUNT];
  __local uint ltraffic[OPSILA_MAX_DEPTH * OPSILA_TRAFFIC_MAX_PES];
  int g = get_group_id(0), lid = get_local_id(0), lsz = get_local_size(0);
  int P = fp.num_pes, depth = fp.max_depth;
  int ntraffic = traffic_levels * P;
  for (int i = lid; i < depth * OPSILA_STAT_COUNT; i += lsz) lstats[i] = 0u;
  for (int i = lid; i < ntraffic; i += lsz) ltraffic[i] = 0u;
  barrier(CLK_LOCAL_MEM_FENCE);

  int pe = group_pe[g];
  int slot = group_first[g] + lid;
  int item = g * lsz + lid;
  Outputs out;
  out.v = o;
  out.v_dest = o_dest;
  out.base = item * fp.spawn_slots;
  out.count = 0;
  out.num_pes = P;
  out.traffic_levels = traffic_levels;
  out.traffic = ltraffic;
  Routing rt;
  rt.pes = pes;
  rt.clusters = clusters;
  rt.route = route;
  rt.num_pes = P;
  rt.mode = routing;
  if (slot < bank_begin[pe] + bank_count[pe]) {
    Descriptor ds = desc_load(b, slot);
    int level = OPSILA_META_LEVEL(DESC_META(ds));
    PrivStats st;
    for (int s = 0; s < OPSILA_STAT_COUNT; ++s) st.v[s] = 0u;
    process(fp, pe, &rt, nodes, tris, materials, lights, SURFACE_ARGS, ds, &out, accum, &st);
    /* Children that miss every sphere finish here but count at their level. */
    uint child_misses = 0u;
    if (OPSILA_META_KIND(DESC_META(ds)) != OPSILA_KIND_SHADOW && st.v[OPSILA_STAT_RESOLVED] != 0u) {
      child_misses = st.v[OPSILA_STAT_MISS];
      st.v[OPSILA_STAT_MISS] = 0u;
    }
    for (int s = 0; s < OPSILA_STAT_COUNT; ++s)
      if (st.v[s] != 0u) atomic_add(&lstats[level * OPSILA_STAT_COUNT + s], st.v[s]);
    if (child_misses != 0u && level + 1 < OPSILA_MAX_DEPTH)
      atomic_add(&lstats[(level + 1) * OPSILA_STAT_COUNT + OPSILA_STAT_MISS], child_misses);
  }
  out_item_count[item] = out.count;
  /* Statistics and traffic leave the work-group once, not per descriptor. */
  barrier(CLK_LOCAL_MEM_FENCE);
  for (int i = lid; i < depth * OPSILA_STAT_COUNT; i += lsz) {
    uint v = lstats[i];
    if (v != 0u) count_stat(stats, P, i / OPSILA_STAT_COUNT, pe, i % OPSILA_STAT_COUNT, v);
  }
  for (int i = lid; i < ntraffic; i += lsz) {
    uint v = ltraffic[i];
    if (v != 0u) atomic_add(&traffic[((long)(i / P) * P + pe) * P + i % P], v);
  }
}
