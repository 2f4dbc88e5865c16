/* Ray descriptors as the kernels see them: a vector of 64-byte records,
 * generated from the field table OPSILA_DESCRIPTOR_LANES (opsila_shared.h). */
#include "../opsila_shared.h"
#include "../hit_order.h"

#define DESC_MEMBER(lane, name, type, host_type) type name;
typedef struct {
  OPSILA_DESCRIPTOR_LANES(DESC_MEMBER)
} Descriptor;

/* A descriptor vector as a kernel parameter: record k is lanes 4k .. 4k+3,
 * and p_dest[k] holds record k's sort key (its destination PE, DESC_DEST,
 * and whether it can still spawn radiance rays: OPSILA_STREAM_KEY) in a
 * dense stream, so that the exchange's count reads 4 bytes per descriptor,
 * not the record's whole 64-byte line. Whoever writes a record writes both,
 * except the exchange's move into a bank (see desc_move_record). */
#define DESC_PARAMS(p) __global float4 *p, __global int *p##_dest

/* Record k into *d. Filled through a pointer, not returned: a returned
 * struct is a no-alias result pointer, and LLVM marks where such a call
 * was inlined with llvm.experimental.noalias.scope.decl, an intrinsic
 * some OpenCL implementations (Oclgrind 21.10) cannot load. */
#define DESC_LOAD_LANE(lane, name, type, host_type) d->name = as_##type(v[at + lane]);
inline void desc_load(__global const float4 *v, int k, Descriptor *d) {
  long at = (long)k * OPSILA_DESCRIPTOR_LANE_COUNT;
  OPSILA_DESCRIPTOR_LANES(DESC_LOAD_LANE)
}

#define DESC_STORE_LANE(lane, name, type, host_type) v[at + lane] = as_float4(d.name);
/* depth: the frame's (FrameParams.max_depth), for the sort key. */
inline void desc_store(__global float4 *v, __global int *v_dest, int k, Descriptor d, int depth) {
  long at = (long)k * OPSILA_DESCRIPTOR_LANE_COUNT;
  OPSILA_DESCRIPTOR_LANES(DESC_STORE_LANE)
  v_dest[k] = OPSILA_STREAM_KEY(d.ids.w, d.ids.y, depth);
}

/* The exchange's move: one record, lane by lane, untouched, and its
 * sort key with it; into a bank, the record alone (every slot of a bank
 * belongs to its PE, and the SPMD phase reads only records). */
inline void desc_move_record(__global float4 *to, int j, __global const float4 *from, int k) {
  long a = (long)j * OPSILA_DESCRIPTOR_LANE_COUNT, b = (long)k * OPSILA_DESCRIPTOR_LANE_COUNT;
  for (int lane = 0; lane < OPSILA_DESCRIPTOR_LANE_COUNT; ++lane) to[a + lane] = from[b + lane];
}
inline void desc_move(__global float4 *to, __global int *to_dest, int j, __global const float4 *from,
                      __global const int *from_dest, int k) {
  desc_move_record(to, j, from, k);
  to_dest[j] = from_dest[k];
}

/* Named slots (see the field table for every overloaded one). */
#define DESC_ORIGIN(d) ((d).org.xyz)
#define DESC_T_BEST(d) ((d).org.w)       /* radiance: best hit distance so far */
#define DESC_T_MAX(d) ((d).org.w)        /* shadow: distance to the light */
#define DESC_DIRECTION(d) ((d).dir.xyz)
#define DESC_CURSOR_ENTRY(d) ((d).dir.w) /* entry distance of the cursor PE */
#define DESC_WEIGHT(d) ((d).wgt.xyz)     /* weight product or light contribution */
#define DESC_PIXEL(d) ((d).ids.x)
#define DESC_META(d) ((d).ids.y)
#define DESC_HIT(d) ((d).ids.z)          /* global triangle of the best hit, -1 none */
#define DESC_SHADOW_HOME(d) ((d).ids.z)  /* shadow: the PE that spawned it (and tested its bank first) */
#define DESC_DEST(d) ((d).ids.w)         /* destination PE = cursor PE; -1 NIL */
/* Radiance: facet id of the best hit (its bits), or its instance when the
 * meta field says so (OPSILA_META_INSTANCE); with the fan index in the
 * meta field and the distance, the best hit's key (hit_order.h) for the
 * next PE, whose device may not hold that facet. */
#define DESC_BEST_FACET(d) ((d).wgt.w)

inline Descriptor make_descriptor(float3 origin, float t, float3 direction, float entry, float3 weight, int pixel,
                                  int meta, int hit, int dest) {
  Descriptor d;
  d.org = (float4)(origin, t);
  d.dir = (float4)(direction, entry);
  d.wgt = (float4)(weight, 0.0f);
  d.ids = (int4)(pixel, meta, hit, dest);
  return d;
}

/* The facet id of the facet at global index `hit` when this device holds
 * it (its facets: global tri_base .. tri_base + tri_count - 1), else 0. An
 * instance's best hit carries no facet id (OPSILA_META_INSTANCE): only the
 * device holding the instance can find another hit on it, and reads it. */
inline int held_facet_id(__global const BankTriangle *tris, int tri_base, int tri_count, int hit) {
  int k = hit - tri_base;
  return k >= 0 && k < tri_count ? tris[k].facet_id : 0;
}

/* A radiance descriptor's best hit so far: (DESC_T_BEST, its instance,
 * facet and fan), or none while DESC_HIT is -1 (through a pointer:
 * hit_order.h, hit_key). */
inline void desc_best(Descriptor d, __global const BankTriangle *tris, int tri_base, int tri_count, HitKey *best) {
  int meta = DESC_META(d), fan = OPSILA_META_FAN(meta);
  if (DESC_HIT(d) < 0)
    *best = hit_none();
  else if (meta & OPSILA_META_INSTANCE)
    *best = hit_key(DESC_T_BEST(d), as_int(DESC_BEST_FACET(d)),
                    held_facet_id(tris, tri_base, tri_count, DESC_HIT(d)), fan);
  else
    *best = hit_key(DESC_T_BEST(d), -1, as_int(DESC_BEST_FACET(d)), fan);
}
inline void desc_set_best(Descriptor *d, HitKey best) {
  DESC_T_BEST(*d) = best.t;
  DESC_BEST_FACET(*d) = as_float(best.inst >= 0 ? best.inst : best.facet);
  DESC_META(*d) = OPSILA_META_WITH_FAN(DESC_META(*d), best.fan) | (best.inst >= 0 ? OPSILA_META_INSTANCE : 0);
}
