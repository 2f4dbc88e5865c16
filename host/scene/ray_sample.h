// A sample of the rays one frame will trace (every kind: primary, reflected,
// transmitted, shadow), as segments. The partition weights each cluster by
// the sampled rays that cross its box, so that PEs share the expected work
// and not only the facets (partition/partition.h). It changes which PE owns
// which facet, never the image.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <vector>

#include "scene/scene.h"

namespace opsila {

struct RaySegment {
  Vec3 origin{}, direction{};
  float t_max = std::numeric_limits<float>::infinity();  // the hit, the light, or none
};

struct RaySample {
  std::vector<RaySegment> rays;
  int stride = 0;  // one primary ray every `stride` pixels in x and in y
};

// Primary rays sampled for --balance work: about one in 30 pixels at
// 800x600, a few percent of a frame's time on the host.
constexpr int kBalanceSampleRays = 16000;

// How the holders of a scene read in shares (one per MPI rank) trace the
// sample together (ReferenceTracer::sample_rays): each finds its own
// facets' nearest hits, and these join the others' (mpi/ranks.h).
// Every holder makes the same calls in the same order.
class SampleJoin {
 public:
  virtual ~SampleJoin() = default;
  virtual int holder() const = 0;  // this holder's number, from 0
  // The element-wise minimum over every holder, in place.
  virtual void min(std::vector<std::uint64_t>& values) const = 0;
  // Every holder's bytes, concatenated in holder order.
  virtual std::vector<unsigned char> all_gather(const std::vector<unsigned char>& mine) const = 0;
};

// What traces the sample of a scene (whole, or a share with the join of the
// other holders): ReferenceTracer::sample_rays, handed down by the command
// line, since the machine does not include the reference tracer.
using RaySampler = std::function<RaySample(const Scene& scene, const SampleJoin* join)>;

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
