#include "partition/banks.h"

#include <stdexcept>
#include <string>

#include "core/fixed_point.h"
#include "opsila_shared.h"

namespace opsila {

void check_kernel_limits(const Scene& scene) {
  // Depth and spp are the view's, checked once where it is applied
  // (prepare/view.cpp); here what only the banks' kernels limit.
  if (static_cast<int>(scene.lights.size()) > OPSILA_MAX_LIGHTS)
    throw InputError("scene has " + std::to_string(scene.lights.size()) + " lights; at most " +
                     std::to_string(OPSILA_MAX_LIGHTS) + " are supported");
  if (!scene.has_facets()) throw InputError("scene has no facets");
}

void check_machine_request(const Scene& scene, int num_pes) {
  if (num_pes < 1 || num_pes > OPSILA_MAX_PES)
    throw InputError("--pes " + std::to_string(num_pes) + ": must be 1.." + std::to_string(OPSILA_MAX_PES));
  check_kernel_limits(scene);
}

PreparedBanks bank_scene(const Scene& scene, int num_pes, int routing, const BalancePolicy& policy,
                         const PeGroup& group, Scene* release) {
  const RaySample* sample = nullptr;
  const MeasuredWork* measured = nullptr;
  if (policy.balance == Balance::work) {
    if (!policy.sample) throw std::invalid_argument("bank_scene: --balance work needs its ray sample");
    sample = policy.sample;
  } else if (policy.balance == Balance::measured) {
    if (!policy.measured) throw std::invalid_argument("bank_scene: --balance measured needs the measured work");
    measured = policy.measured;
  }
  PreparedBanks b;
  PartitionUse use;
  use.pilot_maps = policy.pilot;
  use.release = release;
  use.ranks = group.ranks;
  b.scene = partition_scene(scene, num_pes, routing == OPSILA_ROUTING_SPHERES, sample, measured, use);
  b.balance = policy.balance;
  b.group = group;
  if (policy.pilot) {
    b.facet_cluster.assign(scene.triangles.size(), -1);
    for (std::size_t k = 0; k < b.scene.source.size(); ++k)
      b.facet_cluster[std::size_t(b.scene.source[k])] = b.scene.tri_cluster[k];
    b.cluster_facets.assign(b.scene.clusters.size(), 0);
    for (int c : b.scene.tri_cluster) ++b.cluster_facets[std::size_t(c)];
  }
  b.tri_base = keep_group_banks(b.scene, group);
  return b;
}

}  // namespace opsila
