#include "frame/host_scatter.h"

#include <algorithm>
#include <random>

namespace opsila {

HostScatterResult host_scatter(const HostDescriptors& src, int num_pes, int slots, int cap, int group_size, int depth,
                               bool throttle, HostDescriptors& banks, HostDescriptors& next,
                               std::vector<std::size_t>& scratch) {
  const std::size_t len = src.size();
  const std::size_t P = static_cast<std::size_t>(num_pes), K = 2 * P;
  const long long budget = slots, limit = cap > 0 ? cap : slots;
  // scratch[0..K): entries with each sort key (then the running rank);
  // scratch[K..2K): each key's first bank slot; [2K..3K): its slots;
  // [3K..4K): its first place in the next pool.
  scratch.assign(4 * K, 0);
  std::size_t* total = scratch.data();
  std::size_t* key_begin = total + K;
  std::size_t* key_count = total + 2 * K;
  std::size_t* key_base = total + 3 * K;
  for (std::size_t i = 0; i < len; ++i) {
    const int y = desc_key(src[i], depth);
    if (y >= 0 && y < static_cast<int>(K)) ++total[y];
  }
  bool ends_waiting = false;
  for (std::size_t q = 0; q < P; ++q) ends_waiting |= total[2 * q] > 0;
  const bool ends_only = throttle && ends_waiting;
  auto demand = [&](std::size_t q) {
    return static_cast<long long>(total[2 * q] + (ends_only ? 0 : total[2 * q + 1]));
  };
  auto share = [&](std::size_t q, long long level) { return std::min({demand(q), level, limit}); };
  long long level = 0;
  for (long long lo = 0, hi = budget; lo <= hi;) {  // the largest level that fits
    const long long mid = lo + (hi - lo) / 2;
    long long used = 0;
    for (std::size_t q = 0; q < P; ++q) used += share(q, mid);
    if (used <= budget) level = mid, lo = mid + 1; else hi = mid - 1;
  }
  long long spare = budget;
  for (std::size_t q = 0; q < P; ++q) spare -= share(q, level);
  HostScatterResult r;
  r.bank_begin.resize(P);
  r.bank_count.resize(P);
  int begin = 0;
  for (std::size_t q = 0; q < P; ++q) {
    long long c = share(q, level);
    if (spare > 0 && c < demand(q) && c < limit) ++c, --spare;
    r.bank_count[q] = static_cast<int>(c);
    r.bank_begin[q] = begin;
    // The bank's first slots to what ends its tree (key 2q), then key 2q + 1;
    // what waits, per PE in PE order, in the same key order.
    const std::size_t ends = std::min<std::size_t>(c, total[2 * q]);
    key_begin[2 * q] = begin;
    key_count[2 * q] = ends;
    key_base[2 * q] = r.waiting;
    key_begin[2 * q + 1] = begin + ends;
    key_count[2 * q + 1] = c - ends;
    key_base[2 * q + 1] = r.waiting + (total[2 * q] - ends);
    const int groups = static_cast<int>((c + group_size - 1) / group_size);
    begin += groups * group_size;
    r.groups += groups;
    r.waiting += total[2 * q] + total[2 * q + 1] - c;
    r.placed += c;
  }
  std::fill(total, total + K, 0);  // from here on: the rank of the next entry of each key
  for (std::size_t i = 0; i < len; ++i) {
    const int y = desc_key(src[i], depth);
    if (y < 0 || y >= static_cast<int>(K)) continue;
    const std::size_t rank = total[y]++, fits = key_count[y];
    if (rank < fits)
      banks[key_begin[y] + rank] = src[i];
    else
      next[key_base[y] + (rank - fits)] = src[i];
  }
  return r;
}

HostDescriptors random_descriptors(std::size_t length, int pes, double hole_rate, unsigned seed, double shadow_rate) {
  HostDescriptors h(length);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> coin(0, 1);
  std::uniform_int_distribution<int> pe(0, pes - 1);
  for (std::size_t i = 0; i < length; ++i) {
    const float f = static_cast<float>(i);
    const int dest = (hole_rate > 0 && coin(rng) < hole_rate) ? -1 : pe(rng);
    h[i].org = {{f, 1.0f, 2.0f, 3.0f}};
    h[i].dir = {{0.0f, 0.0f, 1.0f, f}};
    h[i].wgt = {{1.0f, 0.5f, 0.25f, 0.0f}};
    // Radiance rays of level 1, or shadow rays (they end their ray tree).
    const bool shadow = shadow_rate > 0 && coin(rng) < shadow_rate;
    h[i].ids = {{static_cast<int>(i), OPSILA_META(shadow ? OPSILA_KIND_SHADOW : OPSILA_KIND_TRACE, 1), -1, dest}};
  }
  return h;
}

}  // namespace opsila
