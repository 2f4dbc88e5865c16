// The camera (CONTRACT "Camera"), in one place: the check that a basis exists,
// the basis f, r, u with s = tan(fov/2) and a = W/H (computed in float once,
// as the kernels receive it), the primary ray of a pixel, and the projection
// of a point back to pixel coordinates.
#pragma once

#include <string>
#include <vector>

#include "scene/scene.h"

namespace opsila {

struct CameraFrame {
  Vec3 eye, forward, right, up;
  float tan_half_fov = 1, aspect = 1;
};

// The basis in float: f = normalize(look_at - eye), r = normalize(f x up),
// u = r x f. The renderer's FrameParams, the megakernel, the Embree baseline
// and the reference all take it from here.
CameraFrame camera_frame(const CameraDesc& camera, int width, int height);

// Unit direction of pixel (x, y)'s primary ray (through the pixel centre).
Vec3 primary_direction(const CameraFrame& frame, int width, int height, int x, int y);
// Samples per pixel (CONTRACT "Camera"), N = k*k: sample i (0..k-1) sits at
// (i + 0.5) / k inside its pixel along each axis, computed once here in float
// so that every device and the reference use the same bits (k = 1 gives
// exactly 0.5, the centre ray). sample_offsets(N) lists them for i = 0..k-1.
float spp_offset(int i, int k);
std::vector<float> sample_offsets(int spp);

// Unit direction of the ray through image point (px, py): px = x + 0.5 is
// pixel x's centre, px = x + spp_offset(i, k) its sample i (CONTRACT's k x k grid).
Vec3 primary_direction_at(const CameraFrame& frame, int width, int height, float px, float py);

// Where `point` lands on the screen, in continuous pixel coordinates (pixel
// centres at integers). False when the point is behind the eye (or on its
// plane), where no projection exists.
bool project_to_pixels(const CameraFrame& frame, int width, int height, const Vec3& point, double& px, double& py);

// "x,y,z" as the camera's messages write a point.
std::string format_vec(const Vec3& v);

// Throws InputError unless the basis exists: eye != look-at, up non-zero and
// not parallel to the view direction. The sources name the flags or the file
// in the message.
// `parallel_source` names an up parallel to the view ("" : up_source): where
// the eye or look-at of a flag made it so, the flag.
void check_camera(const CameraDesc& camera, const std::string& eye_source, const std::string& up_source,
                  const std::string& parallel_source = "");

}  // namespace opsila
