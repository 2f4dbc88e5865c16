// The "obj" and "model" entries of a JSON scene (scenes/FORMAT.md): the
// file is read when the entry is planned (its triangles counted against
// the scene's limit, its materials, maps and warnings joined to the
// scene's), its triangles appended when the entry is built. A scene read in
// shares streams an OBJ (and a PLY or binary STL its stream reads as the
// importer does) instead, and reads other models again when the entry is
// built. Internal to formats/json.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "formats/json/scene_build.h"
#include "formats/json/scene_sections.h"

namespace opsila {
namespace scene_json {

class ModelIncludes {
 public:
  using Make = std::function<void(std::vector<Triangle>&)>;

  ModelIncludes(SceneValues& values, SceneSections& sections, TriangleBudget& budget, ShareDealer& dealer,
                Building& building, Scene& scene, const std::string& base_dir)
      : v_(values), sections_(sections), budget_(budget), dealer_(dealer), building_(building), scene_(scene),
        base_dir_(base_dir) {}

  // The entry `v` at `path` ("model" when any_format, else "obj"), read,
  // counted and joined; the returned build appends its triangles.
  Make plan(const Json& v, const std::string& path, bool any_format);

 private:
  // How the file is read now: streamed in windows (several ranks), by the
  // OBJ reader, or by the importer.
  struct Reading {
    std::string full, fkey;
    bool obj = false, windowed = false, streamed = false;
  };
  void read(Scene& sub, const Reading& r, bool any_format, std::uint64_t& fans);
  void join_materials(Scene& sub);
  void file_window(Scene& sub, const std::string& file, std::uint64_t fans, const std::string& fkey);
  void model_again(Scene& sub, const std::string& file, std::size_t triangles, const std::string& fkey);

  SceneValues& v_;
  SceneSections& sections_;
  TriangleBudget& budget_;
  ShareDealer& dealer_;
  Building& building_;
  Scene& scene_;
  const std::string& base_dir_;
  // The scene's maps by path: a map that several includes name is held once.
  std::unordered_map<std::string, int> texture_at_;
};

}  // namespace scene_json
}  // namespace opsila
