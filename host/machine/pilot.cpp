#include "machine/pilot.h"

#include <chrono>

#include "machine/ranks.h"
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

MeasuredWork pilot_work(const Scene& scene, const RenderSettings& settings, ClRuntime& runtime, int* frames,
                        double* seconds) {
  const auto t0 = std::chrono::steady_clock::now();
  const Scene view = pilot_scene(scene);
  RenderSettings ps;
  ps.num_pes = settings.num_pes;
  ps.work_groups_per_pe = settings.work_groups_per_pe;
  ps.routing = settings.routing;
  ps.measure_cost = true;
  // mean: the mean of the measurements so far, the partition of the next
  // pilot; best: the input whose partition measured the best occupancy.
  MeasuredWork mean, best;
  double best_occupancy = -1;
  int k = 0;
  for (; k < kPilotFrames; ++k) {
    ps.measured = k == 0 ? nullptr : &mean;
    Renderer pilot(view, ps, runtime);
    const RenderResult r = pilot.render();
    if (const double occ = shared_occupancy(r.stats); occ > best_occupancy) {
      best_occupancy = occ;
      best = k == 0 ? MeasuredWork{} : mean;  // k = 0: the facets' partition
    }
    const MeasuredWork w = pilot.measured_work();
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
