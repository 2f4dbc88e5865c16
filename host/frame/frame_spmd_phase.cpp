#include "frame/frame.h"

namespace opsila {

// SPMD phase: the plan's work-groups, each on one PE's bank.
void Renderer::Machine::spmd_phase(Launcher& launch, Frame& f, int round) {
  kernels().spmd.bind(fp, b_pes, b_clusters, b_route, routing, b_nodes, b_tris, b_mats, b_lights, surface, banks,
                      scatter->group_pe.buffer, scatter->group_first.buffer, scatter->bank_begin,
                      scatter->bank_count, outputs, b_out_count, b_accum, b_stats, b_traffic, traffic_levels,
                      b_node_cluster, b_tri_cluster, b_cost);
  launch.run(kernels().spmd.kernel(), "spmd_phase", std::size_t(f.groups) * spmd_wg, spmd_wg, round);
  f.out_groups = f.groups;
  if (round % 16 == 15) launch.harvest();
}

}  // namespace opsila
