// Instances in the banks (scenes/FORMAT.md, "instances"; the layout:
// kernels/opsila_shared.h, Instance). Each instance is a cluster of its
// own, dealt to a PE by a bisection of the instances' centres, so that a
// PE's instances lie near one another. A bank that owns instances holds,
// after its own facets and nodes:
//   - a copy of each model its instances place (its facets and BVH, built
//     once per model), unless another bank of the same device holds it
//     already: the banks of a device share one copy, in the range of the
//     first of them that places it, as they share a texture's texels (a
//     bank counts every model it places in its bytes), and
//   - a BVH over its instances' world boxes (PeInfo.instance_root), whose
//     leaves name instances (count OPSILA_INSTANCE_LEAF).
// An instance's cluster has root -2 - the instance (kernels/lib/bvh.cl,
// cluster_nearest), the table BankedScene::instances is global. A hit on an
// instance goes to the instance's PE to be shaded (Instance.pe), not to the
// PE whose range holds the copy.
#pragma once

#include <vector>

#include "partition/partition.h"
#include "scene/scene.h"

namespace opsila {

// The PE of every instance among `num_pes`: recursive bisection of the
// instances' world-box centres at the median (ties by index), each PE
// getting an equal share of the instances. Deterministic: every rank
// computes the same.
std::vector<int> deal_instances(const Scene& scene, int num_pes);

// Adds the instances of PEs [pe_begin, pe_end) to the banks of `bs`, whose
// PE p is bs.pes[p - pe_begin] (all of them on one process; a rank's group,
// numbered from 0, in a collective partition): the copies, the instance
// BVHs and the instance clusters (after each PE's own clusters), and fills
// bs.instances for every instance (root only for those added here). Bank
// arrays are laid out again PE by PE; `attributes` (a facet's
// Scene::attributes index, or empty when the scene has none) follows the
// facets. device_of: the device of each of those PEs (non-decreasing; empty:
// one device), whose banks share the models' copies. Must run before the
// routing and the vertex attributes are made.
void add_instance_banks(const Scene& scene, const std::vector<int>& pe_of, int pe_begin, int pe_end,
                        const Box& sbox, BankedScene& bs, std::vector<int>& attributes,
                        const std::vector<int>& device_of = {});

// What the instances add to each of `num_pes` banks, the PEs in `ranks`
// groups (pe_group.h), one device each: their clusters and the facets of
// the model copies each bank holds (every rank computes it alike).
struct InstanceShares {
  std::vector<int> clusters, facets;
};
InstanceShares instance_shares(const Scene& scene, const std::vector<int>& pe_of, int num_pes, int ranks);

// The prototypes and instances of `from` into `to` (a rank's facets as
// received in a collective partition), with the vertex attributes their
// facets use appended to to.attributes and their indices moved there.
void copy_instances(const Scene& from, Scene& to);

}  // namespace opsila
