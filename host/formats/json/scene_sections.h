// The sections of a JSON scene (scenes/FORMAT.md) other than "objects":
// image, camera, lights and materials, into the scene; and what the
// objects take from them (a material by name or inline, a transform).
// Internal to formats/json.
#pragma once

#include <string>
#include <unordered_map>
#include <vector>

#include "formats/json/primitives.h"
#include "formats/json/scene_values.h"
#include "scene/scene.h"

namespace opsila {
namespace scene_json {

class SceneSections {
 public:
  SceneSections(SceneValues& values, Scene& scene) : v_(values), scene_(scene) {}

  void image(const Json& v, const std::string& path);
  void camera(const Json& v, const std::string& path);
  void lights(const Json& v, const std::string& path);
  void materials(const Json& v, const std::string& path);
  // A material name from "materials", or an inline material (added to the
  // scene); none = the default.
  int material_ref(const Json* v, const std::string& path);
  std::vector<int> material_list(const Json& v, const std::string& path);
  Transform transform(const Json& v, const std::string& path);

 private:
  MaterialDesc material(const Json& v, const std::string& path, const std::string& name);

  SceneValues& v_;
  Scene& scene_;
  std::unordered_map<std::string, int> named_;
  std::vector<std::string> named_order_;
};

}  // namespace scene_json
}  // namespace opsila
