// The contract (docs/CONTRACT.md) in code, for one processor: the tracer's
// set-up, its pixels and its images (the rules themselves: tracer_impl.h;
// geometry and BVH: reference_bvh.h; the ray sample: ray_sample.cpp).
// Arithmetic is single precision, like the OpenCL kernels.
#include "reference/reference.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <stdexcept>
#include <system_error>
#include <thread>

#include "core/fixed_point.h"
#include "core/progress.h"
#include "reference/tracer_impl.h"

namespace opsila {

ReferenceTracer::ReferenceTracer(const Scene& scene, const FacetQueries* queries, int build_threads)
    : scene_(scene), impl_(new Impl(scene)) {
  // CONTRACT: epsilon = 1e-4 x the diagonal of the bounding box of the facets.
  epsilon_ = scene.epsilon();
  impl_->epsilon = epsilon_;

  impl_->materials = scene.materials;
  // CONTRACT "a face with no material".
  if (impl_->materials.empty()) impl_->materials.push_back(MaterialDesc::default_material());
  check_hit_order_ids(scene);
  const int materials = static_cast<int>(impl_->materials.size());
  impl_->tris = reference::make_tris(scene.triangles, materials);
  impl_->queries = queries;
  const float pad = static_cast<float>(1e-5 * scene.diagonal()) + 1e-30f;
  if (!queries) impl_->bvh = reference::build_bvh(impl_->tris, scene.triangles, pad, build_threads);
  build_instances(build_threads, pad);  // the queries answer instances too, the models' facets shade them
  impl_->frame = camera_frame(scene.camera, scene.width, scene.height);
}

ReferenceTracer::~ReferenceTracer() = default;

void ReferenceTracer::build_instances(int build_threads, float pad) {
  const Scene& scene = scene_;
  const int materials = static_cast<int>(impl_->materials.size());
  // Each prototype once, in its frame, padded for its own size.
  for (const Prototype& p : scene.prototypes) {
    Impl::Model model;
    model.tris = reference::make_tris(p.triangles, materials);
    Vec3 lo = splat(INFINITY), hi = splat(-INFINITY);
    for (const Triangle& t : p.triangles) {
      lo = min(lo, min(t.v0, min(t.v1, t.v2)));
      hi = max(hi, max(t.v0, max(t.v1, t.v2)));
    }
    const float model_pad = p.triangles.empty() ? 0.0f : static_cast<float>(1e-5 * box_diagonal(lo, hi)) + 1e-30f;
    if (!impl_->queries) model.bvh = reference::build_bvh(model.tris, p.triangles, model_pad, build_threads);
    impl_->models.push_back(std::move(model));
  }
  if (impl_->queries) return;
  // The instances' world boxes, padded as the scene's nodes are.
  const std::size_t n = scene.instances.size();
  std::vector<Vec3> lo_of(n), hi_of(n);
  impl_->inst_boxes.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    instance_holding_box(scene, scene.instances[i], lo_of[i], hi_of[i]);
    impl_->inst_boxes[i] = {lo_of[i] - splat(pad), hi_of[i] + splat(pad)};
  }
  impl_->inst_bvh = reference::build_bvh(lo_of, hi_of, std::vector<bool>(n, true), pad, build_threads);
}

