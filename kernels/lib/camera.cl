/* The CONTRACT camera on the device: the primary rays of the item buffer, the
 * primary descriptors and the replicated megakernel. The basis comes from
 * the host (FrameParams, computed once by host/scene/camera.cpp, which also
 * holds the host's copy of these two functions). */
#include "geometry.cl"

/* CONTRACT camera: direction of the ray through image point (px, py); pixel
 * (x, y)'s centre is (x + 0.5, y + 0.5), its sample (i, j) is
 * (x + (i+0.5)/k, y + (j+0.5)/k) with the offsets computed on the host. */
inline float3 primary_direction_at(FrameParams fp, float px, float py) {
  float sx = (2.0f * px / (float)fp.width - 1.0f) * fp.tan_half_fov * fp.aspect;
  float sy = (1.0f - 2.0f * py / (float)fp.height) * fp.tan_half_fov;
  return unit3(load3(fp.forward) + sx * load3(fp.right) + sy * load3(fp.up));
}

/* Primary (centre) ray direction of pixel (x, y). */
inline float3 primary_direction(FrameParams fp, int x, int y) {
  return primary_direction_at(fp, (float)x + 0.5f, (float)y + 0.5f);
}
