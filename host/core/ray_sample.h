// A sample of the rays one frame will trace (every kind: primary, reflected,
// transmitted, shadow), as segments. The partition weights each cluster by
// the sampled rays that cross its box, so that PEs share the expected work
// and not only the facets (machine/partition.h). It changes which PE owns
// which facet, never the image.
#pragma once

#include <cstddef>
#include <limits>
#include <vector>

#include "core/scene.h"

namespace opsila {

struct RaySegment {
  Vec3 origin{}, direction{};
  float t_max = std::numeric_limits<float>::infinity();  // the hit, the light, or none
};

struct RaySample {
  std::vector<RaySegment> rays;
  int stride = 0;  // one primary ray every `stride` pixels in x and in y
};

}  // namespace opsila
