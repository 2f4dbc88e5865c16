/* Stage clocks (OPSILA_STAGES, kernels/opsila_shared.h): a work-item's
 * cycles per stage, read from the processor's time-stamp counter. Only a
 * program built with OPSILA_STAGE_CYCLES counts them: the bench's breakdown
 * frame, on an x86 CPU device, where a work-item runs on one core from its
 * start to its end between two barriers. Every other program compiles
 * STAGE(clock, stage, statement) to the statement alone (a variadic
 * macro: the statement may hold commas).
 *
 * A clock charges the cycles since its last reading to the stage it is in;
 * STAGE enters a stage for one statement and returns to the one it was in,
 * so a stage entered inside another (a walk inside shading) is charged to
 * itself only. Reading the clock costs cycles of its own, charged to the
 * stage entered: every entry is counted too, so that the host can take that
 * cost out (stage_times, host/bench/report.cpp). A clock must be stopped before a barrier and started after:
 * a device that runs a work-group's items one after the other between
 * barriers would otherwise charge one item with the others' time. */
#ifdef OPSILA_STAGE_CYCLES
typedef struct {
  ulong last;
  int stage;
  ulong cycles[OPSILA_STAGE_COUNT];
  uint entries[OPSILA_STAGE_COUNT]; /* clock readings that entered each stage */
} CycleClock;

inline ulong stage_now(void) {
  uint lo, hi;
  __asm__ volatile("rdtsc" : "=a"(lo), "=d"(hi));
  return ((ulong)hi << 32) | lo;
}

inline void stage_clear(CycleClock *c) {
  for (int s = 0; s < OPSILA_STAGE_COUNT; ++s) {
    c->cycles[s] = 0ul;
    c->entries[s] = 0u;
  }
}

inline void stage_start(CycleClock *c, int stage) {
  c->stage = stage;
  ++c->entries[stage];
  c->last = stage_now();
}

/* Charges the cycles so far to the current stage; enters `stage`; returns the one left. */
inline int stage_enter(CycleClock *c, int stage) {
  ulong now = stage_now();
  c->cycles[c->stage] += now - c->last;
  c->last = now;
  int left = c->stage;
  c->stage = stage;
  ++c->entries[stage];
  return left;
}

/* The cycles, then the entries, into the frame's OPSILA_STAGE_COUNTERS
 * 64-bit counters (OPSILA_COUNTER_WORDS words each), added as the pixel
 * sums are: order-independent. */
inline void stage_flush(const CycleClock *c, volatile __global uint *out) {
  for (int s = 0; s < OPSILA_STAGE_COUNT; ++s) {
    if (c->cycles[s] != 0ul) add_fixed(&out[s * OPSILA_COUNTER_WORDS], (long)c->cycles[s]);
    if (c->entries[s] != 0u) add_fixed(&out[(OPSILA_STAGE_COUNT + s) * OPSILA_COUNTER_WORDS], (long)c->entries[s]);
  }
}

#define STAGE(clock, stage, ...)                     \
  do {                                               \
    int stage_left_ = stage_enter((clock), (stage)); \
    __VA_ARGS__;                                     \
    stage_enter((clock), stage_left_);               \
  } while (0)
#else
#define STAGE(clock, stage, ...) \
  do {                           \
    __VA_ARGS__;                 \
  } while (0)
#endif
