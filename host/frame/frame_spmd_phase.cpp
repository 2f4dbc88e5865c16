#include "frame/frame.h"

namespace opsila {

// SPMD phase: the plan's work-groups, each on one PE's bank, and before
// them those that build the next round's primary descriptors, if any.
void Renderer::Machine::spmd_phase(Launcher& launch, Frame& f, int round) {
  frame_kernels::SpmdArgs a;
  a.fp = fp;
  a.routing = routing_tables;
  a.routing_mode = routing;
  a.geometry = geometry;
  a.shading = shading;
  a.banks = banks;
  a.groups = scatter->group_table();
  a.bank_ranges = scatter->bank_ranges;
  a.outputs = outputs;
  a.out_count = b_out_count;
  a.accum = b_accum;
  a.stats = b_stats;
  a.traffic = b_traffic;
  a.traffic_levels = traffic_levels;
  a.work = work;
  a.spmd_groups = f.groups;
  const int builders = primary_ahead(f, a.primary);
  kernels().spmd.bind(a);
  launch.run(kernels().spmd.kernel(), "spmd_phase", std::size_t(f.groups + builders) * spmd_wg, spmd_wg, round,
             nullptr, Launcher::Watch::always);
  f.out_groups = f.groups;
  if (round % 16 == 15) launch.harvest();
}

}  // namespace opsila
