#include "scene/camera.h"

#include <cmath>
#include <limits>
#include <sstream>

namespace opsila {

namespace {

// Unit vector, divided by its length in float (the order of operations the
// kernels' FrameParams have always been computed with; normalize multiplies
// by the inverse instead).
Vec3 unit(const Vec3& v) { return v / length(v); }

double dot(const Vec3& a, const double (&b)[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

}  // namespace

std::string format_vec(const Vec3& v) {
  std::ostringstream out;
  out << v[0] << "," << v[1] << "," << v[2];
  return out.str();
}


CameraFrame camera_frame(const CameraDesc& camera, int width, int height) {
  CameraFrame frame;
  frame.eye = camera.eye;
  frame.forward = unit(camera.look_at - camera.eye);
  frame.right = unit(cross(frame.forward, camera.up));
  frame.up = cross(frame.right, frame.forward);
  frame.tan_half_fov = std::tan(camera.fov_deg * 0.5f * static_cast<float>(M_PI) / 180.0f);
  frame.aspect = static_cast<float>(width) / static_cast<float>(height);
  return frame;
}

float spp_offset(int i, int k) { return (static_cast<float>(i) + 0.5f) / static_cast<float>(k); }

std::vector<float> sample_offsets(int spp) {
  const int k = spp_side(spp);
  std::vector<float> offsets(static_cast<std::size_t>(k));
  for (int i = 0; i < k; ++i) offsets[static_cast<std::size_t>(i)] = spp_offset(i, k);
  return offsets;
}

Vec3 primary_direction_at(const CameraFrame& frame, int width, int height, float px, float py) {
  const float s = frame.tan_half_fov, a = frame.aspect;
  const float sx = 2.0f * px / static_cast<float>(width) - 1.0f;
  const float sy = 1.0f - 2.0f * py / static_cast<float>(height);
  return normalize(frame.forward + sx * s * a * frame.right + sy * s * frame.up);
}

Vec3 primary_direction(const CameraFrame& frame, int width, int height, int x, int y) {
  return primary_direction_at(frame, width, height, static_cast<float>(x) + 0.5f, static_cast<float>(y) + 0.5f);
}

bool project_to_pixels(const CameraFrame& frame, int width, int height, const Vec3& point, double& px, double& py) {
  const double d[3] = {double(point[0]) - frame.eye[0], double(point[1]) - frame.eye[1],
                       double(point[2]) - frame.eye[2]};
  const double cz = dot(frame.forward, d);
  if (cz <= 1e-6 * std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) || cz <= 0) return false;
  const double s = frame.tan_half_fov, a = double(width) / height;
  px = ((dot(frame.right, d) / cz) / (s * a) + 1.0) * width * 0.5 - 0.5;
  py = (1.0 - (dot(frame.up, d) / cz) / s) * height * 0.5 - 0.5;
  return true;
}

void check_camera(const CameraDesc& c, const std::string& eye_source, const std::string& up_source,
                  const std::string& parallel_source) {
  double f[3], u[3];
  for (int i = 0; i < 3; ++i) {
    f[i] = static_cast<double>(c.look_at[i]) - c.eye[i];
    u[i] = c.up[i];
  }
  const double f_len = std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
  const double u_len = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
  if (!(f_len > 0) || !std::isfinite(f_len))
    throw InputError(eye_source + ": eye and look-at are the same point (" + format_vec(c.eye) + ")");
  if (!(u_len > 0) || !std::isfinite(u_len)) throw InputError(up_source + ": up vector is zero");
  const double fu[3] = {f[1] * u[2] - f[2] * u[1], f[2] * u[0] - f[0] * u[2], f[0] * u[1] - f[1] * u[0]};
  const double sine = std::sqrt(fu[0] * fu[0] + fu[1] * fu[1] + fu[2] * fu[2]) / (f_len * u_len);
  if (sine < 1e-4)  // nearly parallel: the float basis would be noise
    throw InputError((parallel_source.empty() ? up_source : parallel_source) + " (" + format_vec(c.up) +
                     ") is parallel to the view direction (from eye " +
                     format_vec(c.eye) + " to look-at " + format_vec(c.look_at) + ")");
  // The basis is made in float (camera_frame): a vector whose squared
  // length is not a normal float (below about 1e-19 or above 1.8e19) gives
  // no unit vector, or one rounded off unit, and other camera rays.
  // The forward vector depends on the eye and look-at alone; the right one,
  // made from it and the up vector, fails only through the latter: that
  // source is named.
  const auto normal_square = [](const Vec3& v) {
    const float square = dot(v, v);
    return square >= std::numeric_limits<float>::min() && square <= std::numeric_limits<float>::max();
  };
  const Vec3 view = c.look_at - c.eye;
  const bool forward = normal_square(view);
  if (!forward || !normal_square(c.up) || !normal_square(cross(camera_frame(c, 1, 1).forward, c.up)))
    throw InputError((forward ? up_source : eye_source) + ": the view from eye " + format_vec(c.eye) + " to look-at " +
                     format_vec(c.look_at) + " with up " + format_vec(c.up) + " has no unit vectors in float (" +
                     (forward ? "an up vector too small or too large)" : "a distance too small or too large)"));
}

}  // namespace opsila
