// The partition as the machine's input: the banks one device holds, prepared
// before any renderer is built. A renderer takes PreparedBanks and never
// partitions; who prepares them (one process partitioning the whole scene,
// or ranks that each hold part of it) is not its concern. What it reads is
// only its own PEs' banks and the small tables every PE knows.
#pragma once

#include <cstdint>
#include <vector>

#include "scene/ray_sample.h"
#include "scene/scene.h"
#include "partition/partition.h"
#include "partition/pe_group.h"
#include "scene/render_types.h"

namespace opsila {

// How the partition shares the scene (--balance), with what it shares:
// equal facets; the frame's sampled rays (work); or the work pilot frames
// measured on the device (measured). Named, never guessed from which
// pointer is set.
struct BalancePolicy {
  Balance balance = Balance::facets;
  const RaySample* sample = nullptr;       // work: required
  const MeasuredWork* measured = nullptr;  // measured: required (prepare/prepare_banks.h measures it)
  // The banks are a pilot frame's: they keep the maps from bank facets to
  // clusters and scene facets (PartitionUse::pilot_maps), and
  // PreparedBanks::facet_cluster is filled.
  bool pilot = false;
};

// The banks of one device (one MPI rank's group of PEs, or all of them).
struct PreparedBanks {
  // The group's banks, renumbered from 0 (pe_group.h, keep_group_banks),
  // and the global tables of every PE: clusters, routing boxes, PE table,
  // materials, lights. bank_bytes and the like describe the whole scene.
  BankedScene scene;
  PeGroup group;
  int tri_base = 0;  // global index of the group's first facet
  Balance balance = Balance::facets;
  int pilot_frames = 0;      // --balance measured: pilot frames run to prepare these banks
  double pilot_seconds = 0;  // and their time
  double pilot_warm_up_seconds = 0;  // RenderSettings::pilot_warm_up: the untimed frame before them
  PrepareTimes prepare;      // the stages that prepared them: partition, bank build, pilots (core/stage_clock.h)
  // The cluster of every scene facet (of this rank's share, for a scene read
  // in shares): the pilot frames' per-cluster counts are spread over these
  // (dist/pilot.h).
  std::vector<int> facet_cluster;
  std::vector<std::uint64_t> cluster_facets;  // and the facets of every cluster (every rank's)
  ShareFigures share;  // a scene read in shares: what the collective partition did here
};

// Throws InputError when the scene has more lights than the kernels take, or
// no facet. Shared by every OpenCL renderer. (Depth and spp are checked
// where the view is applied, prepare/view.h.)
void check_kernel_limits(const Scene& scene);

// Refuses (InputError) a machine the kernels cannot run: --pes out of range,
// lights beyond the kernels' limits, no facet. Checked once, when the banks
// are prepared (prepare/prepare_banks.h); the renderer takes them as they are.
void check_machine_request(const Scene& scene, int num_pes);

// Partitions `scene` over `num_pes` PEs as `policy` says (spheres routing
// also cuts flat pieces, partition.h), then keeps `group`'s banks.
// Deterministic: every rank that calls it with the same inputs gets the
// same global tables.
// `release` (null, or the scene itself): its triangles go once the banks
// hold copies of them (PartitionUse::release).
PreparedBanks bank_scene(const Scene& scene, int num_pes, int routing, const BalancePolicy& policy,
                         const PeGroup& group, Scene* release = nullptr);

}  // namespace opsila
