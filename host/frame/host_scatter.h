// The scatter written plainly for one processor: the oracle the scatter
// kernels (kernels/scatter.cl) are checked and timed against.
#pragma once

#include <cstddef>
#include <vector>

#include "device/descriptors.h"

namespace opsila {

// Descriptor vectors on the host, laid out as DescriptorSet's records.
using HostDescriptors = std::vector<HostDescriptor>;

// Where the exchange put things: PE q's bank holds bank_count[q] entries at
// slots bank_begin[q] ..; the rest waits in `next`, grouped by PE.
struct HostScatterResult {
  std::vector<int> bank_begin, bank_count;
  std::size_t waiting = 0;  // entries in the next pool
  std::size_t placed = 0;   // entries placed in banks
  int groups = 0;           // SPMD work-groups that serve the banks
};

// The exchange of kernels/scatter.cl written plainly for one processor, on a
// source without SPMD outputs: the same stable counting sort on the sort key
// (desc_key for a frame of this depth: two keys a PE, what ends its ray tree
// first), and the same plan (each PE's bank is min(demand, level, cap)
// slots, the level the largest that fits `slots`, spare slots one each to
// the PEs still waiting in PE order; banks start at multiples of
// group_size; with `throttle`, demand is only what ends its tree, if any PE
// has some). Entry i goes to its PE's bank, key 2q's entries first, when it
// fits, else to the next pool (per PE in PE order, each key's in source
// order). Holes (dest < 0) are skipped. `banks` must hold slots + num_pes *
// group_size entries and `next` src.size(); `scratch` is resized as needed.
HostScatterResult host_scatter(const HostDescriptors& src, int num_pes, int slots, int cap, int group_size, int depth,
                               bool throttle, HostDescriptors& banks, HostDescriptors& next,
                               std::vector<std::size_t>& scratch);

// Uniformly random destinations over `pes` PEs (a fraction `hole_rate` of
// NIL holes), fixed seed; the payload lanes carry the source index. Radiance
// rays of level 1, a fraction `shadow_rate` of shadow rays.
HostDescriptors random_descriptors(std::size_t length, int pes, double hole_rate, unsigned seed,
                                   double shadow_rate = 0.0);

}  // namespace opsila
