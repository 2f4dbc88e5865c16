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

// The work a pilot frame measured (--balance measured): the SPMD phase's
// ray-box and ray-facet tests, counted per cluster and level on the device,
// then spread evenly over each cluster's facets, so that any later grouping
// of the facets (other clusters, cut clusters) can sum its own share.
// per_facet[t * levels + l]: scene triangle t, level l.
struct MeasuredWork {
  int levels = 0;
  std::vector<float> per_facet;
  bool empty() const { return levels == 0 || per_facet.empty(); }
};

}  // namespace opsila
