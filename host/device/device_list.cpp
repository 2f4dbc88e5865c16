// The OpenCL devices this machine offers: listing them (with a word on a
// platform that lists none) and choosing one from --device (CONTRACT.md).
#include <algorithm>
#include <cctype>
#include <cstdlib>

#include "core/errors.h"
#include "core/util.h"
#include "device/cl_runtime.h"

namespace opsila {

namespace {

bool all_digits(const std::string& s) {
  return !s.empty() && s.size() < 9 &&
         std::all_of(s.begin(), s.end(), [](unsigned char c) { return std::isdigit(c); });
}

std::vector<cl::Platform> all_platforms() {
  std::vector<cl::Platform> platforms;
  cl_int err = cl::Platform::get(&platforms);
  if (err == -1001 || (err == CL_SUCCESS && platforms.empty()))
    throw ClError("no OpenCL platform found (clGetPlatformIDs): install an OpenCL driver, e.g. pocl-opencl-icd, or "
                  "raise the limits (ulimit -n, ulimit -v) that kept one from loading");
  cl_check(err, "clGetPlatformIDs");
  return platforms;
}

// The platform's devices; none (not an error) where it reports CL_DEVICE_NOT_FOUND.
std::vector<cl::Device> platform_devices(const cl::Platform& platform) {
  std::vector<cl::Device> devices;
  const cl_int err = platform.getDevices(CL_DEVICE_TYPE_ALL, &devices);
  if (err == CL_DEVICE_NOT_FOUND) return {};
  cl_check(err, "clGetDeviceIDs");
  return devices;
}

}  // namespace

std::vector<std::string> platforms_without_devices() {
  std::vector<std::string> out;
  for (const cl::Platform& p : all_platforms())
    if (platform_devices(p).empty()) out.push_back(trim_blanks(p.getInfo<CL_PLATFORM_NAME>()));
  return out;
}

namespace {

// PoCL's kernel cache folder: POCL_CACHE_DIR, else $XDG_CACHE_HOME/pocl, else
// $HOME/.cache/pocl; "" when none of these is set.
std::string pocl_cache_folder() {
  if (const char* dir = std::getenv("POCL_CACHE_DIR"); dir && *dir) return dir;
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg) return std::string(xdg) + "/pocl";
  if (const char* home = std::getenv("HOME"); home && *home) return std::string(home) + "/.cache/pocl";
  return "";
}

}  // namespace

std::string no_devices_hint(const std::string& platform_name) {
  const std::string name = lower(platform_name);
  if (name == "rusticl")
    return "Rusticl lists a device only for the drivers RUSTICL_ENABLE names, e.g. RUSTICL_ENABLE=llvmpipe";
  // PoCL hides its CPU device when it cannot make its kernel cache (a file
  // in the way, a folder it may not write, /proc), the likeliest cause.
  const std::string cache = pocl_cache_folder();
  if (name == "portable computing language" && !cache.empty())
    return "PoCL lists no device when it cannot create its kernel cache (here " + shown_text(cache) +
           "): set POCL_CACHE_DIR to a folder this user can write";
  return "";
}

