#include "device/counters.h"

#include <string>

#include "core/fixed_point.h"

namespace opsila {

namespace {

#define OPSILA_STAT_NAME(name, json, sum) json,
const char* const kStatNames[] = {OPSILA_STAT_COUNTERS(OPSILA_STAT_NAME)};
#undef OPSILA_STAT_NAME
static_assert(sizeof(kStatNames) / sizeof(kStatNames[0]) == OPSILA_STAT_COUNT, "one name per counter");

#define OPSILA_STAGE_NAME(name, json) json,
const char* const kStageNames[] = {OPSILA_STAGES(OPSILA_STAGE_NAME)};
#undef OPSILA_STAGE_NAME
static_assert(sizeof(kStageNames) / sizeof(kStageNames[0]) == OPSILA_STAGE_COUNT, "one name per stage");

enum class Sum { NONE, SPAWNED, FINISHED };
#define OPSILA_STAT_SUM(name, json, sum) Sum::sum,
const Sum kStatSums[] = {OPSILA_STAT_COUNTERS(OPSILA_STAT_SUM)};
#undef OPSILA_STAT_SUM

}  // namespace

const char* stat_name(int index) { return index >= 0 && index < OPSILA_STAT_COUNT ? kStatNames[index] : "?"; }

const char* stage_name(int index) { return index >= 0 && index < OPSILA_STAGE_COUNT ? kStageNames[index] : "?"; }

CounterSums counter_sums(const std::uint64_t* values) {
  CounterSums s;
  for (int i = 0; i < OPSILA_STAT_COUNT; ++i) {
    if (kStatSums[i] == Sum::SPAWNED) s.spawned += values[i];
    if (kStatSums[i] == Sum::FINISHED) s.finished += values[i];
  }
  return s;
}

CounterSums counter_sums(const std::vector<std::uint64_t>& flat) {
  CounterSums all;
  for (std::size_t at = 0; at + OPSILA_STAT_COUNT <= flat.size(); at += OPSILA_STAT_COUNT) {
    const CounterSums s = counter_sums(flat.data() + at);
    all.spawned += s.spawned;
    all.finished += s.finished;
  }
  return all;
}

static_assert(OPSILA_COUNTER_WORDS == 2, "a counter is a (low, high) pair of words");

std::vector<std::uint64_t> join_word_pairs(const std::vector<std::uint32_t>& words) {
  std::vector<std::uint64_t> out(words.size() / OPSILA_COUNTER_WORDS);
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = join_words(words[2 * i], words[2 * i + 1]);
  return out;
}

std::vector<std::uint64_t> read_counters(ClRuntime& rt, const cl::Buffer& b, std::size_t count, const char* what) {
  std::vector<std::uint32_t> words(count * OPSILA_COUNTER_WORDS);
  cl_check(rt.queue().enqueueReadBuffer(b, CL_TRUE, 0, counter_bytes(count), words.data()),
           (std::string("clEnqueueReadBuffer(") + what + ")").c_str());
  return join_word_pairs(words);
}

}  // namespace opsila
