// Step 1 of partition_scene (partition/partition.cpp): each object cut into
// clusters at median centroids until every piece is small enough. A scene
// read in shares runs the same cuts, collectively for the objects spread
// over several ranks (dist/collective_cut.cpp).
#include "partition/partition_steps.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <utility>
#include <vector>

#include "core/parallel.h"

namespace opsila {
namespace partition_steps {

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

namespace {

// A facet as the cuts see it: its centroid, computed once and carried
// through the cuts (the median searches compare them many times), and its
// index. Its box is read from the scene where a run's bounds are wanted,
// once a level: carried too, it was 24 more bytes a facet beside the whole
// scene, the preparation's peak on large scenes.
struct CutItem {
  float c[3];
  int tri;
};
using CutItems = std::vector<CutItem>;

constexpr std::size_t kSpreadFacets = 1 << 16;  // fewer facets are not worth a thread

CutItems cut_items(const Scene& scene, const std::vector<int>& tris) {
  CutItems items(tris.size());
  const std::size_t chunks = tris.size() < kSpreadFacets ? 1 : std::size_t(host_threads());
  parallel_for(chunks, [&](std::size_t k) {
    for (std::size_t i = tris.size() * k / chunks, e = tris.size() * (k + 1) / chunks; i < e; ++i) {
      const Triangle& t = scene.triangles[std::size_t(tris[i])];
      for (int a = 0; a < 3; ++a) items[i].c[a] = centroid(t, a);
      items[i].tri = tris[i];
    }
  });
  return items;
}

// A run of items: the cuts reorder them in place, each half a run of its own.
struct Run {
  CutItem* first;
  std::size_t n;
};

// bounds_of on items: the same boxes (a tie between -0 and +0 keeps the
// first met, so the items' order matters only there, and chunks joined in
// order keep it).
void item_bounds(const Scene& scene, Run run, Box& box, Box& cbox) {
  const std::size_t chunks = run.n < kSpreadFacets ? 1 : std::size_t(host_threads());
  std::vector<Box> part(2 * chunks);
  parallel_for(chunks, [&](std::size_t k) {
    // Local boxes: grown through part[] itself, every item's min and max
    // went to memory and back (the items' floats may alias part's).
    Box b, c;
    for (std::size_t i = run.n * k / chunks, e = run.n * (k + 1) / chunks; i < e; ++i) {
      b.grow(tri_box(scene.triangles[std::size_t(run.first[i].tri)]));
      c.grow(run.first[i].c);
    }
    part[2 * k] = b, part[2 * k + 1] = c;
  });
  for (std::size_t k = 0; k < chunks; ++k) box.grow(part[2 * k]), cbox.grow(part[2 * k + 1]);
}

// cut_at_median on items: the same halves (the n / 2 lowest (centroid,
// index) pairs come first). False when it cannot be cut.
bool cut_items_at_median(Run run, const Box& cbox) {
  const int axis = cbox.longest();
  if (run.n < 2 || !(cbox.extent(axis) > 0)) return false;
  const std::size_t mid = run.n / 2;
  std::nth_element(run.first, run.first + mid, run.first + run.n, [axis](const CutItem& a, const CutItem& b) {
    return a.c[axis] < b.c[axis] || (a.c[axis] == b.c[axis] && a.tri < b.tri);
  });
  return true;
}

}  // namespace

// Cuts `tris` in two at the median centroid of the centroids' longest axis
// (ties by index); `tris` keeps the lower half. False when it cannot be cut.
bool cut_at_median(const Scene& scene, std::vector<int>& tris, const Box& cbox, std::vector<int>& upper) {
  CutItems items = cut_items(scene, tris);
  if (!cut_items_at_median(Run{items.data(), items.size()}, cbox)) return false;
  const std::size_t mid = items.size() / 2;
  upper.resize(items.size() - mid);
  tris.resize(mid);
  for (std::size_t i = 0; i < items.size(); ++i) (i < mid ? tris[i] : upper[i - mid]) = items[i].tri;
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

bool needs_cut(std::size_t facets, const Box& box, const SplitLimits& limits, bool split_flat) {
  const float limit = split_flat && is_flat(box) ? kFlatShare * limits.max_extent : limits.max_extent;
  return facets > limits.max_tris || (facets > 1 && box.diagonal() > limit);
}

namespace {

ClusterBuild item_cluster(Run run, const Box& box) {
  std::vector<int> tris(run.n);
  for (std::size_t i = 0; i < run.n; ++i) tris[i] = run.first[i].tri;
  return make_cluster(std::move(tris), box);
}

// Splits a list of triangles at the median centroid of its longest axis
// until every piece is small enough (facet count and spatial extent). The
// upper half's clusters are listed before the lower half's. Large halves
// are split side by side on the host threads (`spread` levels deep).
void split_items(const Scene& scene, Run cur, const SplitLimits& limits, bool split_flat,
                 std::vector<ClusterBuild>& out, int spread) {
  Box box, cbox;
  item_bounds(scene, cur, box, cbox);
  if (!(needs_cut(cur.n, box, limits, split_flat) && cut_items_at_median(cur, cbox))) {
    out.push_back(item_cluster(cur, box));
    return;
  }
  const std::size_t mid = cur.n / 2;
  const Run pieces[2] = {{cur.first + mid, cur.n - mid}, {cur.first, mid}};  // upper half first
  if (spread <= 0 || pieces[0].n < kSpreadFacets) {
    for (const Run& piece : pieces) split_items(scene, piece, limits, split_flat, out, 0);
    return;
  }
  std::vector<ClusterBuild> halves[2];
  parallel_for(
      2, [&](std::size_t k) { split_items(scene, pieces[k], limits, split_flat, halves[k], spread - 1); }, 2);
  for (std::vector<ClusterBuild>& h : halves) out.insert(out.end(), std::make_move_iterator(h.begin()),
                                                          std::make_move_iterator(h.end()));
}

}  // namespace

void split_object(const Scene& scene, std::vector<int> cur, std::size_t max_tris, float max_extent,
                  bool split_flat, std::vector<ClusterBuild>& out, int spread) {
  CutItems items = cut_items(scene, cur);
  cur = std::vector<int>();
  split_items(scene, Run{items.data(), items.size()}, SplitLimits{max_tris, max_extent}, split_flat, out, spread);
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
  const int last = static_cast<int>(by_object.size()) - 1;
  // Counted first, so that each list is its exact size (grown by doubling, a
  // terrain's list could hold twice its facets at the partition's peak).
  std::vector<std::size_t> count(by_object.size(), 0);
  for (const Triangle& t : scene.triangles) ++count[std::size_t(std::clamp(t.object_id, 0, last))];
  for (std::size_t o = 0; o < by_object.size(); ++o) by_object[o].reserve(count[o]);
  for (std::size_t i = 0; i < scene.triangles.size(); ++i)
    by_object[std::size_t(std::clamp(scene.triangles[i].object_id, 0, last))].push_back(static_cast<int>(i));
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
