// The "objects" of a JSON scene (scenes/FORMAT.md): each is checked and
// its triangles counted first (TriangleBudget), and built only when the
// whole scene fits the limits; on several ranks each entry is dealt as it
// is built (ShareDealer). Internal to formats/json.
#pragma once

#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "formats/json/scene_build.h"
#include "formats/json/scene_includes.h"
#include "formats/json/scene_sections.h"

namespace opsila {
namespace scene_json {

class ObjectReader {
 public:
  // limit: one rank's (one entry's triangles); share.ranks > 1 reads this
  // rank's share (scene_share.h).
  ObjectReader(SceneValues& values, SceneSections& sections, Scene& scene, const std::string& base_dir,
               const TriangleLimit& limit, const SceneShare& share)
      : v_(values), sections_(sections), scene_(scene), budget_(values, limit, share.ranks), dealer_(share),
        includes_(values, sections, budget_, dealer_, building_, scene, base_dir) {}

  // Checks every object of the array `v` and counts its triangles.
  void read(const Json& v, const std::string& path);
  // Builds every object in order, then sets the scene's counts (and share).
  void build();

 private:
  using Make = ModelIncludes::Make;

  void object(const Json& v, const std::string& path);
  Make shape(const Json& v, const std::string& path, const std::string& type);
  std::optional<Transform> placement(const Json& v, const std::string& path);  // its "transform"
  // An instances entry (scene_instances.cpp): checked and counted; the
  // build returned makes its prototype and instances.
  std::function<void()> instances(const Json& v, const std::string& path);
  Prototype prototype(const Make& make, const std::optional<Transform>& placed, const std::string& path);
  void check_placed_extent(std::size_t first, const std::string& where, std::size_t listed);
  Make solid(const Json& v, const std::string& path, const std::string& type);
  Make plane(const Json& v, const std::string& path, bool checker);
  Make terrain(const Json& v, const std::string& path);
  Make generator(const Json& v, const std::string& path, bool grid);
  void box_extent(const Json& v, const std::string& path, Vec3& lo, Vec3& hi) const;
  void flush_entry();
  // Triangles [first, end) of `tris`; returns those dropped.
  std::size_t settle(std::vector<Triangle>& tris, std::size_t first, const std::string& path);
  void warn_dropped(const std::string& path, std::size_t dropped);

  SceneValues& v_;
  SceneSections& sections_;
  Scene& scene_;
  TriangleBudget budget_;
  ShareDealer dealer_;
  Building building_;
  ModelIncludes includes_;
  std::vector<std::function<void()>> builds_;  // one per object, in order
  int prototypes_planned_ = 0;  // instances entries so far
};

}  // namespace scene_json
}  // namespace opsila
