#include "machine/memory_plan.h"

#include <algorithm>

#include "machine/counters.h"
#include "machine/descriptors.h"
#include "opsila_shared.h"

namespace opsila {

FlightPlan::FlightPlan(int P, int n, std::size_t wg, int S) {
  slots = std::size_t(P) * n;
  group_size = wg;
  groups = slots / wg + P + 1;
  outputs = groups * wg * S;
  // Primaries are injected when the pool runs short, a quarter of the
  // slots at a time: waiting descriptors are moved again by every
  // exchange, so fewer of them wait when the work arrives in smaller steps.
  inject = std::max<std::size_t>(slots / 4, 1024);
  pool = outputs + 2 * inject;
}

DevicePlan plan_device_memory(const BankedScene& bs, std::size_t npix, int P, const FlightPlan& f, int depth) {
  using u64 = std::uint64_t;
  DevicePlan plan;
  plan.scene = bs.triangles.size() * sizeof(BankTriangle) + bs.nodes.size() * sizeof(BankNode) +
               bs.clusters.size() * (sizeof(Cluster) + sizeof(cl_int4)) +
               bs.route_nodes.size() * sizeof(BankNode) + bs.pes.size() * sizeof(PeInfo) +
               bs.materials.size() * sizeof(Material) + std::max<std::size_t>(1, bs.lights.size()) * sizeof(Light) +
               bs.attributes.size() * sizeof(BankAttributes) + bs.textures.size() * sizeof(BankTexture) +
               bs.texels.size() * sizeof(std::uint32_t);
  // Item buffer (pair, triangle, distance, facet) and 64-bit fixed-point RGB sums.
  plan.image = u64(npix) * (sizeof(cl_int2) + 2 * sizeof(cl_int) + sizeof(cl_float) + OPSILA_ACCUM_WORDS * sizeof(cl_uint));
  // Banks (slots, each bank padded to a work-group), SPMD outputs, two pools.
  plan.descriptors = (u64(f.slots) + u64(P) * f.group_size + f.outputs + 2 * u64(f.pool)) * DescriptorSet::kSlotBytes;
  // Stats, traffic, output counts, work-group table, and the exchange's
  // ranks and block counts (1.5x the source).
  const u64 source = (u64(f.outputs) + f.pool) * 3 / 2;
  plan.other = counter_bytes(std::size_t(OPSILA_MAX_DEPTH) * P * OPSILA_STAT_COUNT) +
               counter_bytes(P <= OPSILA_TRAFFIC_MAX_PES ? std::size_t(depth) * P * P : 1) + counter_bytes(1) +
               u64(f.groups) * (f.group_size + 2) * sizeof(cl_int) + source * sizeof(cl_int) +
               (source / ScatterPass::kBlock + f.groups + 1) * 3 / 2 * P * sizeof(cl_int);
  return plan;
}

}  // namespace opsila
