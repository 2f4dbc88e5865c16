// Running the test-only batch kernels (tests/kernels/*_test.cl): one
// runtime built on their program, buffers in and out, and the scene and
// random rays they are tried on.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "scene/scene.h"
#include "device/cl_runtime.h"
#include "test_device.h"
#include "test_scenes.h"

namespace opsila {
const std::string& test_kernel_source();  // generated from tests/kernels/*_test.cl
}

namespace opsila::test {

inline std::unique_ptr<ClRuntime>& batch_slot(bool quantised = false) {
  static std::unique_ptr<ClRuntime> rt[2];
  return rt[quantised ? 1 : 0];
}

// The device with the batch kernels as its program (released when the
// tests end); `quantised`: its bank walks read BankQNode whatever the
// device (partition/bank_qnode.h), otherwise the device's own layout.
inline ClRuntime& batch_runtime(bool quantised = false) {
  std::unique_ptr<ClRuntime>& rt = batch_slot(quantised);
  if (!rt) {
    ClRuntimeOptions o;
    o.kernel_source = test_kernel_source();
    o.kernel_source_origin = "test batch kernels";
    o.read_environment = false;
    if (quantised) o.node_layout = ClRuntimeOptions::NodeLayout::quantised;
    rt = std::make_unique<ClRuntime>(test_device(), o);
  }
  return *rt;
}

class BatchRelease : public ::testing::Environment {
 public:
  void TearDown() override {
    batch_slot(false).reset();
    batch_slot(true).reset();
  }
};
inline ::testing::Environment* const kBatchRelease = ::testing::AddGlobalTestEnvironment(new BatchRelease);

template <typename T, typename A>
cl::Buffer to_device(ClRuntime& rt, const std::vector<T, A>& v) {
  cl_int err = CL_SUCCESS;
  // A zero-sized buffer is invalid: an empty table gets one unread element.
  std::vector<T> data = v.empty() ? std::vector<T>(1) : std::vector<T>(v.begin(), v.end());
  cl::Buffer b(rt.context(), CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR, data.size() * sizeof(T), data.data(), &err);
  cl_check(err, "clCreateBuffer");
  return b;
}

// The kernel's arguments, in order.
template <typename... Args>
void set_args(cl::Kernel& k, const Args&... args) {
  cl_uint at = 0;
  (cl_check(k.setArg(at++, args), "clSetKernelArg"), ...);
}

inline void run_batch(ClRuntime& rt, cl::Kernel& k, std::size_t count) {
  cl_check(rt.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(count), cl::NullRange),
           "clEnqueueNDRangeKernel");
  cl_check(rt.queue().finish(), "clFinish");
}

// Forty icospheres and a floor at random places: many clusters, shared
// edges, overlapping boxes.
inline Scene batch_scene(unsigned seed) {
  Scene s;
  int m = add_material(s, {0.1f, 0.1f, 0.1f}, {0.8f, 0.8f, 0.8f}, {0, 0, 0}, 1, {0, 0, 0}, 1, 1);
  std::mt19937 gen(seed);
  std::uniform_real_distribution<float> pos(-4.0f, 4.0f), radius(0.2f, 1.2f);
  for (int i = 0; i < 40; ++i) add_sphere(s, {pos(gen), pos(gen), pos(gen)}, radius(gen), 1 + i % 2, i, m);
  add_quad(s, {-6, -5, -6}, {6, -5, -6}, {6, -5, 6}, {-6, -5, 6}, 40, m);
  return s;
}

// Rays as the batch kernels read them: org.xyz, dir.xyz (unit), the
// segment (org.w, dir.w). Origins in and around the scene, directions
// uniform over the sphere.
struct RayBatch {
  std::vector<cl_float4> org, dir;
  std::size_t size() const { return org.size(); }
};

inline RayBatch random_rays(std::size_t n, unsigned seed, float tmin, float tmax_lo, float tmax_hi) {
  RayBatch b;
  std::mt19937 gen(seed);
  const bool open = std::isinf(tmax_hi);
  std::uniform_real_distribution<float> pos(-7.0f, 7.0f), u(-1.0f, 1.0f), seg(tmax_lo, open ? tmax_lo : tmax_hi);
  while (b.size() < n) {
    float d[3] = {u(gen), u(gen), u(gen)};
    const float l = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    if (!(l > 0.1f && l <= 1.0f)) continue;  // uniform directions: points inside the unit ball
    b.org.push_back({{pos(gen), pos(gen), pos(gen), tmin}});
    b.dir.push_back({{d[0] / l, d[1] / l, d[2] / l, open ? INFINITY : seg(gen)}});
  }
  return b;
}

}  // namespace opsila::test
