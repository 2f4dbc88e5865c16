// The sequential reference: SPEC.md written out plainly for one processor.
// No OpenCL, no banks, no descriptors: one recursive Whitted tracer. It is the
// oracle the tests compare the OpenCL renderer with, and the "sequential host"
// baseline of the benchmark.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "core/camera.h"
#include "core/scene.h"

namespace opsila {

// Rays cast, counted as RenderStats counts them.
struct ReferenceCounts {
  std::uint64_t primary = 0;       // one per pixel
  std::uint64_t secondary = 0;     // reflected + transmitted rays spawned
  std::uint64_t shadow = 0;        // shadow rays cast (only where n.Lv > 0)
  std::uint64_t primary_hits = 0;  // pixels whose primary ray hit a facet
  std::uint64_t total() const { return primary + secondary + shadow; }
  ReferenceCounts& operator+=(const ReferenceCounts& o);
};

struct ReferenceImage {
  int width = 0, height = 0;
  std::vector<float> rgb;                 // linear, row 0 = top, 3 floats per pixel
  std::vector<std::int32_t> item_buffer;  // (object, facet) per pixel, (-1,-1) on miss
  ReferenceCounts counts;
};

// Holds the scene (by reference: it must outlive the tracer), its epsilon and
// a BVH. Const after construction, so several threads may render row ranges
// of one tracer at once.
class ReferenceTracer {
 public:
  explicit ReferenceTracer(const Scene& scene);
  ~ReferenceTracer();
  ReferenceTracer(const ReferenceTracer&) = delete;
  ReferenceTracer& operator=(const ReferenceTracer&) = delete;

  // Renders rows [y0, y1) into `out`, which must already be sized for the
  // whole image (see make_reference_image); adds the rays cast to `counts`.
  void render_rows(int y0, int y1, ReferenceImage& out, ReferenceCounts& counts) const;
  // Radiance of the ray tree rooted at one pixel; also reports the primary hit.
  Vec3 render_pixel(int x, int y, std::int32_t* object_facet, ReferenceCounts& counts) const;
  float epsilon() const { return epsilon_; }

 private:
  struct Impl;
  const Scene& scene_;
  float epsilon_ = 0;
  std::unique_ptr<Impl> impl_;
};

// An image of the scene's size with zeroed pixels and (-1,-1) items.
ReferenceImage make_reference_image(const Scene& scene);

// The whole image. `threads` > 1 splits rows among threads; the result is the
// same for any thread count (each pixel is computed the same way).
ReferenceImage render_reference(const Scene& scene, int threads = 1);

// Rows [y0, y1) only (builds its own tracer): for timing and tests.
void render_reference_rows(const Scene& scene, int y0, int y1, ReferenceImage& out);

}  // namespace opsila
