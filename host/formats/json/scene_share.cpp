// A rank's share of a JSON scene (docs/DISTRIBUTED.md). Every rank reads
// the scene file and builds every entry of "objects" in order, so ids, the facet counters and every error are the
// same on every rank; after each entry it counts the entry into the whole
// scene's figures and keeps only the objects dealt to it. An object goes
// whole to the rank whose equal slice of the planned triangles holds its
// first triangle (each entry's built triangles spread evenly over its part
// of the plan): ranks hold about equal shares, and a rank's peak is its
// share plus the largest entry. A terrain is made in windows instead: each
// rank makes only its slice of the plan's triangles (window()).
#include "formats/json/scene_reader.h"

#include <limits>

#include "core/input_file.h"

namespace opsila {
namespace scene_json {

void SceneReader::deal(std::size_t first, std::size_t first_attribute) {
  auto& tris = scene_.triangles;
  auto& attributes = scene_.attributes;
  const std::uint64_t planned = std::max<std::size_t>(planned_triangles_, 1);
  // The entry's size: exact when known before it is built, else (one flush
  // at the end) what it built.
  const std::uint64_t built = std::max<std::uint64_t>(
      1, entry_.expected > 0 ? entry_.expected : entry_.dealt + (tris.size() - first));
  const std::uint64_t span = entry_.planned_end - entry_.planned_begin;
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
    const std::uint64_t at = entry_.planned_begin + std::min<std::uint64_t>(entry_.dealt++, built - 1) * span / built;
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

void SceneReader::grow_bounds(const Triangle& t) {
  if (!bounded_) share_.lo = share_.hi = t.v0;
  bounded_ = true;
  for (const Vec3* v : {&t.v0, &t.v1, &t.v2})
    for (int a = 0; a < 3; ++a) {
      share_.lo[a] = std::min(share_.lo[a], (*v)[a]);
      share_.hi[a] = std::max(share_.hi[a], (*v)[a]);
    }
}

// A windowed entry of `all` triangles (its part of the plan): this rank
// makes the ones in its slice of the plan, the same slice deal() gives
// whole objects, [ceil(r N / R), ceil((r + 1) N / R)). An object whose
// triangles fall in several slices is spread.
void SceneReader::window(std::size_t all, int object, std::size_t& begin, std::size_t& end) {
  const std::uint64_t N = std::max<std::size_t>(planned_triangles_, 1), R = std::uint64_t(share_.ranks);
  const std::uint64_t pb = entry_.planned_begin;
  const auto slice_start = [&](std::uint64_t r) { return (r * N + R - 1) / R; };
  const auto local = [&](std::uint64_t at) { return std::size_t(std::clamp<std::uint64_t>(at, pb, pb + all) - pb); };
  begin = local(slice_start(std::uint64_t(share_.rank)));
  end = local(slice_start(std::uint64_t(share_.rank) + 1));
  entry_.windowed = true;
  const auto owner = [&](std::uint64_t at) { return std::min(at * R / N, R - 1); };
  if (all > 0 && owner(pb) != owner(pb + all - 1)) share_.spread.push_back(object);
}

// An imported model of a share, read again when its entry is built (the
// plan kept only its counts, materials and maps): its triangles and
// attributes, which must be those the plan counted.
void SceneReader::model_again(Scene& sub, const std::string& file, std::size_t triangles,
                              const std::string& fkey) {
  Scene again;
  try {
    again = load_model(file, share_.map_images);
  } catch (const InputError& e) {
    fail(fkey, e.what());
  }
  if (again.triangles.size() != triangles)
    fail(fkey, file + ": the file changed while the scene was read (" + std::to_string(triangles) +
                   " triangles, then " + std::to_string(again.triangles.size()) + ")");
  sub.triangles = std::move(again.triangles);
  sub.attributes = std::move(again.attributes);
}

// An OBJ entry (or a PLY or STL model its stream reads) read as a stream again,
// keeping this rank's window: the polygons whose first fan triangle falls
// in its slice of the plan, the file's fan triangles spread evenly over the
// entry's part of it (ModelWindow). The file's objects that fall in several
// slices are spread.
void SceneReader::file_window(Scene& sub, const std::string& file, std::uint64_t fans, const std::string& fkey) {
  ModelWindow w;
  w.rank = share_.rank, w.ranks = share_.ranks;
  w.plan_begin = entry_.planned_begin;
  w.plan_all = entry_.planned_end - entry_.planned_begin;
  w.plan_total = planned_triangles_;
  w.fans = fans;
  w.load_maps = false;  // the first read loaded them
  entry_.windowed = true;
  try {
    const FileReadStamp stamp(file);
    std::uint64_t again = 0;
    Scene part = is_streamed_model(file) ? load_model_window(file, max_triangles_, w, again)
                                         : load_obj_window(file, max_triangles_, w, again);
    if (again != fans) throw InputError(file + ": the file changed while it was read (its polygons)");
    share_.reads.emplace_back(file, stamp.after(again, part.share.total_triangles, std::uint64_t(part.num_facets)));
    sub.triangles = std::move(part.triangles);
    sub.attributes = std::move(part.attributes);
    sub.share.spread = std::move(part.share.spread);
  } catch (const InputError& e) {  // the file changed since it was first read
    fail(fkey, e.what());
  }
}

// A window's triangles, all this rank's: counted into the figures here,
// added up over the ranks by share_.combine.
void SceneReader::count_window(std::size_t first) {
  const auto& tris = scene_.triangles;
  for (std::size_t k = first; k < tris.size(); ++k) grow_bounds(tris[k]);
  share_.total_triangles += tris.size() - first;
  share_.window_triangles += tris.size() - first;
}

void SceneReader::settle_share() {
  if (share_.combine) {
    const float inf = std::numeric_limits<float>::infinity();
    if (!bounded_) share_.lo = splat(inf), share_.hi = splat(-inf);  // nothing here: no part in the bounds
    share_.combine(share_);
  }
  for (std::size_t k = 0; k < window_paths_.size(); ++k) warn_dropped(window_paths_[k], share_.window_dropped[k]);
  scene_.share = share_;
  scene_.triangles.shrink_to_fit();
  scene_.attributes.shrink_to_fit();
}

}  // namespace scene_json
}  // namespace opsila
