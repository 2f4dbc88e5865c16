#include "cl_runtime.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <sstream>

#include "scene.h"

namespace opsila {

const std::string& kernel_source();  // generated from kernels/*.cl

const char* cl_error_name(cl_int code) {
  switch (code) {
#define OPSILA_CASE(x) \
  case x:              \
    return #x;
    OPSILA_CASE(CL_SUCCESS)
    OPSILA_CASE(CL_DEVICE_NOT_FOUND)
    OPSILA_CASE(CL_DEVICE_NOT_AVAILABLE)
    OPSILA_CASE(CL_COMPILER_NOT_AVAILABLE)
    OPSILA_CASE(CL_MEM_OBJECT_ALLOCATION_FAILURE)
    OPSILA_CASE(CL_OUT_OF_RESOURCES)
    OPSILA_CASE(CL_OUT_OF_HOST_MEMORY)
    OPSILA_CASE(CL_PROFILING_INFO_NOT_AVAILABLE)
    OPSILA_CASE(CL_MEM_COPY_OVERLAP)
    OPSILA_CASE(CL_IMAGE_FORMAT_MISMATCH)
    OPSILA_CASE(CL_IMAGE_FORMAT_NOT_SUPPORTED)
    OPSILA_CASE(CL_BUILD_PROGRAM_FAILURE)
    OPSILA_CASE(CL_MAP_FAILURE)
    OPSILA_CASE(CL_MISALIGNED_SUB_BUFFER_OFFSET)
    OPSILA_CASE(CL_EXEC_STATUS_ERROR_FOR_EVENTS_IN_WAIT_LIST)
    OPSILA_CASE(CL_COMPILE_PROGRAM_FAILURE)
    OPSILA_CASE(CL_LINKER_NOT_AVAILABLE)
    OPSILA_CASE(CL_LINK_PROGRAM_FAILURE)
    OPSILA_CASE(CL_DEVICE_PARTITION_FAILED)
    OPSILA_CASE(CL_KERNEL_ARG_INFO_NOT_AVAILABLE)
    OPSILA_CASE(CL_INVALID_VALUE)
    OPSILA_CASE(CL_INVALID_DEVICE_TYPE)
    OPSILA_CASE(CL_INVALID_PLATFORM)
    OPSILA_CASE(CL_INVALID_DEVICE)
    OPSILA_CASE(CL_INVALID_CONTEXT)
    OPSILA_CASE(CL_INVALID_QUEUE_PROPERTIES)
    OPSILA_CASE(CL_INVALID_COMMAND_QUEUE)
    OPSILA_CASE(CL_INVALID_HOST_PTR)
    OPSILA_CASE(CL_INVALID_MEM_OBJECT)
    OPSILA_CASE(CL_INVALID_IMAGE_FORMAT_DESCRIPTOR)
    OPSILA_CASE(CL_INVALID_IMAGE_SIZE)
    OPSILA_CASE(CL_INVALID_SAMPLER)
    OPSILA_CASE(CL_INVALID_BINARY)
    OPSILA_CASE(CL_INVALID_BUILD_OPTIONS)
    OPSILA_CASE(CL_INVALID_PROGRAM)
    OPSILA_CASE(CL_INVALID_PROGRAM_EXECUTABLE)
    OPSILA_CASE(CL_INVALID_KERNEL_NAME)
    OPSILA_CASE(CL_INVALID_KERNEL_DEFINITION)
    OPSILA_CASE(CL_INVALID_KERNEL)
    OPSILA_CASE(CL_INVALID_ARG_INDEX)
    OPSILA_CASE(CL_INVALID_ARG_VALUE)
    OPSILA_CASE(CL_INVALID_ARG_SIZE)
    OPSILA_CASE(CL_INVALID_KERNEL_ARGS)
    OPSILA_CASE(CL_INVALID_WORK_DIMENSION)
    OPSILA_CASE(CL_INVALID_WORK_GROUP_SIZE)
    OPSILA_CASE(CL_INVALID_WORK_ITEM_SIZE)
    OPSILA_CASE(CL_INVALID_GLOBAL_OFFSET)
    OPSILA_CASE(CL_INVALID_EVENT_WAIT_LIST)
    OPSILA_CASE(CL_INVALID_EVENT)
    OPSILA_CASE(CL_INVALID_OPERATION)
    OPSILA_CASE(CL_INVALID_GL_OBJECT)
    OPSILA_CASE(CL_INVALID_BUFFER_SIZE)
    OPSILA_CASE(CL_INVALID_MIP_LEVEL)
    OPSILA_CASE(CL_INVALID_GLOBAL_WORK_SIZE)
    OPSILA_CASE(CL_INVALID_PROPERTY)
    OPSILA_CASE(CL_INVALID_IMAGE_DESCRIPTOR)
    OPSILA_CASE(CL_INVALID_COMPILER_OPTIONS)
    OPSILA_CASE(CL_INVALID_LINKER_OPTIONS)
    OPSILA_CASE(CL_INVALID_DEVICE_PARTITION_COUNT)
#undef OPSILA_CASE
    case -1001:
      return "CL_PLATFORM_NOT_FOUND_KHR (no OpenCL platform: is an ICD installed?)";
    default:
      return "unknown OpenCL error";
  }
}

void cl_check(cl_int code, const char* what) {
  if (code != CL_SUCCESS) {
    std::ostringstream os;
    os << what << ": " << cl_error_name(code) << " (" << code << ")";
    throw ClError(os.str());
  }
}

namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

std::string trim(std::string s) {
  while (!s.empty() && (s.back() == '\0' || std::isspace(static_cast<unsigned char>(s.back())))) s.pop_back();
  return s;
}

bool all_digits(const std::string& s) {
  return !s.empty() && s.size() < 9 &&
         std::all_of(s.begin(), s.end(), [](unsigned char c) { return std::isdigit(c); });
}

}  // namespace

