// What the objects of a JSON scene share while they are planned and built
// (scene_objects.cpp, scene_includes.cpp): the scene's triangle budget,
// and the entry being built with the ids given so far. Internal to
// formats/json.
#pragma once

#include <algorithm>
#include <cstddef>
#include <limits>
#include <optional>
#include <string>

#include "formats/json/primitives.h"
#include "formats/json/scene_share.h"
#include "formats/json/scene_values.h"
#include "scene/triangle_limit.h"

namespace opsila {
namespace scene_json {

// Counts each object's triangles (and facets, an upper bound for generated
// shapes) against the scene's limits before anything is built.
class TriangleBudget {
 public:
  // limit: one rank's, so one entry's of "objects"; the scene may have
  // `ranks` times it (under the ids ceiling).
  TriangleBudget(const SceneValues& values, const TriangleLimit& limit, int ranks)
      : v_(values),
        limit_(limit),
        entry_limit_(limit.triangles),
        most_(std::min(limit.triangles * std::size_t(std::max(ranks, 1)), kMaxTriangles)),
        ranks_(std::max(ranks, 1)) {}

  // windowed: an entry no rank holds whole (a terrain made in windows, a
  // generator's items dealt as they are made), so not limited to one
  // rank's triangles on several ranks.
  void add(std::size_t triangles, std::size_t facets, std::size_t objects, const std::string& path,
           bool windowed = false);
  void add(std::size_t triangles, const std::string& path) { add(triangles, triangles, 1, path); }

  // Counts an instances entry (scenes/FORMAT.md "Instances"): its model,
  // planned by add() since the plan held `from` triangles, and 3 triangles
  // for each of its `placements` (what a placement holds while the scene
  // is prepared). Every rank keeps them all: they leave the plan that is
  // dealt (planned()), count against the scene's limit and, together, one
  // rank's.
  void hold_everywhere(std::size_t from, std::size_t placements, const std::string& path);

  std::size_t planned() const { return planned_triangles_; }  // triangles so far, to be dealt
  std::size_t most() const { return most_; }                   // the whole scene's
  std::size_t left() const { return most_ - planned_triangles_ - everywhere_; }
  std::size_t entry_limit() const { return entry_limit_; }
  // Why an included file that streamed past the scene's limit does not fit
  // (TooManyTriangles), "" for other errors: added to its message.
  std::string beyond(const InputError& e) const;

 private:
  std::string hint(std::size_t triangles, bool windowed) const;

  const SceneValues& v_;
  TriangleLimit limit_;
  std::size_t entry_limit_, most_;
  int ranks_;
  std::size_t planned_triangles_ = 0, planned_facets_ = 0, planned_objects_ = 0;
  std::size_t everywhere_ = 0, instances_ = 0;  // hold_everywhere's
};

// The entry of "objects" being built: what is not yet placed, settled and
// dealt starts at `first`.
struct Entry {
  std::optional<Transform> placed;
  std::string path;
  std::size_t first = 0, first_attribute = 0, dropped = 0;
  EntryShare share;
};

// The entry being built and the ids given so far, shared by the builds.
struct Building {
  Entry entry;
  int next_object = 0;
  int next_facet = 0;
  // The box of the facets settled so far: the entry that takes it past the
  // renderer's extent is the one the error names.
  Vec3 lo{kInf, kInf, kInf}, hi{-kInf, -kInf, -kInf};
  static constexpr float kInf = std::numeric_limits<float>::infinity();
};

}  // namespace scene_json
}  // namespace opsila
