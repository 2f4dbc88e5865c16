// libFuzzer target: OBJ text -> load_obj_from_string. Only InputError is an
// acceptable way to refuse input; anything else (another exception, a
// sanitizer report, a broken invariant) crashes and is reported.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "input/obj_loader.h"
#include "core/scene.h"

namespace {

void require(bool ok) {
  if (!ok) std::abort();
}

// What every successfully loaded scene must satisfy (SPEC ids, finite data).
void check(const opsila::Scene& s) {
  require(!s.triangles.empty() && !s.materials.empty());
  require(s.num_objects >= 1 && s.num_facets >= 1);
  for (const opsila::Triangle& t : s.triangles) {
    require(t.facet_id >= 0 && t.facet_id < s.num_facets);
    require(t.object_id >= 0 && t.object_id < s.num_objects);
    require(t.material >= 0 && static_cast<std::size_t>(t.material) < s.materials.size());
    require(t.attributes >= -1 && (t.attributes < 0 || static_cast<std::size_t>(t.attributes) < s.attributes.size()));
    for (const opsila::Vec3* v : {&t.v0, &t.v1, &t.v2})
      for (float x : *v) require(std::isfinite(x));
  }
  for (const opsila::Vec3* v : {&s.camera.eye, &s.camera.look_at})
    for (float x : *v) require(std::isfinite(x));
  const float eps = s.epsilon();
  require(std::isfinite(eps) && eps > 0);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    // No base folder: mtllib lines never touch the disk.
    check(opsila::load_obj_from_string(text, "fuzz.obj", ""));
  } catch (const opsila::InputError&) {
  }
  return 0;
}
