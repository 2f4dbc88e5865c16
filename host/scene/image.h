// What every renderer hands back (the OpenCL renderer, the sequential
// reference, the megakernel and Embree baselines): the image, its item
// buffer and the rays it took, counted the same way everywhere.
#pragma once

#include <cstdint>
#include <vector>

namespace opsila {

// Rays of one frame (CONTRACT "Statistics"): one primary ray per pixel,
// secondary = reflected + transmitted rays spawned, shadow rays cast.
struct RayCounts {
  std::uint64_t primary = 0;
  std::uint64_t primary_hits = 0;  // primary rays that hit a facet
  std::uint64_t secondary = 0;
  std::uint64_t shadow = 0;
  std::uint64_t total() const { return primary + secondary + shadow; }
  // The same rays by kind (primary hits aside: not every renderer knows them).
  bool same_rays(const RayCounts& o) const {
    return primary == o.primary && secondary == o.secondary && shadow == o.shadow;
  }
  RayCounts& operator+=(const RayCounts& o) {
    primary += o.primary;
    primary_hits += o.primary_hits;
    secondary += o.secondary;
    shadow += o.shadow;
    return *this;
  }
};

struct ImageResult {
  int width = 0, height = 0;
  std::vector<float> rgb;                 // linear, row 0 = top, 3 floats per pixel
  std::vector<std::int32_t> item_buffer;  // (object, facet) per pixel, (-1,-1) on a miss
  RayCounts rays;
};

// An image of width x height with black pixels, (-1,-1) items and no rays.
inline ImageResult blank_image(int width, int height) {
  ImageResult image;
  image.width = width;
  image.height = height;
  image.rgb.assign(std::size_t(width) * std::size_t(height) * 3, 0.0f);
  image.item_buffer.assign(std::size_t(width) * std::size_t(height) * 2, -1);
  return image;
}

}  // namespace opsila
