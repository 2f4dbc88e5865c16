#include "machine/prepare_banks.h"

#include <stdexcept>

#include "machine/collective_partition.h"
#include "machine/pilot.h"
#include "machine/ranks.h"

namespace opsila {

PreparedBanks prepare_banks(const Scene& scene, const RenderSettings& settings, ClRuntime& runtime) {
  check_machine_request(scene, settings.num_pes);
  const PrepareTimes before = prepare_times();
  Ranks& ranks = Ranks::world();
  const PeGroup group = pe_group(settings.num_pes, ranks.size(), ranks.rank());
  if (scene.is_share()) {  // read in shares: the ranks partition it together
    if (settings.balance != Balance::facets)
      throw std::invalid_argument("prepare_banks: a scene read in shares is balanced by facets");
    return bank_share(scene, settings.num_pes, settings.routing, group, ranks);
  }
  BalancePolicy policy;
  policy.balance = settings.balance;
  policy.sample = settings.ray_sample;
  MeasuredWork measured;
  int frames = 0;
  double seconds = 0;
  if (settings.balance == Balance::measured) {
    measured = pilot_work(scene, settings, runtime, &frames, &seconds);
    policy.measured = &measured;
  }
  PreparedBanks banks = bank_scene(scene, settings.num_pes, settings.routing, policy, group);
  banks.pilot_frames = frames;
  banks.pilot_seconds = seconds;
  banks.prepare = stages_since(before);
  return banks;
}

}  // namespace opsila
