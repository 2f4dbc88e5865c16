#include "machine/host_scatter.h"

#include <algorithm>
#include <random>

namespace opsila {

HostScatterResult host_scatter(const HostDescriptors& src, int num_pes, int slots, int cap, int group_size,
                               HostDescriptors& banks, HostDescriptors& next, std::vector<std::size_t>& scratch) {
  const std::size_t len = src.size();
  const std::size_t P = static_cast<std::size_t>(num_pes);
  const long long budget = slots, limit = cap > 0 ? cap : slots;
  // scratch[0..P): entries bound for each PE (its demand, then the running
  // rank); scratch[P..2P): first pool slot of each PE's overflow.
  scratch.assign(2 * P, 0);
  std::size_t* total = scratch.data();
  std::size_t* base = scratch.data() + P;
  for (std::size_t i = 0; i < len; ++i) {
    const int d = desc_dest(src[i]);
    if (d >= 0 && d < num_pes) ++total[d];
  }
  auto share = [&](std::size_t q, long long level) {
    return std::min({static_cast<long long>(total[q]), level, limit});
  };
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
    if (spare > 0 && c < static_cast<long long>(total[q]) && c < limit) ++c, --spare;
    r.bank_count[q] = static_cast<int>(c);
    r.bank_begin[q] = begin;
    const int groups = static_cast<int>((c + group_size - 1) / group_size);
    begin += groups * group_size;
    r.groups += groups;
    base[q] = r.waiting;
    r.waiting += total[q] - c;
    r.placed += c;
    total[q] = 0;  // from here on: the rank of the next entry bound for q
  }
  for (std::size_t i = 0; i < len; ++i) {
    const int d = desc_dest(src[i]);
    if (d < 0 || d >= num_pes) continue;
    const std::size_t rank = total[d]++, fits = r.bank_count[d];
    if (rank < fits)
      banks[r.bank_begin[d] + rank] = src[i];
    else
      next[base[d] + (rank - fits)] = src[i];
  }
  return r;
}

HostDescriptors random_descriptors(std::size_t length, int pes, double hole_rate, unsigned seed) {
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
    h[i].ids = {{static_cast<int>(i), 4, -1, dest}};
  }
  return h;
}

}  // namespace opsila
