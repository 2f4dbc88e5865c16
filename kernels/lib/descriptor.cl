/* Ray descriptors as the kernels see them: a vector of 64-byte records,
 * generated from the field table OPSILA_DESCRIPTOR_LANES (opsila_shared.h). */
#include "opsila_shared.h"

#define DESC_MEMBER(lane, name, type, host_type) type name;
typedef struct {
  OPSILA_DESCRIPTOR_LANES(DESC_MEMBER)
} Descriptor;

/* A descriptor vector as a kernel parameter: record k is lanes 4k .. 4k+3. */
#define DESC_PARAMS(p) __global float4 *p

#define DESC_LOAD_LANE(lane, name, type, host_type) d.name = as_##type(v[at + lane]);
inline Descriptor desc_load(__global const float4 *v, int k) {
  Descriptor d;
  long at = (long)k * OPSILA_DESCRIPTOR_LANE_COUNT;
  OPSILA_DESCRIPTOR_LANES(DESC_LOAD_LANE)
  return d;
}

#define DESC_STORE_LANE(lane, name, type, host_type) v[at + lane] = as_float4(d.name);
inline void desc_store(__global float4 *v, int k, Descriptor d) {
  long at = (long)k * OPSILA_DESCRIPTOR_LANE_COUNT;
  OPSILA_DESCRIPTOR_LANES(DESC_STORE_LANE)
}

/* The exchange's move: one record, lane by lane, untouched. */
inline void desc_move(__global float4 *to, int j, __global const float4 *from, int k) {
  long a = (long)j * OPSILA_DESCRIPTOR_LANE_COUNT, b = (long)k * OPSILA_DESCRIPTOR_LANE_COUNT;
  for (int lane = 0; lane < OPSILA_DESCRIPTOR_LANE_COUNT; ++lane) to[a + lane] = from[b + lane];
}

/* Destination PE of record k, reading only its ids lane. */
inline int desc_dest_at(__global const float4 *v, int k) {
  return as_int4(v[(long)k * OPSILA_DESCRIPTOR_LANE_COUNT + 3]).w;
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
#define DESC_DEST(d) ((d).ids.w)         /* destination PE = cursor PE; -1 NIL */
/* Radiance: facet id of the best hit (its bits), for the tie rule at the
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
