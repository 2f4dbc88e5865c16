#include "scene/work_bound.h"

#include <algorithm>
#include <cstdio>

#include "core/progress.h"

namespace opsila {

WorkBound work_bound(const Scene& scene) {
  std::vector<char> used(scene.materials.size() + 1, 0);
  for (const Triangle& t : scene.triangles)
    if (t.material >= 0 && std::size_t(t.material) < scene.materials.size()) used[std::size_t(t.material)] = 1;
  bool reflects = false, transmits = false;
  for (std::size_t m = 0; m < scene.materials.size(); ++m) {
    if (!used[m]) continue;
    const Vec3 kr = scene.materials[m].kr(), kt = scene.materials[m].kt();
    reflects = reflects || kr[0] != 0 || kr[1] != 0 || kr[2] != 0;
    transmits = transmits || kt[0] != 0 || kt[1] != 0 || kt[2] != 0;
  }
  WorkBound b;
  b.branches = int(reflects) + int(transmits);
  double nodes = 0, level = 1;
  for (int l = 0; l < std::max(1, scene.max_depth); ++l, level *= b.branches) nodes += level;
  b.rays_per_sample = nodes * (1.0 + double(scene.lights.size()));
  b.rays = double(scene.width) * double(scene.height) * double(std::max(1, scene.spp)) * b.rays_per_sample;
  return b;
}

std::string large_work_note(const Scene& scene) {
  const WorkBound b = work_bound(scene);
  if (b.rays < kLargeWork) return "";
  const char* why = b.branches == 2 ? "reflective and transmissive materials"
                    : b.branches == 1 ? "reflective or transmissive materials"
                                      : "no reflection or transmission";
  char text[400];
  std::snprintf(text, sizeof text,
                "expected work: up to %s rays (%dx%d pixels x %d samples x up to %s rays each: depth %d, %zu "
                "lights, %s)",
                count_text(b.rays).c_str(), scene.width, scene.height, scene.spp, count_text(b.rays_per_sample).c_str(),
                scene.max_depth, scene.lights.size(), why);
  return text;
}

}  // namespace opsila
