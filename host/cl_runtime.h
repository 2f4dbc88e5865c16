// OpenCL set-up: device listing and choice, checked calls, program build.
#pragma once

#include <CL/opencl.hpp>

#include <stdexcept>
#include <string>
#include <vector>

namespace opsila {

// A failed OpenCL call or driver fault: what() names the call and the error.
struct ClError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

const char* cl_error_name(cl_int code);

struct DeviceEntry {
  int platform_index = 0, device_index = 0, flat_index = 0;
  cl::Platform platform;
  cl::Device device;
  std::string platform_name, device_name, vendor, version, driver_version;
  bool is_gpu = false;
};

std::vector<DeviceEntry> list_devices();  // throws ClError when there is no platform

// SPEC: empty -> first GPU, else first CPU, else first device. Otherwise an
// index ("2"), "platform:device" ("0:1") or a case-insensitive substring of
// platform/device/vendor name ("pocl", "nvidia"). Throws InputError if none.
DeviceEntry choose_device(const std::string& spec);

class ClRuntime {
 public:
  explicit ClRuntime(const DeviceEntry& device);
  const DeviceEntry& device() const { return device_; }
  cl::Context& context() { return context_; }
  cl::CommandQueue& queue() { return queue_; }
  cl::Program& program();  // built on first use; throws ClError with the build log
  cl::Kernel kernel(const char* name);
  // Limits read from the device (never assumed).
  std::size_t max_work_group_size() const { return max_wg_; }
  cl_ulong max_alloc() const { return max_alloc_; }
  cl_ulong global_mem() const { return global_mem_; }
  std::string description() const;  // "device (platform, driver)"
  double last_build_seconds() const { return build_seconds_; }

 private:
  DeviceEntry device_;
  cl::Context context_;
  cl::CommandQueue queue_;
  cl::Program program_;
  bool built_ = false;
  std::size_t max_wg_ = 1;
  cl_ulong max_alloc_ = 0, global_mem_ = 0;
  double build_seconds_ = 0;
};

// Throws ClError("<what>: <ERROR_NAME> (<code>)") when code != CL_SUCCESS.
void cl_check(cl_int code, const char* what);

}  // namespace opsila
