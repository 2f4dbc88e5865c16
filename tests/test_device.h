// The OpenCL device under test, shared by the test programs.
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <memory>
#include <vector>

#include "device/cl_runtime.h"

namespace opsila::test {

// OPSILA_TEST_DEVICE takes any --device value; unset, the default device.
inline const char* test_device_spec() {
  const char* spec = std::getenv("OPSILA_TEST_DEVICE");
  return spec ? spec : "";
}

inline DeviceEntry test_device() { return choose_device(test_device_spec()); }

inline std::unique_ptr<ClRuntime>& runtime_slot() {
  static std::unique_ptr<ClRuntime> rt;
  return rt;
}

// One runtime for the whole test program, released when the tests end:
// some drivers (Oclgrind) crash when OpenCL objects outlive main().
inline ClRuntime& shared_runtime() {
  std::unique_ptr<ClRuntime>& rt = runtime_slot();
  if (!rt) rt = std::make_unique<ClRuntime>(test_device());
  return *rt;
}

class RuntimeRelease : public ::testing::Environment {
 public:
  void TearDown() override { runtime_slot().reset(); }
};
inline ::testing::Environment* const kRuntimeRelease = ::testing::AddGlobalTestEnvironment(new RuntimeRelease);

// The first n values of a device buffer.
template <typename T>
std::vector<T> from_device(ClRuntime& rt, const cl::Buffer& b, std::size_t n) {
  std::vector<T> v(n);
  if (n) cl_check(rt.queue().enqueueReadBuffer(b, CL_TRUE, 0, n * sizeof(T), v.data()), "clEnqueueReadBuffer");
  return v;
}

}  // namespace opsila::test
