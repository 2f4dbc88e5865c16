// The largest ray tree a scene's render can cast, said up front when large.
#pragma once

#include <string>

#include "scene/scene.h"

namespace opsila {

// Upper bound of the rays a render can cast: pixels x spp x the largest ray
// tree (a radiance ray per level per reflective/transmissive branch, each
// with a shadow ray per light). Worth saying up front when it is large.
struct WorkBound {
  double rays = 0;           // the bound (double: 2^31-node trees overflow 64 bits)
  double rays_per_sample = 0;
  int branches = 0;          // 0, 1 or 2: reflected and/or transmitted children possible
};
WorkBound work_bound(const Scene& scene);
// One line for stderr when the bound is at least kLargeWork rays, else "".
constexpr double kLargeWork = 1e9;
std::string large_work_note(const Scene& scene);

}  // namespace opsila
