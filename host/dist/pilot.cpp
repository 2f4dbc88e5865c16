#include "dist/pilot.h"

#include <algorithm>
#include <chrono>
#include <functional>

#include "core/stage_clock.h"
#include "partition/banks.h"
#include "dist/collective_partition.h"
#include "mpi/ranks.h"
#include "frame/renderer.h"
#include "frame/stats.h"

namespace opsila {

namespace {

// The pilot's occupancy, the same on every rank: a rank's counters hold its
// own PEs (rank 0's, every PE's), so the largest count over the ranks is
// each PE's count.
double shared_occupancy(RenderStats st, Ranks& ranks) {
  std::vector<std::uint64_t> flat;
  for (const auto& level : st.counters)
    for (const auto& pe : level) flat.insert(flat.end(), pe.begin(), pe.end());
  ranks.max(flat);
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
  std::vector<std::uint64_t> facets(levels < 1 ? 0 : work.size() / std::size_t(levels), 0);
  for (int c : facet_cluster)
    if (c >= 0) ++facets[std::size_t(c)];
  return spread_cluster_work(work, levels, facet_cluster, facets);
}

MeasuredWork spread_cluster_work(const std::vector<std::uint64_t>& work, int levels,
                                 const std::vector<int>& facet_cluster, const std::vector<std::uint64_t>& facets) {
  MeasuredWork w;
  if (work.empty() || levels < 1) return w;
  const std::size_t C = work.size() / std::size_t(levels);
  bool any = false;  // over every cluster: the same answer on every rank of a share
  for (std::uint64_t v : work) any = any || v != 0;
  if (!any) return w;
  w.levels = levels;
  w.per_facet.assign(facet_cluster.size() * std::size_t(levels), 0.0f);
  for (std::size_t t = 0; t < facet_cluster.size(); ++t) {
    if (facet_cluster[t] < 0) continue;  // a facet no bank holds (none today)
    const std::size_t c = std::size_t(facet_cluster[t]);
    for (int l = 0; l < levels; ++l)
      w.per_facet[t * std::size_t(levels) + std::size_t(l)] =
          float(double(work[std::size_t(l) * C + c]) / double(facets[c]));
  }
  return w;
}

namespace {

// The pilots' settings: the frame's PEs, routing and work-groups, counting;
// they read the work, not the item buffer.
RenderSettings pilot_settings(const RenderSettings& settings) {
  RenderSettings ps;
  ps.ranks = settings.ranks;
  ps.num_pes = settings.num_pes;
  ps.work_groups_per_pe = settings.work_groups_per_pe;
  ps.routing = settings.routing;
  ps.measure_cost = true;
  ps.item_buffer_output = false;
  ps.pilot_warm_up = settings.pilot_warm_up;
  return ps;
}

// The pilot frames on `view`, each on the banks `partition` makes of the
// mean measured so far (null: the facets' partition).
using PilotPartition = std::function<PreparedBanks(const MeasuredWork* measured)>;

MeasuredWork run_pilots(const Scene& view, const RenderSettings& ps, const PilotPartition& partition,
                        ClRuntime& runtime, PilotFigures& figures) {
  auto t0 = std::chrono::steady_clock::now();
  StageClock clock(PrepareStage::pilots);
  // mean: the mean of the measurements so far, the partition of the next
  // pilot; best: the input whose partition measured the best occupancy.
  MeasuredWork mean, best;
  double best_occupancy = -1;
  OneProcess solo;  // one process, when the settings name no ranks
  Ranks& ranks = ps.ranks ? *ps.ranks : solo;
  int k = 0;
  for (; k < kPilotFrames; ++k) {
    clock.progress(double(k) / kPilotFrames);
    PreparedBanks banks = partition(k > 0 ? &mean : nullptr);
    figures.facets_held = std::max<std::uint64_t>(figures.facets_held, banks.share.facets_held);
    const std::vector<int> facet_cluster = std::move(banks.facet_cluster);
    const std::vector<std::uint64_t> cluster_facets = std::move(banks.cluster_facets);
    Renderer pilot(view, std::move(banks), ps, runtime);
    if (k == 0 && ps.pilot_warm_up) {
      // The same frame twice gives the same counts (deterministic); the
      // first pays the driver's kernel compilation, outside the pilots' time.
      const auto w0 = std::chrono::steady_clock::now();
      pilot.render();
      const auto w1 = std::chrono::steady_clock::now();
      figures.warm_up_seconds = std::chrono::duration<double>(w1 - w0).count();
      t0 += w1 - w0;
    }
    const RenderResult r = pilot.render();
    if (const double occ = shared_occupancy(r.stats, ranks); occ > best_occupancy) {
      best_occupancy = occ;
      best = k == 0 ? MeasuredWork{} : mean;  // k = 0: the facets' partition
    }
    const MeasuredWork w = spread_cluster_work(pilot.cluster_work(), view.max_depth, facet_cluster, cluster_facets);
    if (w.levels == 0) break;  // nothing measured (no descriptor reached a bank; a rank's share may be empty)
    if (k == 0) {
      mean = w;
      continue;
    }
    for (std::size_t i = 0; i < mean.per_facet.size(); ++i)
      mean.per_facet[i] = (float(k) * mean.per_facet[i] + w.per_facet[i]) / float(k + 1);
  }
  figures.frames = std::min(k + 1, kPilotFrames);
  figures.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return best;
}

}  // namespace

namespace {

// The pilots' partitions of a whole scene, rendered with `view`.
MeasuredWork whole_scene_pilots(const Scene& scene, const Scene& view, const RenderSettings& settings,
                                ClRuntime& runtime, PilotFigures& figures) {
  const RenderSettings ps = pilot_settings(settings);
  OneProcess solo;  // one process, when the settings name no ranks
  Ranks& ranks = settings.ranks ? *settings.ranks : solo;
  const PeGroup group = pe_group(ps.num_pes, ranks.size(), ranks.rank());
  return run_pilots(
      view, ps,
      [&](const MeasuredWork* measured) {
        BalancePolicy policy;
        if (measured) policy = BalancePolicy{Balance::measured, nullptr, measured};
        policy.pilot = true;
        return bank_scene(scene, ps.num_pes, ps.routing, policy, group);
      },
      runtime, figures);
}

// The pilots' view without a copy of the facets, their attributes and the
// texture images: the renderer reads only the banks for those, and the
// partitions are made from the scene itself. The facets are lent out while
// the rest is copied. A whole scene's view keeps one facet spanning the
// scene's box, so that its bounds (the frame's epsilon and box slack) are
// the scene's; a share's bounds are its figures.
Scene view_without_facets(Scene& scene) {
  Vec3 lo, hi;
  if (!scene.is_share()) scene.bounds(lo, hi);
  std::vector<Triangle> facets = std::move(scene.triangles);
  std::vector<VertexAttributes> attributes = std::move(scene.attributes);
  std::vector<Texture> textures = std::move(scene.textures);
  Scene view = pilot_scene(scene);
  scene.triangles = std::move(facets);
  scene.attributes = std::move(attributes);
  scene.textures = std::move(textures);
  if (!scene.is_share() && !scene.triangles.empty()) {
    Triangle span = scene.triangles.front();
    span.v0 = lo, span.v1 = hi, span.v2 = lo;
    span.attributes = -1;
    view.triangles.push_back(span);
  }
  return view;
}

}  // namespace

MeasuredWork pilot_work(const Scene& scene, const RenderSettings& settings, ClRuntime& runtime,
                        PilotFigures& figures) {
  return whole_scene_pilots(scene, pilot_scene(scene), settings, runtime, figures);
}

MeasuredWork pilot_work(Scene& share, const RenderSettings& settings, ClRuntime& runtime, PilotFigures& figures,
                        ShareClusters& clusters) {
  const Scene view = view_without_facets(share);
  if (!share.is_share()) return whole_scene_pilots(share, view, settings, runtime, figures);
  const RenderSettings ps = pilot_settings(settings);
  OneProcess solo;  // one process, when the settings name no ranks
  Ranks& ranks = settings.ranks ? *settings.ranks : solo;
  const PeGroup group = pe_group(ps.num_pes, ranks.size(), ranks.rank());
  ShareBalance how;
  how.keep_share = true;
  how.pilot = true;
  how.clusters = &clusters;
  const MeasuredWork best = run_pilots(
      view, ps,
      [&](const MeasuredWork* measured) {
        how.measured = measured;
        PreparedBanks banks = bank_share(share, ps.num_pes, ps.routing, group, ranks, how);
        how.reuse = true;  // the clusters are made: the next pilots copy them
        return banks;
      },
      runtime, figures);
  figures.facets_held += share.triangles.size();  // the share beside a pilot's banks
  return best;
}

}  // namespace opsila
