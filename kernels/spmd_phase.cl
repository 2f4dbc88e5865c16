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
 * empty slot.
 *
 * The launch's first work-groups, when it has more than spmd_groups, build
 * the next round's primary descriptors into the waiting pool (primary.cl,
 * the same function as build_primary): they read neither the banks nor
 * the outputs, and a launch of their own costs a GPU more than their work.
 * First, not last: last, PoCL's two threads finished each round unevenly
 * (docs/BENCHMARKS.md, "Levers kept"). */
#include "primary.cl"
#include "lib/bvh.cl"
#include "lib/routing.cl"
#include "lib/shading.cl"
#include "lib/accum.cl"
#include "lib/stage_cycles.cl"

typedef struct {
  uint v[OPSILA_STAT_COUNT];
#ifdef OPSILA_STAGE_CYCLES
  CycleClock *clock; /* the work-item's, shared by its levels' counts */
#endif
} PrivStats;

/* A work-item's counts into its work-group's, at `level`: one test per
 * counter, written out, none for a work counter in a program that does not
 * count the work (a loop over every counter tested them all, as the
 * compiler cannot see that those stay 0). */
#define ADD_STAT(name, json, sum)                                                            \
  if ((OPSILA_COUNT_WORK || !OPSILA_STAT_WORK_##name) && st->v[OPSILA_STAT_##name] != 0u) \
    atomic_add(&lstats[level * OPSILA_STAT_COUNT + OPSILA_STAT_##name], st->v[OPSILA_STAT_##name]);
inline void add_stats(__local uint *lstats, int level, const PrivStats *st) { OPSILA_STAT_COUNTERS(ADD_STAT) }
#undef ADD_STAT

/* Output records of one work-item: its S places, filled from the front,
 * and the PE x PE traffic of its work-group (local, flushed once). */
typedef struct {
  __global float4 *v; /* the output records and their destinations (DESC_PARAMS) */
  __global int *v_dest;
  int base, count;
  int depth;                   /* the frame's, for the records' sort keys */
  int num_pes, traffic_levels; /* traffic_levels = 0: not counted */
  __local uint *traffic;       /* [level][destination PE] from this work-group's PE */
} Outputs;

inline void emit(Outputs *o, Descriptor d) {
  desc_store(o->v, o->v_dest, o->base + o->count, d, o->depth);
  ++o->count;
  int level = OPSILA_META_LEVEL(DESC_META(d));
  if (level < o->traffic_levels) atomic_inc(&o->traffic[level * o->num_pes + DESC_DEST(d)]);
}

/* This PE's bank, which only it reads. */
typedef struct {
  __global const WalkNode *nodes;
  __global const BankTriangle *tris;
  __global const Instance *insts; /* the instance table, global */
  int pe, root;
  int inst_root; /* its instances' BVH, -1 none */
  bool empty;
  float slack; /* FrameParams.box_slack */
  int tri_base, tri_count; /* this device's facets, global indices (desc_best) */
} Bank;

/* What a ray's visit to this PE ends in. */
#define VISIT_DONE 0  /* finished here (a miss, occluded or lit) */
#define VISIT_SEND 1  /* *next goes on to its destination PE */
#define VISIT_SHADE 2 /* a radiance ray whose nearest hit is a facet of this bank */

/* A shadow ray at this PE: any hit in the bank ends it; otherwise it goes on
 * to the next PE its segment meets in PE order after `after_pe`, skipping
 * its home PE (which spawned it and tested its own bank first), or it is
 * lit. */
inline int shadow_visit(const Routing *rt, const Bank *bank, const RayPre *r, float eps, float tmax, int after_pe,
                        int home, float3 contrib, int pixel, int meta, volatile __global uint *accum, PrivStats *st,
                        const CostProbe *probe, Descriptor *next) {
  bool blocked = false;
  if (!bank->empty)
    STAGE(st->clock, OPSILA_STAGE_BANK_WALK, {
      blocked = traverse_any(r, bank->nodes, bank->tris, bank->insts, bank->root, eps, tmax, bank->slack,
                             &st->v[OPSILA_STAT_TRI_TESTS], &st->v[OPSILA_STAT_BOX_TESTS], probe);
      if (OPSILA_INSTANCES && !blocked && bank->inst_root >= 0)
        blocked = traverse_any(r, bank->nodes, bank->tris, bank->insts, bank->inst_root, eps, tmax, bank->slack,
                               &st->v[OPSILA_STAT_TRI_TESTS], &st->v[OPSILA_STAT_BOX_TESTS], probe);
    });
  if (blocked) {
    STAT_INC(st, OCCLUDED);
    return VISIT_DONE;
  }
  int dest;
  STAGE(st->clock, OPSILA_STAGE_DESTINATION,
        dest = next_shadow_destination(rt, r, eps, tmax, after_pe, home, &st->v[OPSILA_STAT_SPHERE_TESTS],
                                       &st->v[OPSILA_STAT_ROUTE_TESTS]));
  if (dest < 0) {
    STAT_INC(st, LIT);
    STAGE(st->clock, OPSILA_STAGE_PIXEL_SUMS, accumulate(accum, pixel, contrib));
    return VISIT_DONE;
  }
  STAT_INC(st, FORWARD);
  *next = make_descriptor(r->org, tmax, r->dir, 0.0f, contrib, pixel, meta, home, dest);
  return VISIT_SEND;
}

/* A radiance ray at this PE (the cursor of its ordered forwarding: entry
 * cursor_entry here): its nearest hit in the bank, then on to the next PE
 * that may hold a hit before it (hit_order.h), a miss, or to the PE that
 * owns its hit. *best and *hit carry the best hit so far in and out.
 * after: the next PE, when the ray's first destination choice found it
 * (first_destination). */
inline int trace_visit(FrameParams fp, const Routing *rt, const Bank *bank, const RayPre *r, float3 w, int pixel,
                       int meta, float cursor_entry, HitKey *best, int *hit, const NextPe *after,
                       volatile __global uint *accum, PrivStats *st, const CostProbe *probe, Descriptor *next) {
  float eps = fp.epsilon;
  int found = -1; /* local index of a facet of this bank that won */
  if (!bank->empty)
    STAGE(st->clock, OPSILA_STAGE_BANK_WALK, {
      traverse_nearest(r, bank->nodes, bank->tris, bank->insts, bank->root, eps, bank->slack, best, &found,
                       &st->v[OPSILA_STAT_TRI_TESTS], &st->v[OPSILA_STAT_BOX_TESTS], probe);
      if (OPSILA_INSTANCES && bank->inst_root >= 0)
        traverse_nearest(r, bank->nodes, bank->tris, bank->insts, bank->inst_root, eps, bank->slack, best, &found,
                         &st->v[OPSILA_STAT_TRI_TESTS], &st->v[OPSILA_STAT_BOX_TESTS], probe);
    });
  if (found >= 0) *hit = fp.tri_base + found;
  float entry, limit = hit_limit(best->t);
  int dest;
  if (after->known) { /* the same choice, made before (see first_two_destinations_boxes) */
    dest = after->pe >= 0 && after->entry < limit ? after->pe : -1;
    entry = after->entry;
  } else {
    STAGE(st->clock, OPSILA_STAGE_DESTINATION,
          dest = next_destination(rt, r, eps, limit, cursor_entry, bank->pe, &entry,
                                  &st->v[OPSILA_STAT_SPHERE_TESTS], &st->v[OPSILA_STAT_ROUTE_TESTS]));
  }
  if (dest >= 0) { /* a hit before the best may wait in another bank */
    STAT_INC(st, FORWARD);
    *next = make_descriptor(r->org, best->t, r->dir, entry, w, pixel, meta, *hit, dest);
    desc_set_best(next, *best);
    return VISIT_SEND;
  }
  if (*hit < 0) {
    STAT_INC(st, MISS);
    STAGE(st->clock, OPSILA_STAGE_PIXEL_SUMS, accumulate(accum, pixel, w * load3(fp.background)));
    return VISIT_DONE;
  }
  /* An instance's hit is shaded by the instance's PE (the model's copy
   * may lie in another bank of the device: partition/instance_banks.h). */
  int owner = OPSILA_INSTANCES && best->inst >= 0 ? bank->insts[best->inst].pe : owner_pe(rt->pes, fp.num_pes, *hit);
  if (owner == bank->pe) return VISIT_SHADE;
  /* nearest hit known; its facet lives in another bank */
  STAT_INC(st, FORWARD);
  *next = make_descriptor(r->org, best->t, r->dir, 0.0f, w, pixel, OPSILA_META(OPSILA_KIND_RESOLVED,
                                                                               OPSILA_META_LEVEL(meta)), *hit, owner);
  desc_set_best(next, *best); /* an instance's hit is shaded in its frame */
  return VISIT_SEND;
}

/* Whitted shading of a resolved hit at its owner PE: ambient now, a shadow
 * ray per light that can contribute, reflected and transmitted rays for the
 * next level. A new ray is tested in this PE's own bank at once (its origin
 * lies in one of this PE's clusters, so it would be sent here first or
 * soon): only what must leave the bank becomes an output descriptor, one at
 * most per new ray. st counts at `level`, st_child at level + 1. */
inline void shade(FrameParams fp, const Routing *rt, const Bank *bank, __global const Material *materials,
                  __global const Light *lights, SURFACE_PARAMS, float3 org, float3 d, float t, int tri_index,
                  int inst, float3 weight, int pixel, int level, Outputs *out, volatile __global uint *accum, PrivStats *st,
                  PrivStats *st_child, const CostProbe *probe, const CostProbe *probe_child) {
  __global const Material *m = &materials[OPSILA_TRI_MATERIAL(bank->tris[tri_index])];
  SurfacePoint sp = surface_point(fp, bank->tris, bank->insts, tri_index, inst, m, SURFACE_ARGS, org, d, t);
  float3 p = sp.p;
  float eps = fp.epsilon;
  Descriptor next;

  STAGE(st->clock, OPSILA_STAGE_PIXEL_SUMS, accumulate(accum, pixel, weight * load3(fp.ambient) * sp.ka));

  for (int l = 0; l < fp.num_lights; ++l) {
    float3 lv;
    float dist;
    float3 contrib = light_term(m, &lights[l], sp, d, weight, &lv, &dist);
    if (all(contrib == (float3)(0.0f))) continue;
    STAT_INC(st, SPAWN_SHADOW);
    STAT_INC(st, LOCAL);
    RayPre sr = make_ray(p, lv);
    if (shadow_visit(rt, bank, &sr, eps, dist, -1, bank->pe, contrib, pixel, OPSILA_META(OPSILA_KIND_SHADOW, level),
                     accum, st, probe, &next) == VISIT_SEND)
      STAGE(st->clock, OPSILA_STAGE_OUTPUTS, emit(out, next));
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
  int child_meta = OPSILA_META(OPSILA_KIND_TRACE, level + 1);
  for (int j = 0; j < 2; ++j) {
    if (!child_ok[j]) continue;
    STAT_INC(st, SPAWN_RADIANCE);
    RayPre cr = make_ray(p, child_d[j]);
    float entry;
    NextPe after;
    int dest;
    STAGE(st->clock, OPSILA_STAGE_DESTINATION,
          dest = first_destination(rt, &cr, eps, &entry, &after, &st->v[OPSILA_STAT_SPHERE_TESTS],
                                   &st->v[OPSILA_STAT_ROUTE_TESTS]));
    if (dest < 0) { /* meets no box or sphere: a miss, finished here */
      STAGE(st->clock, OPSILA_STAGE_PIXEL_SUMS, accumulate(accum, pixel, child_w[j] * load3(fp.background)));
      STAT_INC(st_child, MISS);
      continue;
    }
    if (dest != bank->pe) {
      STAGE(st->clock, OPSILA_STAGE_OUTPUTS,
            emit(out, make_descriptor(p, OPSILA_INF, child_d[j], entry, child_w[j], pixel, child_meta, -1, dest)));
      continue;
    }
    /* Its first PE is this one: visit it now. A hit here that no other bank
     * can beat is shaded next round, by this PE, like any resolved hit. The
     * visit's next choice is the runner-up of the choice just made. */
    STAT_INC(st_child, LOCAL);
    HitKey best = hit_none();
    int hit = -1;
    int v = trace_visit(fp, rt, bank, &cr, child_w[j], pixel, child_meta, entry, &best, &hit, &after, accum,
                        st_child, probe_child, &next);
    if (v == VISIT_SHADE) {
      STAT_INC(st_child, FORWARD);
      next = make_descriptor(p, best.t, child_d[j], 0.0f, child_w[j], pixel,
                             OPSILA_META(OPSILA_KIND_RESOLVED, level + 1), hit, bank->pe);
      desc_set_best(&next, best);
      v = VISIT_SEND;
    }
    if (v == VISIT_SEND) STAGE(st->clock, OPSILA_STAGE_OUTPUTS, emit(out, next));
  }
}

/* One descriptor at its PE: a shadow ray tests its segment in the bank; a
 * radiance ray looks for its nearest hit here and is sent on, finished as a
 * miss, or (its nearest hit known) shaded by the PE that owns the facet. */
inline void process(FrameParams fp, const Routing *rt, const Bank *bank, __global const Material *materials,
                    __global const Light *lights, SURFACE_PARAMS, Descriptor ds, Outputs *out,
                    volatile __global uint *accum, PrivStats *st, PrivStats *st_child, const CostProbe *probe,
                    const CostProbe *probe_child) {
  float eps = fp.epsilon;
  int meta = DESC_META(ds);
  int kind = OPSILA_META_KIND(meta), level = OPSILA_META_LEVEL(meta);
  int pixel = DESC_PIXEL(ds);
  float3 org = DESC_ORIGIN(ds), d = DESC_DIRECTION(ds), w = DESC_WEIGHT(ds);
  STAT_INC(st, TRACED);
  RayPre r = make_ray(org, d);
  Descriptor next;

  if (kind == OPSILA_KIND_SHADOW) {
    STAT_INC(st, SHADOW);
    if (shadow_visit(rt, bank, &r, eps, DESC_T_MAX(ds), bank->pe, DESC_SHADOW_HOME(ds), w, pixel, meta, accum, st,
                     probe, &next) == VISIT_SEND)
      STAGE(st->clock, OPSILA_STAGE_OUTPUTS, emit(out, next));
    return;
  }
  int hit = DESC_HIT(ds);
  HitKey best;
  desc_best(ds, bank->tris, bank->tri_base, bank->tri_count, &best);
  if (kind == OPSILA_KIND_TRACE) {
    STAT_INC(st, RADIANCE);
    NextPe unknown = {false, -1, OPSILA_INF};
    int v = trace_visit(fp, rt, bank, &r, w, pixel, meta, DESC_CURSOR_ENTRY(ds), &best, &hit, &unknown, accum, st,
                        probe, &next);
    if (v == VISIT_SEND) STAGE(st->clock, OPSILA_STAGE_OUTPUTS, emit(out, next));
    if (v != VISIT_SHADE) return;
  }
  STAT_INC(st, RESOLVED);
  STAGE(st->clock, OPSILA_STAGE_SHADING,
        shade(fp, rt, bank, materials, lights, SURFACE_ARGS, org, d, best.t, hit - fp.tri_base, best.inst, w, pixel,
              level, out,
              accum, st, st_child, probe, probe_child));
}

/* PE pe's bank, on this device (its facets: fp.tri_base on); through a
 * pointer, as desc_load (a returned struct: descriptor.cl). */
inline void own_bank(FrameParams fp, __global const PeInfo *pes, __global const WalkNode *nodes,
                     __global const BankTriangle *tris, __global const Instance *insts, int pe, Bank *bank) {
  int tri_end = pes[fp.group_end - 1].tri_end;
  Bank b = {nodes, tris, insts, pe, pes[pe].node_begin, pes[pe].instance_root,
            pes[pe].node_begin == pes[pe].node_end, fp.box_slack, fp.tri_base, tri_end - fp.tri_base};
  *bank = b;
}

/* A work-group's statistics and traffic, after its barrier, to the frame's
 * counters: once a work-group, not once a descriptor. */
inline void flush_group_counts(__local const uint *lstats, __local const uint *ltraffic, int depth, int ntraffic,
                               int P, int pe, volatile __global uint *stats, volatile __global uint *traffic) {
  int lid = get_local_id(0), lsz = get_local_size(0);
  for (int i = lid; i < depth * OPSILA_STAT_COUNT; i += lsz) {
    uint v = lstats[i];
    if (v != 0u) count_stat(stats, P, i / OPSILA_STAT_COUNT, pe, i % OPSILA_STAT_COUNT, v);
  }
  for (int i = lid; i < ntraffic; i += lsz) count_add(traffic, ((long)(i / P) * P + pe) * P + i % P, ltraffic[i]);
}

__kernel void spmd_phase(FrameParams fp, __global const PeInfo *pes, __global const Cluster *clusters,
                         __global const BankNode *route, int routing, __global const WalkNode *nodes,
                         __global const BankTriangle *tris, __global const Instance *insts,
                         __global const Material *materials, __global const Light *lights, SURFACE_PARAMS,
                         DESC_PARAMS(b), __global const int *group_pe, __global const int *group_first,
                         __global const int *bank_begin, __global const int *bank_count, DESC_PARAMS(o),
                         __global int *out_item_count, volatile __global uint *accum, volatile __global uint *stats,
                         volatile __global uint *traffic, int traffic_levels, __global const int *node_cluster,
                         __global const int *tri_cluster, volatile __global uint *cost, int spmd_groups,
                         __global const int *hit_pixels, __global const int *item_tri, __global const float *item_t,
                         __global const int2 *item_key, int prim_first, int prim_count, float prim_ox,
                         float prim_oy, int prim_offset, DESC_PARAMS(pool), volatile __global uint *hit_count) {
  __local uint lstats[OPSILA_MAX_DEPTH * OPSILA_STAT_COUNT];
  __local uint ltraffic[OPSILA_MAX_DEPTH * OPSILA_TRAFFIC_MAX_PES];
  int g = get_group_id(0), lid = get_local_id(0), lsz = get_local_size(0);
  int builders = get_num_groups(0) - spmd_groups;
  if (g < builders) {
    PrimaryBuild pb = {hit_pixels, item_tri, item_t, item_key, prim_first, prim_count, prim_ox, prim_oy, prim_offset};
    build_primary_ahead(fp, pes, insts, &pb, g, pool, pool_dest, hit_count);
    return;
  }
  g -= builders; /* the phase's work-group */
  int P = fp.num_pes, depth = fp.max_depth;
  int ntraffic = traffic_levels * P;
  for (int i = lid; i < depth * OPSILA_STAT_COUNT; i += lsz) lstats[i] = 0u;
  for (int i = lid; i < ntraffic; i += lsz) ltraffic[i] = 0u;
  barrier(CLK_LOCAL_MEM_FENCE);
#ifdef OPSILA_STAGE_CYCLES
  /* The breakdown frame's program: `cost` holds the stage counters. */
  CycleClock clock;
  stage_clear(&clock);
  stage_start(&clock, OPSILA_STAGE_BODY);
#endif

  int pe = group_pe[g];
  int slot = group_first[g] + lid;
  int item = g * lsz + lid;
  Outputs out = {o, o_dest, item * fp.spawn_slots, 0, depth, P, traffic_levels, ltraffic};
  Routing rt = {pes, clusters, route, P, routing};
  Bank bank;
  own_bank(fp, pes, nodes, tris, insts, pe, &bank);
  if (slot < bank_begin[pe] + bank_count[pe]) {
    Descriptor ds;
    desc_load(b, slot, &ds);
    int level = OPSILA_META_LEVEL(DESC_META(ds));
    PrivStats st, st_child;
    for (int s = 0; s < OPSILA_STAT_COUNT; ++s) st.v[s] = st_child.v[s] = 0u;
#ifdef OPSILA_STAGE_CYCLES
    st.clock = st_child.clock = &clock;
#endif
    CostProbe probe = no_cost_probe(), probe_child = no_cost_probe();
#ifdef OPSILA_MEASURE_COST
    probe.node_cluster = probe_child.node_cluster = node_cluster;
    probe.tri_cluster = probe_child.tri_cluster = tri_cluster;
    probe.cost = cost + (long)level * fp.num_clusters;
    probe_child.cost = level + 1 < depth ? probe.cost + fp.num_clusters : 0;
#endif
    process(fp, &rt, &bank, materials, lights, SURFACE_ARGS, ds, &out, accum, &st, &st_child, &probe, &probe_child);
    STAGE(st.clock, OPSILA_STAGE_STATISTICS, {
      add_stats(lstats, level, &st);
      /* Children traced or finished here count at their own level. */
      if (level + 1 < depth) add_stats(lstats, level + 1, &st_child);
    });
  }
  out_item_count[item] = out.count;
#ifdef OPSILA_STAGE_CYCLES
  stage_enter(&clock, OPSILA_STAGE_BODY); /* stopped at the barrier */
#endif
  barrier(CLK_LOCAL_MEM_FENCE);
#ifdef OPSILA_STAGE_CYCLES
  stage_start(&clock, OPSILA_STAGE_STATISTICS);
#endif
  flush_group_counts(lstats, ltraffic, depth, ntraffic, P, pe, stats, traffic);
#ifdef OPSILA_STAGE_CYCLES
  stage_enter(&clock, OPSILA_STAGE_BODY);
  stage_flush(&clock, cost);
#endif
}
