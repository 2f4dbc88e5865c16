#include "frame/frame.h"

#include <algorithm>
#include <utility>

namespace opsila {

ScatterPass::Args Renderer::Machine::exchange_args(const Frame& f) const {
  ScatterPass::Args sa;
  sa.pool_len = static_cast<int>(f.pool_len);
  sa.pool = &pool;
  sa.out_groups = f.out_groups;
  sa.group_size = static_cast<int>(spmd_wg);
  sa.spawn_slots = S;
  sa.outputs = &outputs;
  sa.out_item_count = &b_out_count;
  sa.slots = static_cast<int>(flight.slots);
  sa.cap = cap;
  sa.banks = &banks;
  sa.next_pool = &next_pool;
  sa.group_begin = group.begin;
  sa.group_end = group.end;
  // Beyond the waiting limit the exchange takes only the rays that end their
  // tree (kernels/scatter.cl), so that what waits stays bounded whatever the
  // depth and the scene. Below it, rounds stay full.
  sa.throttle = f.pool_len > waiting_limit;
  return sa;
}

// SIMD exchange: scatter [pool | SPMD outputs] into the banks of the next
// SPMD phase, each bank as large as its PE's demand allows; what finds no
// slot waits in the next pool. The control unit reads three counts (how many
// wait, how many were placed, how many work-groups serve them) while the
// records move.
void Renderer::Machine::exchange(Launcher& launch, Frame& f, int round, RenderStats& st) {
  const std::size_t bound = f.pool_len + std::size_t(f.out_groups) * spmd_wg * S + flight.inject;
  if (next_pool.capacity < bound) next_pool.allocate(rt, bound + bound / 2, "descriptor pool");
  const ScatterPass::Args sa = exchange_args(f);
  scatter->plan(launch, sa, round);
  st.throttled_rounds += sa.throttle ? 1 : 0;
  cl_int counts[3] = {0, 0, 0};
  cl::Event read;
  launch.check(rt.queue().enqueueReadBuffer(scatter->counts, CL_FALSE, 0, sizeof(counts), counts, nullptr, &read),
               "clEnqueueReadBuffer(scatter counts)");
  scatter->move(launch, sa, round);
  launch.check(read.wait(), "clWaitForEvents(scatter counts)");
  if (rank_exchange) rank_exchange->start(scatter->pe_total, next_pool, static_cast<std::size_t>(counts[0]));
  std::swap(pool, next_pool);
  f.pool_len = static_cast<std::size_t>(counts[0]);
  f.groups = counts[2];
  st.overflow_deferrals += rank_exchange ? rank_exchange->waiting() : static_cast<std::uint64_t>(counts[0]);
  st.waiting_peak = std::max<std::uint64_t>(st.waiting_peak, static_cast<std::uint64_t>(counts[0]));
}

// Several ranks, after the SPMD launch: the records bound for other ranks
// travel while the SPMD phase runs; the next pool is this rank's waiting
// records followed by what the others sent. The ranks go on while any has
// work, and take the next injection decision together. Returns false at the end.
bool Renderer::Machine::end_rank_round(Launcher& launch, Frame& f) {
  launch.check(rt.queue().flush(), "clFlush");
  rank_exchange->exchange();
  f.pool_len = rank_exchange->finish(pool, next_pool, flight.inject);
  std::swap(pool, next_pool);
  const bool left = f.pool_len > 0 || f.out_groups > 0 || f.next_hit < f.listed || f.sample + 1 < spp;
  std::vector<std::uint64_t> all = {left ? 1u : 0u, f.pool_len};
  ranks.max(all);
  f.pool_len_max = all[1];
  return all[0] > 0;
}

}  // namespace opsila
