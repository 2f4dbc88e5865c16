// libFuzzer target: scene JSON text -> load_scene_from_string, with no base
// folder (so "obj" objects are refused and nothing is read from disk) and a
// small triangle budget (so one input cannot take seconds or gigabytes).
// Only InputError is an acceptable refusal; anything else crashes.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "core/scene.h"
#include "input/scene_file.h"

namespace {

void require(bool ok) {
  if (!ok) std::abort();
}

void check(const opsila::Scene& s) {
  require(!s.triangles.empty() && !s.materials.empty());
  require(s.width >= 1 && s.height >= 1 && s.max_depth >= 1);
  for (const opsila::Triangle& t : s.triangles) {
    require(t.facet_id >= 0 && t.facet_id < s.num_facets);
    require(t.object_id >= 0 && t.object_id < s.num_objects);
    require(t.material >= 0 && static_cast<std::size_t>(t.material) < s.materials.size());
    for (const opsila::Vec3* v : {&t.v0, &t.v1, &t.v2})
      for (float x : *v) require(std::isfinite(x));
  }
  for (const opsila::Vec3* v : {&s.camera.eye, &s.camera.look_at, &s.camera.up})
    for (float x : *v) require(std::isfinite(x));
  require(s.camera.fov_deg > 0 && s.camera.fov_deg < 180);
  const float eps = s.epsilon();
  require(std::isfinite(eps) && eps > 0);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    check(opsila::load_scene_from_string(text, "fuzz.json", "", std::size_t(1) << 18));
  } catch (const opsila::InputError&) {
  }
  return 0;
}