Vec3 ReferenceTracer::render_pixel(int x, int y, std::int32_t* object_facet,
                                   RayCounts& counts) const {
  const Scene& scene = scene_;
  const Vec3 eye = scene.camera.eye;
  // CONTRACT "Camera": a k x k grid of samples; the pixel is their mean.
  const int k = spp_side(scene.spp);
  double sum[3] = {0.0, 0.0, 0.0};
  Hit centre;
  for (int j = 0; j < k; ++j) {
    for (int i = 0; i < k; ++i) {
      const float px = static_cast<float>(x) + spp_offset(i, k), py = static_cast<float>(y) + spp_offset(j, k);
      const Vec3 dir = primary_direction_at(impl_->frame, scene.width, scene.height, px, py);
      ++counts.primary;
      Vec3 sample = splat(0.0f);
      // Primary rays accept any t > 0 (only secondary and shadow rays skip t <= epsilon).
      const Hit hit = impl_->trace(eye, dir, 0.0f, 0, splat(1.0f), sample, counts);
      if (hit.tri >= 0) ++counts.primary_hits;
      if (2 * i + 1 == k && 2 * j + 1 == k) centre = hit;  // odd k: this sample is the centre ray
      for (int c = 0; c < 3; ++c) sum[c] += double(sample[c]);
    }
  }
  if (object_facet) {
    if (k % 2 == 0) {  // even k: the centre ray is not a sample; find its hit alone
      const Vec3 dir = primary_direction(impl_->frame, scene.width, scene.height, x, y);
      impl_->nearest(eye, dir, 0.0f, centre);
    }
    impl_->item_ids(centre, object_facet);
  }
  // Saturated as the fixed-point sums of the other renderers are.
  for (int c = 0; c < 3; ++c) sum[c] = saturate_sum(sum[c]);
  Vec3 mean;
  for (int c = 0; c < 3; ++c) mean[c] = static_cast<float>(sum[c] / static_cast<double>(scene.spp));
  return mean;
}

void ReferenceTracer::render_rows(int y0, int y1, ImageResult& out, RayCounts& counts) const {
  const int w = scene_.width;
  y0 = std::max(y0, 0);
  y1 = std::min(y1, scene_.height);
  for (int y = y0; y < y1; ++y) {
    for (int x = 0; x < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      const Vec3 c = render_pixel(x, y, &out.item_buffer[2 * i], counts);
      out.rgb[3 * i + 0] = c[0];
      out.rgb[3 * i + 1] = c[1];
      out.rgb[3 * i + 2] = c[2];
    }
  }
}

void ReferenceTracer::render_image(ImageResult& image, int threads, Progress* progress) const {
  const Scene& scene = scene_;
  threads = std::max(1, std::min(threads, scene.height));
  if (threads == 1 && !progress) {
    render_rows(0, scene.height, image, image.rays);
    return;
  }
  // Interleaved bands of rows balance cheap and expensive parts of the image.
  constexpr int kBand = 4;
  std::vector<RayCounts> counts(threads);
  std::atomic<int> rows_done{0};
  std::atomic<std::uint64_t> rays_done{0};
  if (progress) progress->start();
  const auto bands = [&](int w) {
    for (int y = w * kBand; y < scene.height; y += threads * kBand) {
      const std::uint64_t before = counts[w].total();
      render_rows(y, y + kBand, image, counts[w]);
      rays_done += counts[w].total() - before;
      rows_done += std::min(kBand, scene.height - y);
    }
  };
  std::vector<std::thread> workers;
  int started = 0;
  try {
    for (; started < threads; ++started) workers.emplace_back(bands, started);
  } catch (const std::system_error&) {
    // A thread the system will not start (ulimit -u, -v): this thread
    // renders the bands of those that did not.
  }
  for (int w = started; w < threads; ++w) bands(w);
  // The calling thread only watches: rows finished out of all rows.
  while (progress && rows_done.load() < scene.height) {
    if (progress->due()) progress->report(double(rows_done.load()) / scene.height, rays_done.load());
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  for (std::thread& t : workers) t.join();
  for (const RayCounts& c : counts) image.rays += c;
  if (progress && progress->due()) progress->report(1.0, image.rays.total());
}

ImageResult render_reference(const Scene& scene, int threads, Progress* progress) {
  ImageResult image = blank_image(scene.width, scene.height);
  const ReferenceTracer tracer(scene);
  tracer.render_image(image, threads, progress);
  return image;
}

void render_reference_rows(const Scene& scene, int y0, int y1, ImageResult& out) {
  const ReferenceTracer tracer(scene);
  tracer.render_rows(y0, y1, out, out.rays);
}

}  // namespace opsila
