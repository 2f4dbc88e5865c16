// The host side of the device's counters, from their one declaration in
// kernels/opsila_shared.h (OPSILA_STAT_COUNTERS, OPSILA_COUNTER_WORDS): the
// statistics' --stats names, the sums every reader of them takes, and the
// read-back of the 64-bit counter arrays (statistics, PE x PE traffic,
// primary hits) the kernels write.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "device/cl_runtime.h"
#include "opsila_shared.h"

namespace opsila {

// --stats name of OPSILA_STAT_* counter `index`.
const char* stat_name(int index);
// JSON name of OPSILA_STAGE_* stage `index` (the stage cycles, kernels/lib/stage_cycles.cl).
const char* stage_name(int index);

// What the counters of one (level, PE), or a sum of them, add up to:
// descriptors spawned there (children and shadow rays; the primary ones
// are counted by the item buffer's hits) and descriptors that finished
// there (shaded hits, misses, occluded and lit shadow rays).
struct CounterSums {
  std::uint64_t spawned = 0, finished = 0;
};
CounterSums counter_sums(const std::uint64_t* values);  // OPSILA_STAT_COUNT values
// The same over every (level, PE) of a flat [level][pe][counter] array.
CounterSums counter_sums(const std::vector<std::uint64_t>& flat);

// Device bytes of `count` 64-bit counters.
constexpr std::size_t counter_bytes(std::size_t count) {
  return count * OPSILA_COUNTER_WORDS * sizeof(std::uint32_t);
}

// The first `count` counters of a device counter array (a blocking read).
std::vector<std::uint64_t> read_counters(ClRuntime& rt, const cl::Buffer& b, std::size_t count, const char* what);

// Pairs of 32-bit words (low, high) as the kernels add them (add_fixed),
// joined: counters and pixel sums alike.
std::vector<std::uint64_t> join_word_pairs(const std::vector<std::uint32_t>& words);

}  // namespace opsila
