/* Fixed-point pixel and statistics accumulation. */
#include "../opsila_shared.h"

/* traced: the pixels the item buffer traced (x0, y0, x1, y1); a pixel
 * outside them is a miss, whatever its item_tri holds. */
inline bool was_traced(int pixel, int width, int4 traced) {
  int x = pixel % width, y = pixel / width;
  return x >= traced.x && x <= traced.z && y >= traced.y && y <= traced.w;
}

/* 64-bit fixed-point add from two 32-bit atomics: the carry out of the low
 * word goes to the high word. Integer sums are order-independent, so the
 * image is identical however the work-items are scheduled.
 * Saturation: values are >= 0 and < 2^63 (every term of CONTRACT's pixel sum
 * is >= 0, and fixed3 saturates), so a sum reaching 2^63 sets bit 31 of
 * the high word; an add that carries out of the high word sets it again
 * (atomic_or), and adds that do not carry out cannot clear it. So bit 31 is
 * set at the end exactly when the true sum is >= 2^63, whatever the order:
 * the host then reads the largest value (from_fixed), never a wrapped one. */
inline void add_fixed(volatile __global uint *cell, long value) {
  uint lo = (uint)value;
  uint hi = (uint)(value >> 32);
  uint old = atomic_add(&cell[0], lo);
  if (old + lo < old) hi += 1u;
  if (hi == 0u) return;
  uint old_hi = atomic_add(&cell[1], hi);
  if (old_hi + hi < old_hi) atomic_or(&cell[1], 0x80000000u);
}

/* A contribution in fixed point: round to nearest even, saturating (the host
 * mirror is to_fixed in host/core/fixed_point.h). A NaN (an infinite weight
 * times a zero channel: colours are finite but unbounded) is 0, as OpenCL
 * says and to_fixed does; Rusticl's built-in gives LONG_MIN, hence the mask. */
inline long3 fixed3(float3 value) {
  float3 s = value * OPSILA_FIXED_SCALE;
  /* Below 2^62 in magnitude (a NaN is not) the conversion cannot saturate:
   * rint then the plain conversion give the same bits without the built-in's
   * range and NaN handling, which costs about as much as the rest of an add. */
  if (all(fabs(s) < 0x1p62f)) return convert_long3(rint(s));
  return convert_long3_sat_rte(s) & convert_long3(s == s);
}

/* add_fixed where no other work-item adds to `cell` during the launch (the
 * queue runs launches in order): one 64-bit read and write, no atomics, the
 * same sum and the same saturation bit. */
inline void add_fixed_owned(volatile __global uint *cell, long value) {
  ulong old = ((ulong)cell[1] << 32) | (ulong)cell[0];
  ulong sum = old + (ulong)value;
  uint hi = (uint)(sum >> 32);
  if (sum < old) hi |= 0x80000000u; /* carried out of the high word */
  cell[0] = (uint)sum;
  cell[1] = hi;
}

/* accumulate() into a pixel that no other work-item adds to during the launch. */
inline void add_fixed3_owned(volatile __global uint *accum, int pixel, long3 q) {
  add_fixed_owned(&accum[pixel * OPSILA_ACCUM_WORDS + 0], q.x);
  add_fixed_owned(&accum[pixel * OPSILA_ACCUM_WORDS + 2], q.y);
  add_fixed_owned(&accum[pixel * OPSILA_ACCUM_WORDS + 4], q.z);
}

inline void accumulate_owned(volatile __global uint *accum, int pixel, float3 value) {
  add_fixed3_owned(accum, pixel, fixed3(value));
}

/* A pixel's three sums set to q (each >= 0): what accumulate_owned of the
 * value q came from leaves in cleared sums. */
inline void store_fixed3(volatile __global uint *accum, int pixel, long3 q) {
  __global uint *at = (__global uint *)&accum[pixel * OPSILA_ACCUM_WORDS];
  at[0] = (uint)q.x, at[1] = (uint)(q.x >> 32);
  at[2] = (uint)q.y, at[3] = (uint)(q.y >> 32);
  at[4] = (uint)q.z, at[5] = (uint)(q.z >> 32);
}

inline void accumulate(volatile __global uint *accum, int pixel, float3 value) {
  long3 q = fixed3(value);
  if (q.x != 0) add_fixed(&accum[pixel * OPSILA_ACCUM_WORDS + 0], q.x);
  if (q.y != 0) add_fixed(&accum[pixel * OPSILA_ACCUM_WORDS + 2], q.y);
  if (q.z != 0) add_fixed(&accum[pixel * OPSILA_ACCUM_WORDS + 4], q.z);
}

/* Counter `index` of a 64-bit counter array (OPSILA_COUNTER_WORDS words
 * each): statistics, PE x PE traffic, primary hits. */
inline void count_add(volatile __global uint *counters, long index, uint amount) {
  if (amount != 0u) add_fixed(&counters[index * OPSILA_COUNTER_WORDS], (long)amount);
}

/* One more of counter NAME in a work-item's counts (PrivStats-like: a
 * member v[OPSILA_STAT_COUNT]); nothing for a work counter in a program
 * that does not count the work (OPSILA_COUNT_WORK). */
#define STAT_INC(st, NAME)                                                      \
  do {                                                                          \
    if (OPSILA_COUNT_WORK || !OPSILA_STAT_WORK_##NAME) ++(st)->v[OPSILA_STAT_##NAME]; \
  } while (0)

inline void count_stat(volatile __global uint *stats, int num_pes, int level, int pe, int which, uint amount) {
  count_add(stats, ((long)level * num_pes + pe) * OPSILA_STAT_COUNT + which, amount);
}
