// The sequential reference: docs/CONTRACT.md written out plainly for one processor.
// No OpenCL, no banks, no descriptors: one recursive Whitted tracer. It is the
// oracle the tests compare the OpenCL renderer with, and the "sequential host"
// baseline of the benchmark.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include "scene/camera.h"
#include "scene/image.h"
#include "scene/ray_sample.h"
#include "scene/scene.h"

namespace opsila {

class Progress;

// A ray's nearest facet: its index in Scene::triangles (-1: none), or with
// inst >= 0 in the triangles of instance inst's prototype; the ray
// parameter t and CONTRACT's barycentrics b1, b2 of the hit (an instance's in
// its model's frame).
struct FacetHit {
  float t = std::numeric_limits<float>::infinity();
  int tri = -1;
  int inst = -1;  // the instance hit (Scene::instances), -1: a facet of the scene's own
  float b1 = 0, b2 = 0;
};

// Where rays meet the facets, when another library traverses the scene (the
// bench's Embree baseline): the tracer then shades, samples and counts as
// always, on these answers. Called from several threads at once. A hit on
// an instance names it (FacetHit::inst) and its model's triangle.
class FacetQueries {
 public:
  virtual ~FacetQueries() = default;
  // The nearest facet with t > t_min along the unit direction `dir`.
  virtual bool nearest(const Vec3& origin, const Vec3& dir, float t_min, FacetHit& hit) const = 0;
  // Is any facet hit with t in (t_min, t_max)?
  virtual bool occluded(const Vec3& origin, const Vec3& dir, float t_min, float t_max) const = 0;
};

// Holds the scene (by reference: it must outlive the tracer), its epsilon and
// a BVH, or the `queries` it is given instead (which must outlive it too).
// Const after construction, so several threads may render row ranges of one
// tracer at once. The BVHs (the scene's own facets', one per prototype in
// its frame, one over the instances' world boxes) are built on
// `build_threads` threads (0: every hardware thread); each is the same tree
// for any number; given `queries`, only the models' facets are kept (to
// shade the instances' hits).
class ReferenceTracer {
 public:
  explicit ReferenceTracer(const Scene& scene, const FacetQueries* queries = nullptr, int build_threads = 0);
  ~ReferenceTracer();
  ReferenceTracer(const ReferenceTracer&) = delete;
  ReferenceTracer& operator=(const ReferenceTracer&) = delete;

  // Renders rows [y0, y1) into `out`, which must already be sized for the
  // whole image (see blank_image); adds the rays cast to `counts`.
  void render_rows(int y0, int y1, ImageResult& out, RayCounts& counts) const;
  // The whole image into `out` (sized by blank_image), rows split among
  // `threads`; adds the rays to out.rays. With a `progress`, the fraction
  // shown is the rows finished.
  void render_image(ImageResult& out, int threads, Progress* progress = nullptr) const;
  // Pixel value: the mean of the radiance of its scene.spp sample ray trees;
  // also reports the centre ray's primary hit (CONTRACT "Item buffer").
  Vec3 render_pixel(int x, int y, std::int32_t* object_facet, RayCounts& counts) const;
  float epsilon() const { return epsilon_; }
  // The ray trees of about `target_primary` centre rays on a regular pixel
  // lattice, every ray as a segment (scene/ray_sample.h): what the partition
  // weighs the clusters with. Traced a level at a time (the primary rays,
  // then every ray they spawn, ...), each level's segments in its rays'
  // order; at most kMaxSampleRays segments (a deep tree of glass and
  // mirrors is cut there, its last level first).
  //
  // A ray ends at its least hit in the image's hit order
  // (kernels/hit_order.h), a total order: on a scene read in shares each
  // holder finds the least of its own facets and `join` (every holder
  // calling it alike) picks the least of those, which is the whole
  // scene's. The holder of that facet makes its segments' children. The
  // answer is one process's for any number of holders.
  RaySample sample_rays(int target_primary, const SampleJoin* join = nullptr) const;
  static constexpr std::size_t kMaxSampleRays = std::size_t(1) << 20;

  // The tracer's state and rules: host/reference/tracer_impl.h, private to
  // host/reference (named here so that the sample's steps can take it).
  struct Impl;

 private:
  // The prototypes' BVHs and the one over the instances (constructor's).
  void build_instances(int build_threads, float pad);

  const Scene& scene_;
  float epsilon_ = 0;
  std::unique_ptr<Impl> impl_;
};

// The whole image. `threads` > 1 splits rows among threads; the result is the
// same for any thread count (each pixel is computed the same way). With a
// `progress`, the fraction shown is the rows finished.
ImageResult render_reference(const Scene& scene, int threads = 1, Progress* progress = nullptr);

// Rows [y0, y1) only (builds its own tracer): for timing and tests.
void render_reference_rows(const Scene& scene, int y0, int y1, ImageResult& out);

}  // namespace opsila
