// A rank's share of a JSON scene (docs/DISTRIBUTED.md). Every rank reads
// the scene file and builds every entry of "objects" in order, so ids, the
// facet counters and every error are the same on every rank; after each
// entry it counts the entry into the whole scene's figures and keeps only
// the objects dealt to it. An object goes whole to the rank whose equal
// slice of the planned triangles holds its first triangle (each entry's
// built triangles spread evenly over its part of the plan): ranks hold
// about equal shares, and a rank's peak is its share plus the largest
// entry. A terrain is made in windows instead: each rank makes only its
// slice of the plan's triangles (window()).
#include "formats/json/scene_share.h"

#include <algorithm>
#include <limits>

#include "core/page_ledger.h"
#include "scene/instances.h"

namespace opsila {
namespace scene_json {

void ShareDealer::deal(Scene& scene, EntryShare& entry, std::size_t first, std::size_t first_attribute,
                       std::size_t planned_triangles) {
  auto& tris = scene.triangles;
  auto& attributes = scene.attributes;
  const std::uint64_t planned = std::max<std::size_t>(planned_triangles, 1);
  // The entry's size: exact when known before it is built, else (one flush
  // at the end) what it built.
  const std::uint64_t built =
      std::max<std::uint64_t>(1, entry.expected > 0 ? entry.expected : entry.dealt + (tris.size() - first));
  const std::uint64_t span = entry.planned_end - entry.planned_begin;
  const std::uint64_t ranks = std::uint64_t(share_.ranks);
  std::size_t keep = first;
  std::vector<int> moved(attributes.size() - first_attribute, -1);  // this entry's attributes, renumbered
  std::vector<VertexAttributes> kept;
  for (std::size_t k = first; k < tris.size(); ++k) {
    Triangle t = tris[k];
    ++share_.total_triangles;
    grow_bounds(t);
    if (std::size_t(t.object_id) >= owner_.size()) owner_.resize(std::size_t(t.object_id) + 1, -1);
    int& owner = owner_[std::size_t(t.object_id)];
    // The entry's triangles spread evenly over its part of the plan (a plan
    // counts the largest shape of a generator for each item).
    const std::uint64_t at = entry.planned_begin + std::min<std::uint64_t>(entry.dealt++, built - 1) * span / built;
    if (owner < 0) owner = static_cast<int>(std::min(at * ranks / planned, ranks - 1));
    if (owner != share_.rank) continue;
    if (t.attributes >= 0 && std::size_t(t.attributes) >= first_attribute) {
      int& to = moved[std::size_t(t.attributes) - first_attribute];
      if (to < 0) {
        to = static_cast<int>(first_attribute + kept.size());
        kept.push_back(attributes[std::size_t(t.attributes)]);
      }
      t.attributes = to;
    }
    tris[keep++] = t;
  }
  tris.resize(keep);
  attributes.resize(first_attribute);
  attributes.insert(attributes.end(), kept.begin(), kept.end());
}

void ShareDealer::grow_bounds(const Triangle& t) {
  for (const Vec3* v : {&t.v0, &t.v1, &t.v2}) grow_bounds(*v);
}

void ShareDealer::grow_bounds(const Vec3& p) {
  if (!bounded_) share_.lo = share_.hi = p;
  bounded_ = true;
  for (int a = 0; a < 3; ++a) {
    share_.lo[a] = std::min(share_.lo[a], p[a]);
    share_.hi[a] = std::max(share_.hi[a], p[a]);
  }
}

// The same world boxes on every rank (scene/instances.h), so the bounds
// `combine` joins hold them wherever the instances' triangles end up.
void ShareDealer::add_instances(const Scene& scene) {
  for (const InstanceDesc& in : scene.instances) {
    Vec3 lo, hi;
    instance_box(scene, in, lo, hi);
    grow_bounds(lo);
    grow_bounds(hi);
  }
}

// This rank makes the triangles in its slice of the plan, the same slice
// deal() gives whole objects, [ceil(r N / R), ceil((r + 1) N / R)). An
// object whose triangles fall in several slices is spread.
void ShareDealer::window(EntryShare& entry, std::size_t all, int object, std::size_t planned, std::size_t& begin,
                         std::size_t& end) {
  const std::uint64_t N = std::max<std::size_t>(planned, 1), R = std::uint64_t(share_.ranks);
  const std::uint64_t pb = entry.planned_begin;
  const auto slice_start = [&](std::uint64_t r) { return (r * N + R - 1) / R; };
  const auto local = [&](std::uint64_t at) { return std::size_t(std::clamp<std::uint64_t>(at, pb, pb + all) - pb); };
  begin = local(slice_start(std::uint64_t(share_.rank)));
  end = local(slice_start(std::uint64_t(share_.rank) + 1));
  entry.windowed = true;
  const auto owner = [&](std::uint64_t at) { return std::min(at * R / N, R - 1); };
  if (all > 0 && owner(pb) != owner(pb + all - 1)) share_.spread.push_back(object);
}

// The polygons whose first fan triangle falls in this rank's slice of the
// plan, the file's fan triangles spread evenly over the entry's part of it
// (ModelWindow).
ModelWindow ShareDealer::file_window(EntryShare& entry, std::size_t planned, std::uint64_t fans) {
  ModelWindow w;
  w.rank = share_.rank, w.ranks = share_.ranks;
  w.plan_begin = entry.planned_begin;
  w.plan_all = entry.planned_end - entry.planned_begin;
  w.plan_total = planned;
  w.fans = fans;
  w.load_maps = false;  // the first read loaded them
  entry.windowed = true;
  return w;
}

// Counted into the figures here, added up over the ranks by share_.combine.
void ShareDealer::count_window(const Scene& scene, std::size_t first) {
  const auto& tris = scene.triangles;
  for (std::size_t k = first; k < tris.size(); ++k) grow_bounds(tris[k]);
  share_.total_triangles += tris.size() - first;
  share_.window_triangles += tris.size() - first;
}

void ShareDealer::add_read(const std::string& file, std::vector<std::uint64_t> stamp) {
  share_.reads.emplace_back(file, std::move(stamp));
}

void ShareDealer::add_window_dropped(const std::string& path, std::size_t dropped) {
  share_.window_dropped.push_back(dropped);
  window_paths_.push_back(path);
}

void ShareDealer::finish(Scene& scene, const std::function<void(const std::string&, std::size_t)>& warn_dropped) {
  if (share_.combine) {
    const float inf = std::numeric_limits<float>::infinity();
    if (!bounded_) share_.lo = splat(inf), share_.hi = splat(-inf);  // nothing here: no part in the bounds
    share_.combine(share_);
  }
  for (std::size_t k = 0; k < window_paths_.size(); ++k) warn_dropped(window_paths_[k], share_.window_dropped[k]);
  scene.share = share_;
  // Its entries were built whole, then dealt: what they left behind goes
  // (moved, not copied whole: the share may be most of the memory).
  if (scene.triangles.capacity() > scene.triangles.size() + scene.triangles.size() / 8)
    move_to_capacity(scene.triangles, scene.triangles.size());
  scene.attributes.shrink_to_fit();
}

}  // namespace scene_json
}  // namespace opsila
