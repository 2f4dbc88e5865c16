#include "prepare/prepare_banks.h"

#include "frame/renderer.h"

#include <stdexcept>

#include "dist/collective_balance.h"
#include "dist/collective_partition.h"
#include "dist/collective_cut.h"
#include "dist/pilot.h"
#include "mpi/ranks.h"

namespace opsila {

namespace {

// The pilots' maps follow the scene's own facets only (dist/pilot.h): an
// instanced scene is shared by facets or by sampled work.
void check_balance(const Scene& scene, const RenderSettings& settings) {
  if (!scene.instances.empty() && (settings.balance == Balance::measured || settings.measure_cost))
    throw InputError("--balance measured: pilot frames measure the work of the scene's own facets, not of "
                     "instances (scenes/FORMAT.md, Instances); use --balance facets or work");
}

// A whole scene; `lendable` (null, or the scene itself) lends its facets
// out while the pilots' view is copied, so the view costs no second copy,
// and with Facets::released gives its triangles up to the banks.
PreparedBanks prepare_whole(const Scene& scene, Scene* lendable, const RenderSettings& settings,
                            ClRuntime& runtime, Facets after) {
  check_machine_request(scene, settings.num_pes);
  check_balance(scene, settings);
  const PrepareTimes before = prepare_times();
  OneProcess solo;  // one process, when the settings name no ranks
  Ranks& ranks = settings.ranks ? *settings.ranks : solo;
  const PeGroup group = pe_group(settings.num_pes, ranks.size(), ranks.rank());
  BalancePolicy policy;
  policy.balance = settings.balance;
  policy.sample = settings.ray_sample;
  policy.pilot = settings.measure_cost;  // a renderer that measures reads the maps
  RaySample sample;
  if (settings.balance == Balance::work && !policy.sample) {
    sample = balance_sample(scene, settings.sampler, ranks);
    policy.sample = &sample;
  }
  MeasuredWork measured;
  PilotFigures pilots;
  if (settings.balance == Balance::measured) {
    ShareClusters unused;  // a whole scene's clusters are made by its partition
    measured = lendable ? pilot_work(*lendable, settings, runtime, pilots, unused)
                        : pilot_work(scene, settings, runtime, pilots);
    policy.measured = &measured;
  }
  Scene* release = after == Facets::released ? lendable : nullptr;
  PreparedBanks banks = bank_scene(scene, settings.num_pes, settings.routing, policy, group, release);
  banks.pilot_frames = pilots.frames;
  banks.pilot_seconds = pilots.seconds;
  banks.pilot_warm_up_seconds = pilots.warm_up_seconds;
  banks.prepare = stages_since(before);
  return banks;
}

}  // namespace

PreparedBanks prepare_banks_consuming(Scene& scene, const RenderSettings& settings, ClRuntime& runtime,
                                      Facets after) {
  if (!scene.is_share()) return prepare_whole(scene, &scene, settings, runtime, after);
  // Read in shares: the ranks partition it together, and it gives up its facets once they are sent.
  check_machine_request(scene, settings.num_pes);
  check_balance(scene, settings);
  const PrepareTimes before = prepare_times();
  OneProcess solo;  // one process, when the settings name no ranks
  Ranks& ranks = settings.ranks ? *settings.ranks : solo;
  ShareBalance how;
  how.pilot = settings.measure_cost;  // a renderer that measures reads the maps
  MeasuredWork measured;
  PilotFigures pilots;
  ShareClusters clusters;  // the pilots' clusters before the balance's cuts, for the frame's partition too
  RaySample sample;
  if (settings.balance == Balance::work) {
    // Traced by the ranks together (each through its own facets), so past
    // the point where a rank that failed to read its share stops them all.
    ranks.begin_collective();
    if (!settings.ray_sample) sample = balance_sample(scene, settings.sampler, ranks);
    how.sample = settings.ray_sample ? settings.ray_sample : &sample;
  } else if (settings.balance == Balance::measured) {
    measured = pilot_work(scene, settings, runtime, pilots, clusters);
    how.measured = &measured;
    how.clusters = &clusters;
    how.reuse = pilots.frames > 0;
  }
  PreparedBanks banks = bank_share(scene, settings.num_pes, settings.routing,
                                   pe_group(settings.num_pes, ranks.size(), ranks.rank()), ranks, how);
  banks.balance = settings.balance;
  banks.pilot_frames = pilots.frames;
  banks.pilot_seconds = pilots.seconds;
  banks.pilot_warm_up_seconds = pilots.warm_up_seconds;
  banks.share.pilot_facets_held = pilots.facets_held;
  banks.prepare = stages_since(before);
  return banks;
}

PreparedBanks prepare_banks(const Scene& scene, const RenderSettings& settings, ClRuntime& runtime) {
  if (scene.is_share()) {  // kept whole by the caller: partitioned from a copy
    Scene copy = scene;
    return prepare_banks_consuming(copy, settings, runtime);
  }
  return prepare_whole(scene, nullptr, settings, runtime, Facets::kept);
}

RenderResult render(const Scene& scene, const RenderSettings& settings, ClRuntime& runtime) {
  PreparedBanks banks = prepare_banks(scene, settings, runtime);
  return Renderer(scene, std::move(banks), settings, runtime).render();
}

RenderResult render_consuming(Scene& scene, const RenderSettings& settings, ClRuntime& runtime) {
  PreparedBanks banks = prepare_banks_consuming(scene, settings, runtime);
  return Renderer(scene, std::move(banks), settings, runtime).render();
}

}  // namespace opsila
