#include "formats/common/window.h"

#include <algorithm>

namespace opsila {

int window_owner(const ModelWindow& plan, std::uint64_t fan) {
  if (plan.fans == 0) return -1;
  // The fan triangle's place in the plan, then the slice that holds it.
  const std::uint64_t at = plan.plan_begin + std::uint64_t((unsigned __int128)fan * plan.plan_all / plan.fans);
  const std::uint64_t N = std::max<std::uint64_t>(plan.plan_total, 1), R = std::uint64_t(plan.ranks);
  return static_cast<int>(std::min<std::uint64_t>((unsigned __int128)at * R / N, R - 1));
}

}  // namespace opsila
