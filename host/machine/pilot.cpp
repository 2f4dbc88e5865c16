#include "machine/pilot.h"

#include <chrono>

#include "core/stage_clock.h"
#include "machine/banks.h"
#include "machine/ranks.h"
#include "machine/renderer.h"
#include "machine/stats.h"

namespace opsila {

namespace {

// The pilot's occupancy, the same on every rank: a rank's counters hold its
// own PEs (rank 0's, every PE's), so the largest count over the ranks is
// each PE's count.
double shared_occupancy(RenderStats st) {
  std::vector<std::uint64_t> flat;
  for (const auto& level : st.counters)
    for (const auto& pe : level) flat.insert(flat.end(), pe.begin(), pe.end());
  Ranks::world().max(flat);
  std::size_t k = 0;
  for (auto& level : st.counters)
    for (auto& pe : level)
      for (auto& c : pe) c = flat[k++];
  return test_occupancy(st);
}

// The pilot's view: the same camera, 1 sample per pixel, the image divided
// by the smallest whole factor that brings it to kPilotPixels or fewer.
Scene pilot_scene(const Scene& scene) {
  Scene s = scene;
  const double npix = double(scene.width) * scene.height;
  int f = 1;
  while (npix / (double(f) * f) > kPilotPixels) ++f;
  s.width = std::max(1, scene.width / f);
  s.height = std::max(1, scene.height / f);
  s.spp = 1;
  return s;
}

}  // namespace

MeasuredWork spread_cluster_work(const std::vector<std::uint64_t>& work, int levels,
                                 const std::vector<int>& facet_cluster) {
  MeasuredWork w;
  if (work.empty() || levels < 1) return w;
  const std::size_t C = work.size() / std::size_t(levels);
  std::vector<std::size_t> facets(C, 0);
  for (int c : facet_cluster)
    if (c >= 0) ++facets[std::size_t(c)];
  w.levels = levels;
  w.per_facet.assign(facet_cluster.size() * std::size_t(levels), 0.0f);
  bool any = false;
  for (std::size_t t = 0; t < facet_cluster.size(); ++t) {
    if (facet_cluster[t] < 0) continue;  // a facet no bank holds (none today)
    const std::size_t c = std::size_t(facet_cluster[t]);
    for (int l = 0; l < levels; ++l) {
      const std::uint64_t v = work[std::size_t(l) * C + c];
      any = any || v != 0;
      w.per_facet[t * std::size_t(levels) + std::size_t(l)] = float(double(v) / double(facets[c]));
    }
  }
  if (!any) w = MeasuredWork{};
  return w;
}

MeasuredWork pilot_work(const Scene& scene, const RenderSettings& settings, ClRuntime& runtime, int* frames,
                        double* seconds) {
  const auto t0 = std::chrono::steady_clock::now();
  StageClock clock(PrepareStage::pilots);
  const Scene view = pilot_scene(scene);
  RenderSettings ps;
  ps.num_pes = settings.num_pes;
  ps.work_groups_per_pe = settings.work_groups_per_pe;
  ps.routing = settings.routing;
  ps.measure_cost = true;
  Ranks& ranks = Ranks::world();
  const PeGroup group = pe_group(ps.num_pes, ranks.size(), ranks.rank());
  // mean: the mean of the measurements so far, the partition of the next
  // pilot; best: the input whose partition measured the best occupancy.
  MeasuredWork mean, best;
  double best_occupancy = -1;
  int k = 0;
  for (; k < kPilotFrames; ++k) {
    clock.progress(double(k) / kPilotFrames);
    BalancePolicy policy;
    if (k > 0) policy = BalancePolicy{Balance::measured, nullptr, &mean};
    PreparedBanks banks = bank_scene(view, ps.num_pes, ps.routing, policy, group);
    const std::vector<int> facet_cluster = banks.facet_cluster;
    Renderer pilot(view, std::move(banks), ps, runtime);
    const RenderResult r = pilot.render();
    if (const double occ = shared_occupancy(r.stats); occ > best_occupancy) {
      best_occupancy = occ;
      best = k == 0 ? MeasuredWork{} : mean;  // k = 0: the facets' partition
    }
    const MeasuredWork w = spread_cluster_work(pilot.cluster_work(), view.max_depth, facet_cluster);
    if (w.empty()) break;  // nothing to measure (no descriptor reached a bank)
    if (k == 0) {
      mean = w;
      continue;
    }
    for (std::size_t i = 0; i < mean.per_facet.size(); ++i)
      mean.per_facet[i] = (float(k) * mean.per_facet[i] + w.per_facet[i]) / float(k + 1);
  }
  if (frames) *frames = std::min(k + 1, kPilotFrames);
  if (seconds) *seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return best;
}

}  // namespace opsila
