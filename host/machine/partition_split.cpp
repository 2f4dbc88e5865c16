// Step 1 of partition_scene (machine/partition.cpp): each object cut into
// clusters at median centroids until every piece is small enough. A scene
// read in shares runs the same cuts, collectively for the objects spread
// over several ranks (machine/collective_cut.cpp).
#include "machine/partition_steps.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <utility>
#include <vector>

#include "core/parallel.h"

namespace opsila {
namespace partition_steps {

float centroid(const Triangle& t, int a) { return (t.v0[a] + t.v1[a] + t.v2[a]) * (1.0f / 3.0f); }

// With split_flat, a flat piece (a floor, a wall, a terrain patch) must
// also fit a fraction of a PE's region: its bounding sphere is mostly empty
// space, so rays meet it far from any facet.
constexpr float kFlatness = 0.125f;  // smallest box extent / largest, at most
constexpr float kFlatShare = 0.5f;   // largest flat piece, in regions across

bool is_flat(const Box& b) {
  const float big = std::max({b.extent(0), b.extent(1), b.extent(2)});
  const float small = std::min({b.extent(0), b.extent(1), b.extent(2)});
  return small <= kFlatness * big;
}

// The bounds of a list of triangles, and of their centroids.
void bounds_of(const Scene& scene, const std::vector<int>& tris, Box& box, Box& cbox) {
  for (int i : tris) {
    box.grow(tri_box(scene.triangles[i]));
    cbox.grow(Vec3{centroid(scene.triangles[i], 0), centroid(scene.triangles[i], 1), centroid(scene.triangles[i], 2)});
  }
}

// Cuts `tris` in two at the median centroid of the centroids' longest axis
// (ties by index); `tris` keeps the lower half. False when it cannot be cut.
bool cut_at_median(const Scene& scene, std::vector<int>& tris, const Box& cbox, std::vector<int>& upper) {
  const int axis = cbox.longest();
  if (tris.size() < 2 || !(cbox.extent(axis) > 0)) return false;
  const std::size_t mid = tris.size() / 2;
  // Each centre computed once, next to its index (the same comparisons in
  // the same order as on the facets themselves, so the same halves).
  std::vector<std::pair<float, int>> keyed(tris.size());
  for (std::size_t i = 0; i < tris.size(); ++i) keyed[i] = {centroid(scene.triangles[tris[i]], axis), tris[i]};
  std::nth_element(keyed.begin(), keyed.begin() + mid, keyed.end(), [](const auto& a, const auto& b) {
    return a.first < b.first || (a.first == b.first && a.second < b.second);
  });
  for (std::size_t i = 0; i < tris.size(); ++i) tris[i] = keyed[i].second;
  upper.assign(tris.begin() + mid, tris.end());
  tris.resize(mid);
  return true;
}

ClusterBuild make_cluster(std::vector<int> tris, const Box& box) {
  ClusterBuild cb;
  std::sort(tris.begin(), tris.end());
  cb.tris = std::move(tris);
  cb.box = box;
  cb.c = box.center();
  return cb;
}

// Splits a list of triangles at the median centroid of its longest axis
// until every piece is small enough (facet count and spatial extent). The
// upper half's clusters are listed before the lower half's. Large halves
// are split side by side on the host threads (`spread` levels deep).
bool needs_cut(std::size_t facets, const Box& box, const SplitLimits& limits, bool split_flat) {
  const float limit = split_flat && is_flat(box) ? kFlatShare * limits.max_extent : limits.max_extent;
  return facets > limits.max_tris || (facets > 1 && box.diagonal() > limit);
}

void split_object(const Scene& scene, std::vector<int> cur, std::size_t max_tris, float max_extent,
                  bool split_flat, std::vector<ClusterBuild>& out, int spread) {
  Box box, cbox;
  bounds_of(scene, cur, box, cbox);
  std::vector<int> upper;
  if (!(needs_cut(cur.size(), box, SplitLimits{max_tris, max_extent}, split_flat) &&
        cut_at_median(scene, cur, cbox, upper))) {
    out.push_back(make_cluster(std::move(cur), box));
    return;
  }
  constexpr std::size_t kSpreadFacets = 1 << 16;  // smaller halves are not worth a thread
  if (spread <= 0 || upper.size() < kSpreadFacets) {
    split_object(scene, std::move(upper), max_tris, max_extent, split_flat, out, 0);
    split_object(scene, std::move(cur), max_tris, max_extent, split_flat, out, 0);
    return;
  }
  std::vector<ClusterBuild> halves[2];
  std::vector<int>* pieces[2] = {&upper, &cur};
  parallel_for(
      2,
      [&](std::size_t k) {
        split_object(scene, std::move(*pieces[k]), max_tris, max_extent, split_flat, halves[k], spread - 1);
      },
      2);
  for (std::vector<ClusterBuild>& h : halves) out.insert(out.end(), std::make_move_iterator(h.begin()),
                                                          std::make_move_iterator(h.end()));
}

// Several clusters per PE so that bisection can balance; regions are about
// diag / cbrt(P) across.
SplitLimits split_limits(std::size_t total, const Box& sbox, int num_pes) {
  SplitLimits l;
  l.max_tris = std::max<std::size_t>(64, (total + 8 * num_pes - 1) / (8 * static_cast<std::size_t>(num_pes)));
  l.max_extent = std::max(sbox.diagonal() / std::cbrt(static_cast<float>(num_pes)), 1e-30f);
  return l;
}

std::vector<std::vector<int>> triangles_by_object(const Scene& scene) {
  std::vector<std::vector<int>> by_object(std::max(scene.num_objects, 1));
  for (std::size_t i = 0; i < scene.triangles.size(); ++i) {
    int o = std::clamp(scene.triangles[i].object_id, 0, static_cast<int>(by_object.size()) - 1);
    by_object[o].push_back(static_cast<int>(i));
  }
  return by_object;
}

int split_threads() {
  int spread = 0;  // levels of halves split side by side: enough for every host thread
  while ((1 << spread) < host_threads() && spread < 6) ++spread;
  return spread;
}

std::vector<ClusterBuild> split_clusters(const Scene& scene, std::size_t total, const Box& sbox, int num_pes,
                                         bool split_flat) {
  const SplitLimits l = split_limits(total, sbox, num_pes);
  std::vector<ClusterBuild> cb;
  for (auto& tris : triangles_by_object(scene))
    if (!tris.empty()) split_object(scene, std::move(tris), l.max_tris, l.max_extent, split_flat, cb, split_threads());
  return cb;
}

}  // namespace partition_steps
}  // namespace opsila