std::vector<DeviceEntry> list_devices() {
  const std::vector<cl::Platform> platforms = all_platforms();
  std::vector<DeviceEntry> out;
  for (std::size_t p = 0; p < platforms.size(); ++p) {
    const std::vector<cl::Device> devices = platform_devices(platforms[p]);
    for (std::size_t d = 0; d < devices.size(); ++d) {
      DeviceEntry e;
      e.platform_index = static_cast<int>(p);
      e.device_index = static_cast<int>(d);
      e.flat_index = static_cast<int>(out.size());
      e.platform = platforms[p];
      e.device = devices[d];
      e.platform_name = trim_blanks(platforms[p].getInfo<CL_PLATFORM_NAME>());
      e.device_name = trim_blanks(devices[d].getInfo<CL_DEVICE_NAME>());
      e.vendor = trim_blanks(devices[d].getInfo<CL_DEVICE_VENDOR>());
      e.version = trim_blanks(devices[d].getInfo<CL_DEVICE_VERSION>());
      e.driver_version = trim_blanks(devices[d].getInfo<CL_DRIVER_VERSION>());
      e.is_gpu = (devices[d].getInfo<CL_DEVICE_TYPE>() & CL_DEVICE_TYPE_GPU) != 0;
      out.push_back(e);
    }
  }
  if (out.empty()) {
    // Say which platforms are there, and why one may list nothing.
    std::string names, hint;
    for (const cl::Platform& p : platforms) {
      const std::string name = trim_blanks(p.getInfo<CL_PLATFORM_NAME>());
      names += (names.empty() ? "" : ", ") + name;
      if (hint.empty()) hint = no_devices_hint(name);
    }
    throw ClError("no OpenCL device found on any platform (clGetDeviceIDs; platforms: " + names + ")" +
                  (hint.empty() ? "" : ": " + hint));
  }
  return out;
}

DeviceEntry choose_device(const std::string& given) {
  const std::string spec = trim_blanks(given);  // blanks are no part of an index or a name (all names hold one)
  if (spec.empty() && !given.empty()) throw InputError("--device '" + given + "': blank (see 'opsila devices')");
  std::vector<DeviceEntry> all = list_devices();
  if (spec.empty()) {
    for (auto& e : all)
      if (e.is_gpu) return e;
    for (auto& e : all)
      if (e.device.getInfo<CL_DEVICE_TYPE>() & CL_DEVICE_TYPE_CPU) return e;
    return all.front();
  }
  auto colon = spec.find(':');
  if (colon != std::string::npos && all_digits(spec.substr(0, colon)) && all_digits(spec.substr(colon + 1))) {
    int p = std::stoi(spec.substr(0, colon)), d = std::stoi(spec.substr(colon + 1));
    for (auto& e : all)
      if (e.platform_index == p && e.device_index == d) return e;
    throw InputError("--device " + spec + ": no device " + spec + " (see 'opsila devices')");
  }
  if (all_digits(spec)) {
    int i = std::stoi(spec);
    if (i < static_cast<int>(all.size())) return all[i];
    throw InputError("--device " + spec + ": no device with index " + spec + " (" + std::to_string(all.size()) +
                     " found; see 'opsila devices')");
  }
  // Digits and colons alone are an index that is not well formed, not a
  // name: ":" would otherwise match the colon of a version string.
  if (spec.find_first_not_of("0123456789:") == std::string::npos)
    throw InputError("--device " + spec +
                     ": expected an index, PLATFORM:DEVICE (two indices) or a name (see 'opsila devices')");
  std::string needle = lower(spec);
  for (auto& e : all) {
    std::string hay = lower(e.platform_name + " " + e.platform.getInfo<CL_PLATFORM_VERSION>() + " " + e.device_name +
                            " " + e.vendor + " " + e.version);
    if (hay.find(needle) != std::string::npos) return e;
  }
  // Clover without a GPU, or Rusticl without RUSTICL_ENABLE: the platform is
  // there, its devices are not.
  for (const std::string& name : platforms_without_devices())
    if (lower(name).find(needle) != std::string::npos) {
      const std::string hint = no_devices_hint(name);
      throw InputError("--device " + spec + ": platform '" + name + "' has no devices" +
                       (hint.empty() ? "" : " (" + hint + ")") + " (see 'opsila devices')");
    }
  throw InputError("--device " + spec + ": no OpenCL device matches '" + spec + "' (see 'opsila devices')");
}

DeviceEntry choose_rank_device(const std::string& spec, int local_rank) {
  if (!spec.empty() || local_rank == 0) return choose_device(spec);
  std::vector<DeviceEntry> gpus;
  for (auto& e : list_devices())
    if (e.is_gpu) gpus.push_back(e);
  if (gpus.empty()) return choose_device("");
  return gpus[static_cast<std::size_t>(local_rank) % gpus.size()];
}

}  // namespace opsila
