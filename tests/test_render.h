// What the image tests share: a bare model framed as the command line frames
// it, the OpenCL render on the shared device, and its agreement with the
// sequential reference.
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "prepare/prepare_banks.h"
#include "formats/json/scene_file.h"
#include "frame/renderer.h"
#include "reference/reference.h"
#include "test_device.h"
#include "test_util.h"

namespace opsila::test {

// A model file as `opsila render` shows it: framed, lit from the eye.
inline Scene framed_model(const std::string& path, int width, int height) {
  Scene s = load_scene(path);
  s.width = width;
  s.height = height;
  Vec3 lo, hi;
  s.bounds(lo, hi);
  s.camera = frame_bounds(lo, hi, 45.0f, float(width) / float(height));
  s.lights.push_back({s.camera.eye, {1, 1, 1}});
  return s;
}

inline RenderResult render_on_pes(const Scene& s, int pes) {
  RenderSettings rs;
  rs.num_pes = pes;
  return render(s, rs, shared_runtime());
}

// Within what float rounding across implementations allows: PSNR, the share
// of values off by more than 2 levels, and the share of pixels whose first
// hit (object, facet) is the reference's.
inline void expect_near_reference(const RenderResult& r, const ImageResult& ref, double max_off,
                                  double min_agreement) {
  EXPECT_GE(clamped_psnr(r.rgb, ref.rgb), 40.0);
  EXPECT_LE(fraction_off(r.rgb, ref.rgb, 2), max_off);
  EXPECT_GE(item_agreement(r.item_buffer, ref.item_buffer), min_agreement);
}

}  // namespace opsila::test
