#include "machine/host_scatter.h"

#include <algorithm>
#include <random>

namespace opsila {

void HostDescriptors::resize(std::size_t n) {
  org.resize(n);
  dir.resize(n);
  wgt.resize(n);
  ids.resize(n);
  dest.resize(n);
}

HostScatterResult host_scatter(const HostDescriptors& src, int num_pes, int n, HostDescriptors& banks,
                               HostDescriptors& next, std::vector<std::size_t>& scratch) {
  const std::size_t len = src.size();
  const std::size_t P = static_cast<std::size_t>(num_pes);
  // scratch[0..P): entries bound for each PE so far (the running rank);
  // scratch[P..2P): first queue slot of each PE's overflow.
  scratch.assign(2 * P, 0);
  std::size_t* total = scratch.data();
  std::size_t* base = scratch.data() + P;
  for (std::size_t i = 0; i < len; ++i) {
    const int d = src.dest[i];
    if (d >= 0 && d < num_pes) ++total[d];
  }
  HostScatterResult r;
  r.bank_count.resize(P);
  for (std::size_t q = 0; q < P; ++q) {
    const std::size_t placed = std::min<std::size_t>(total[q], std::size_t(n));
    r.bank_count[q] = static_cast<int>(placed);
    base[q] = r.waiting;
    r.waiting += total[q] - placed;
    r.placed += placed;
    total[q] = 0;  // from here on: the rank of the next entry bound for q
  }
  for (std::size_t i = 0; i < len; ++i) {
    const int d = src.dest[i];
    if (d < 0 || d >= num_pes) continue;
    const std::size_t rank = total[d]++;
    const std::size_t at = rank < std::size_t(n) ? std::size_t(d) * n + rank : base[d] + (rank - n);
    HostDescriptors& to = rank < std::size_t(n) ? banks : next;
    to.org[at] = src.org[i];
    to.dir[at] = src.dir[i];
    to.wgt[at] = src.wgt[i];
    to.ids[at] = src.ids[i];
    to.dest[at] = d;
  }
  return r;
}

HostDescriptors random_descriptors(std::size_t length, int pes, double hole_rate, unsigned seed) {
  HostDescriptors h;
  h.resize(length);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> coin(0, 1);
  std::uniform_int_distribution<int> pe(0, pes - 1);
  for (std::size_t i = 0; i < length; ++i) {
    const float f = static_cast<float>(i);
    h.dest[i] = (hole_rate > 0 && coin(rng) < hole_rate) ? -1 : pe(rng);
    h.org[i] = {{f, 1.0f, 2.0f, 3.0f}};
    h.dir[i] = {{0.0f, 0.0f, 1.0f, f}};
    h.wgt[i] = {{1.0f, 0.5f, 0.25f, 0.0f}};
    h.ids[i] = {{static_cast<int>(i), 4, -1, h.dest[i]}};
  }
  return h;
}

}  // namespace opsila
