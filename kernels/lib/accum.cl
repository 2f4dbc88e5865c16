/* Fixed-point pixel and statistics accumulation. */
#include "opsila_shared.h"

/* 64-bit fixed-point add from two 32-bit atomics: the carry out of the low
 * word goes to the high word. Integer sums are order-independent, so the
 * image is identical however the work-items are scheduled. */
inline void add_fixed(volatile __global uint *cell, long value) {
  uint lo = (uint)value;
  uint hi = (uint)(value >> 32);
  uint old = atomic_add(&cell[0], lo);
  if (old + lo < old) hi += 1u;
  if (hi != 0u) atomic_add(&cell[1], hi);
}

/* A contribution in fixed point: round to nearest even, saturating (the host
 * mirror is to_fixed in host/core/fixed_point.h). */
inline long3 fixed3(float3 value) { return convert_long3_sat_rte(value * OPSILA_FIXED_SCALE); }

inline void accumulate(volatile __global uint *accum, int pixel, float3 value) {
  long3 q = fixed3(value);
  if (q.x != 0) add_fixed(&accum[pixel * OPSILA_ACCUM_WORDS + 0], q.x);
  if (q.y != 0) add_fixed(&accum[pixel * OPSILA_ACCUM_WORDS + 2], q.y);
  if (q.z != 0) add_fixed(&accum[pixel * OPSILA_ACCUM_WORDS + 4], q.z);
}

inline void count_stat(volatile __global uint *stats, int num_pes, int level, int pe, int which, uint amount) {
  if (amount != 0u) add_fixed(&stats[((level * num_pes + pe) * OPSILA_STAT_COUNT + which) * 2], (long)amount);
}
