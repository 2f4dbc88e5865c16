// What every scene a reader accepts must satisfy (CONTRACT ids in range, finite
// data, a usable camera and epsilon), for the fuzz targets: a broken
// invariant aborts, which the fuzzer reports like a crash.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdlib>

#include "scene/scene.h"

namespace fuzz {

inline void require(bool ok) {
  if (!ok) std::abort();
}

inline void check_scene(const opsila::Scene& s) {
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
  for (const opsila::MaterialDesc& m : s.materials) {
    require(m.map_kd < static_cast<int>(s.textures.size()));
    require(m.map_ka < static_cast<int>(s.textures.size()));
  }
  for (const opsila::Vec3* v : {&s.camera.eye, &s.camera.look_at, &s.camera.up})
    for (float x : *v) require(std::isfinite(x));
  require(s.camera.fov_deg > 0 && s.camera.fov_deg < 180);
  require(s.width >= 1 && s.height >= 1 && s.max_depth >= 1);
  const float eps = s.epsilon();
  require(std::isfinite(eps) && eps > 0);
}

}  // namespace fuzz
