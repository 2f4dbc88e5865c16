#include "device/memory_plan.h"

#include <algorithm>


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

DevicePlan plan_of(const std::vector<BufferSpec>& table) {
  DevicePlan plan;
  for (const BufferSpec& s : table) {
    switch (s.part) {
      case PlanPart::scene: plan.scene += s.bytes(); break;
      case PlanPart::image: plan.image += s.bytes(); break;
      case PlanPart::descriptors: plan.descriptors += s.bytes(); break;
      case PlanPart::other: plan.other += s.bytes(); break;
    }
  }
  return plan;
}

}  // namespace opsila
