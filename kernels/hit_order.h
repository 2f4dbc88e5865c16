/* opsila: the nearest-hit order, declared once for the kernels (OpenCL C)
 * and the host (C++17: the reference tracer, the ray sample, the tests).
 * docs/CONTRACT.md "Nearest hit" states the rule; this is its only code.
 *
 * A hit's key is (distance on the grid, instance, facet id, fan triangle),
 * compared key by key: a strict total order, so the least hit of a ray is
 * the same whatever order its hits are found in (any PE count, rank count,
 * balance, bank BVH, visit order). It is CONTRACT's (distance, object id, facet
 * id, fan): the scene's own facets have instance -1 and facet ids unique
 * over the scene that never decrease as object ids increase (checked when
 * the banks are built, host/partition/partition.cpp), so the facet id
 * orders them by object id first; instance i (a model placed by a scene
 * file) is object num_objects + i, after every facet of the scene's own,
 * and its facets carry the model's own facet ids.
 *
 * The grid: a distance's float bits with the OPSILA_HIT_GRID_BITS lowest
 * mantissa bits cleared. Positive floats order as their bits do, so the
 * grid is monotonic, and two distances that differ by float noise alone
 * (coplanar facets, a polygon's shared fan edges) usually share a cell and
 * are told apart by ids, not by rounding. 0 bits: exact distances. */
#ifndef OPSILA_HIT_ORDER_H
#define OPSILA_HIT_ORDER_H

#ifdef __OPENCL_C_VERSION__
typedef uint hit_bits_t;
inline hit_bits_t hit_float_bits(float t) { return as_uint(t); }
inline float hit_bits_float(hit_bits_t b) { return as_float(b); }
#else
#include <cmath>
#include <cstdint>
#include <cstring>
typedef std::uint32_t hit_bits_t;
inline hit_bits_t hit_float_bits(float t) {
  hit_bits_t b;
  std::memcpy(&b, &t, sizeof b);
  return b;
}
inline float hit_bits_float(hit_bits_t b) {
  float t;
  std::memcpy(&t, &b, sizeof t);
  return t;
}
#endif
#define OPSILA_HIT_INF INFINITY

/* Mantissa bits cleared: cells of 16 ulps, a relative width between 2^-20
 * and 2^-19, the scale of the watertight test's rounding on coplanar
 * facets (a -D define, so a build can try others: 0 is exact distances). */
#ifndef OPSILA_HIT_GRID_BITS
#define OPSILA_HIT_GRID_BITS 4
#endif
#define OPSILA_HIT_GRID_MASK ((hit_bits_t)((1u << OPSILA_HIT_GRID_BITS) - 1u))
#define OPSILA_HIT_INF_BITS ((hit_bits_t)0x7f800000u)

/* Box culling's relative slack: a box is culled only when it is entered
 * beyond x + |x| * OPSILA_CULL_SLACK (+ an absolute slack), x the end of
 * the best hit's grid cell, so that the slab test's rounding never culls
 * a box whose facet would win (bank walks, routing, the reference). */
#define OPSILA_CULL_SLACK 4e-6f

/* A hit as the order sees it; the least is the nearest hit. No hit:
 * hit_none() (infinite distance, greatest ids). */
typedef struct {
  float t;
  int inst;  /* the instance hit, -1: a facet of the scene's own */
  int facet; /* CONTRACT facet id (an instance's: its model's) */
  int fan;   /* the triangle's index in its facet's fan, 0 first */
} HitKey;

#ifdef __OPENCL_C_VERSION__
/* Made in place (a compound literal), never returned by a function: a
 * returned 16-byte struct is a no-alias result pointer, and LLVM marks
 * where such a function was inlined with llvm.experimental.noalias.scope.decl,
 * which some OpenCL implementations (Oclgrind 21.10) cannot load. Kernel
 * code fills a HitKey through a pointer for the same reason. */
#define hit_key(t, inst, facet, fan) ((HitKey){(t), (inst), (facet), (fan)})
#else
inline HitKey hit_key(float t, int inst, int facet, int fan) {
  HitKey k;
  k.t = t;
  k.inst = inst;
  k.facet = facet;
  k.fan = fan;
  return k;
}
#endif
#define hit_none() hit_key(OPSILA_HIT_INF, 0x7fffffff, 0x7fffffff, 0x7fffffff)

/* The distance's cell (t >= 0, or +inf). */
inline hit_bits_t hit_grid(float t) { return hit_float_bits(t) & ~OPSILA_HIT_GRID_MASK; }

/* The order in two steps, for a caller that reads the ids only when the
 * cells are equal (a walk's leaf): the first key, then the others. */
inline bool hit_cell_before(float t, HitKey best) { return hit_grid(t) < hit_grid(best.t); }
inline bool hit_cell_same(float t, HitKey best) { return hit_grid(t) == hit_grid(best.t); }
inline bool hit_ids_before(int inst, int facet, int fan, HitKey best) {
  if (inst != best.inst) return inst < best.inst;
  return facet != best.facet ? facet < best.facet : fan < best.fan;
}

/* Whether a hit (t, inst, facet, fan) comes before `best` in the order. */
inline bool hit_before(float t, int inst, int facet, int fan, HitKey best) {
  return hit_cell_before(t, best) || (hit_cell_same(t, best) && hit_ids_before(inst, facet, fan, best));
}

/* The least distance whose cell lies after best_t's: a hit at or beyond it
 * cannot come before the best; INFINITY when there is no best. */
inline float hit_limit(float best_t) {
  hit_bits_t b = hit_float_bits(best_t);
  if (b >= OPSILA_HIT_INF_BITS) return OPSILA_HIT_INF;
  return hit_bits_float((b | OPSILA_HIT_GRID_MASK) + 1u);
}

/* A box's exit distance widened by the culling slack (relative) and
 * `slack` (absolute): the box may hold a winner while its entry is not
 * beyond it. */
inline float cull_exit(float leave, float slack) {
  return leave + (leave < 0.0f ? -leave : leave) * OPSILA_CULL_SLACK + slack;
}

#endif /* OPSILA_HIT_ORDER_H */
