/* Fixed-point pixel and statistics accumulation. */
#include "../opsila_shared.h"

/* 64-bit fixed-point add from two 32-bit atomics: the carry out of the low
 * word goes to the high word. Integer sums are order-independent, so the
 * image is identical however the work-items are scheduled.
 * Saturation: values are >= 0 and at most 2^63 read as unsigned (every
 * term of SPEC's pixel sum is >= 0, fixed3 saturates below 2^63, and
 * pixel_add stops at 2^63), so a sum reaching 2^63 sets bit 31 of
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
 * mirror is to_fixed in host/core/fixed_point.h). */
inline long3 fixed3(float3 value) { return convert_long3_sat_rte(value * OPSILA_FIXED_SCALE); }

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

/* A contribution added into a pixel that no other work-item adds to during
 * the launch (the primary descriptors' misses). */
inline void accumulate_owned(volatile __global uint *accum, int pixel, float3 value) {
  long3 q = fixed3(value);
  add_fixed_owned(&accum[pixel * OPSILA_ACCUM_WORDS + 0], q.x);
  add_fixed_owned(&accum[pixel * OPSILA_ACCUM_WORDS + 2], q.y);
  add_fixed_owned(&accum[pixel * OPSILA_ACCUM_WORDS + 4], q.z);
}

/* What one work-item adds to one pixel, summed in private and added into
 * the pixel's sums once (pixel_flush): the SPMD phase's descriptor adds its
 * ambient term, its lit shadow rays and its children's misses to its own
 * pixel, one to three atomics a channel each time before. Each contribution
 * is quantised on its own (fixed3), and the private sum stops at
 * 2^63: below that the pixel's sum is the same integer (addition modulo 2^64
 * is order-free), and a true sum at or above 2^63 still sets the
 * saturation bit (add_fixed of 2^63 adds bit 31 to the high word, or
 * carries out of it), which is all the host reads of a saturated sum. */
typedef struct {
  ulong3 sum;
} PixelSum;

inline PixelSum pixel_sum_zero(void) {
  PixelSum ps;
  ps.sum = (ulong3)(0ul);
  return ps;
}

inline void pixel_add(PixelSum *ps, float3 value) {
  const ulong3 cap = (ulong3)(0x8000000000000000ul); /* 2^63; each term is below it */
  ps->sum = min(ps->sum + convert_ulong3(fixed3(value)), cap);
}

inline void pixel_flush(volatile __global uint *accum, int pixel, const PixelSum *ps) {
  if (ps->sum.x != 0ul) add_fixed(&accum[pixel * OPSILA_ACCUM_WORDS + 0], (long)ps->sum.x);
  if (ps->sum.y != 0ul) add_fixed(&accum[pixel * OPSILA_ACCUM_WORDS + 2], (long)ps->sum.y);
  if (ps->sum.z != 0ul) add_fixed(&accum[pixel * OPSILA_ACCUM_WORDS + 4], (long)ps->sum.z);
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