std::vector<DeviceEntry> list_devices() {
  std::vector<cl::Platform> platforms;
  cl_int err = cl::Platform::get(&platforms);
  if (err == -1001 || (err == CL_SUCCESS && platforms.empty()))
    throw ClError("no OpenCL platform found (clGetPlatformIDs): install an OpenCL driver, e.g. pocl-opencl-icd");
  cl_check(err, "clGetPlatformIDs");
  std::vector<DeviceEntry> out;
  for (std::size_t p = 0; p < platforms.size(); ++p) {
    std::vector<cl::Device> devices;
    err = platforms[p].getDevices(CL_DEVICE_TYPE_ALL, &devices);
    if (err == CL_DEVICE_NOT_FOUND) continue;
    cl_check(err, "clGetDeviceIDs");
    for (std::size_t d = 0; d < devices.size(); ++d) {
      DeviceEntry e;
      e.platform_index = static_cast<int>(p);
      e.device_index = static_cast<int>(d);
      e.flat_index = static_cast<int>(out.size());
      e.platform = platforms[p];
      e.device = devices[d];
      e.platform_name = trim(platforms[p].getInfo<CL_PLATFORM_NAME>());
      e.device_name = trim(devices[d].getInfo<CL_DEVICE_NAME>());
      e.vendor = trim(devices[d].getInfo<CL_DEVICE_VENDOR>());
      e.version = trim(devices[d].getInfo<CL_DEVICE_VERSION>());
      e.driver_version = trim(devices[d].getInfo<CL_DRIVER_VERSION>());
      e.is_gpu = (devices[d].getInfo<CL_DEVICE_TYPE>() & CL_DEVICE_TYPE_GPU) != 0;
      out.push_back(e);
    }
  }
  if (out.empty()) throw ClError("no OpenCL device found on any platform (clGetDeviceIDs)");
  return out;
}

DeviceEntry choose_device(const std::string& spec) {
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
  std::string needle = lower(spec);
  for (auto& e : all) {
    std::string hay = lower(e.platform_name + " " + e.platform.getInfo<CL_PLATFORM_VERSION>() + " " + e.device_name +
                            " " + e.vendor + " " + e.version);
    if (hay.find(needle) != std::string::npos) return e;
  }
  throw InputError("--device " + spec + ": no OpenCL device matches '" + spec + "' (see 'opsila devices')");
}

ClRuntime::ClRuntime(const DeviceEntry& device) : device_(device) {
  cl_int err = CL_SUCCESS;
  context_ = cl::Context(device_.device, nullptr, nullptr, nullptr, &err);
  cl_check(err, "clCreateContext");
  queue_ = cl::CommandQueue(context_, device_.device, CL_QUEUE_PROFILING_ENABLE, &err);
  cl_check(err, "clCreateCommandQueue");
  max_wg_ = device_.device.getInfo<CL_DEVICE_MAX_WORK_GROUP_SIZE>();
  max_alloc_ = device_.device.getInfo<CL_DEVICE_MAX_MEM_ALLOC_SIZE>();
  global_mem_ = device_.device.getInfo<CL_DEVICE_GLOBAL_MEM_SIZE>();
  if (device_.device.getInfo<CL_DEVICE_COMPILER_AVAILABLE>() == CL_FALSE)
    throw ClError("device " + device_.device_name + " has no OpenCL C compiler (CL_DEVICE_COMPILER_AVAILABLE)");
}

std::string ClRuntime::description() const {
  return device_.device_name + " (" + device_.platform_name + ", " + device_.version + ", driver " +
         device_.driver_version + ")";
}

cl::Program& ClRuntime::program() {
  if (built_) return program_;
  auto t0 = std::chrono::steady_clock::now();
  cl_int err = CL_SUCCESS;
  program_ = cl::Program(context_, kernel_source(), false, &err);
  cl_check(err, "clCreateProgramWithSource");
  // No fast-math: every device must reproduce the reference's arithmetic.
  err = program_.build({device_.device}, "-cl-std=CL1.2");
  if (err != CL_SUCCESS) {
    std::string log;
    program_.getBuildInfo(device_.device, CL_PROGRAM_BUILD_LOG, &log);
    throw ClError(std::string("clBuildProgram: ") + cl_error_name(err) + " (" + std::to_string(err) + ") on " +
                  device_.device_name + "; build log:\n" + trim(log));
  }
  build_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  built_ = true;
  return program_;
}

cl::Kernel ClRuntime::kernel(const char* name) {
  cl_int err = CL_SUCCESS;
  cl::Kernel k(program(), name, &err);
  cl_check(err, (std::string("clCreateKernel(") + name + ")").c_str());
  return k;
}

}  // namespace opsila
