// The scatter written plainly for one processor: the oracle the scatter
// kernels (kernels/scatter.cl) are checked and timed against.
#pragma once

#include <cstddef>
#include <vector>

#include "machine/cl_runtime.h"

namespace opsila {

// Descriptor vectors on the host, laid out as DescriptorSet's buffers.
struct HostDescriptors {
  std::vector<cl_float4> org, dir, wgt;
  std::vector<cl_int4> ids;
  std::vector<cl_int> dest;
  void resize(std::size_t n);
  std::size_t size() const { return dest.size(); }
};

// Where the scatter put things: bank PE q holds bank_count[q] entries at
// slots q*n .. q*n + bank_count[q]; the rest waits in `next` (queue order).
struct HostScatterResult {
  std::vector<int> bank_count;
  std::size_t waiting = 0;  // entries in the next queue
  std::size_t placed = 0;   // entries placed in banks
};

// The same stable counting sort on the destination PE as the kernels: entry
// i goes to bank dest(i), slot rank(i) (rank = earlier valid entries for the
// same PE) when rank(i) < n, else to the next queue. Holes (dest < 0) are
// skipped. `banks` must hold num_pes * n entries and `next` src.size()
// entries; `scratch` holds per-PE counters and is resized as needed.
HostScatterResult host_scatter(const HostDescriptors& src, int num_pes, int n, HostDescriptors& banks,
                               HostDescriptors& next, std::vector<std::size_t>& scratch);

// Uniformly random destinations over `pes` PEs (a fraction `hole_rate` of
// NIL holes), fixed seed; the payload fields carry the source index.
HostDescriptors random_descriptors(std::size_t length, int pes, double hole_rate, unsigned seed);

}  // namespace opsila
