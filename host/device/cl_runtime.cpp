#include "device/cl_runtime.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <sstream>

#include "opsila_shared.h"
#include "core/driver_limits.h"
#include "core/env_hooks.h"
#include "core/host_memory.h"
#include "core/input_file.h"
#include "core/progress.h"
#include "scene/scene.h"
#include "core/util.h"

namespace opsila {

const std::string& kernel_source();           // generated from kernels/*.cl
const std::string& baseline_kernel_source();  // generated from kernels/baselines/*.cl

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
    // Memory the plan (device/memory_plan.h) did not foresee, or a driver
    // that promised more than it has: said in words, still exit 3.
    if (code == CL_MEM_OBJECT_ALLOCATION_FAILURE || code == CL_OUT_OF_RESOURCES || code == CL_OUT_OF_HOST_MEMORY)
      os << ": the device ran out of memory (use a smaller --size, fewer --pes or a smaller --bank-capacity)";
    throw ClError(os.str());
  }
}

namespace {

// "OpenCL 1.2 ..." / "OpenCL C 1.2 ...": major * 10 + minor, or -1.
int parse_version(const std::string& text, const char* prefix) {
  int major = 0, minor = 0;
  const std::string format = std::string(prefix) + " %d.%d";
  if (std::sscanf(text.c_str(), format.c_str(), &major, &minor) != 2) return -1;
  return major * 10 + minor;
}

bool has_word(const std::string& list, const std::string& word) {
  std::istringstream in(list);
  std::string w;
  while (in >> w)
    if (w == word) return true;
  return false;
}

}  // namespace

DeviceCapabilities query_capabilities(const cl::Device& d) {
  DeviceCapabilities c;
  c.name = trim_blanks(d.getInfo<CL_DEVICE_NAME>());
  c.version = trim_blanks(d.getInfo<CL_DEVICE_VERSION>());
  c.opencl_c_version = trim_blanks(d.getInfo<CL_DEVICE_OPENCL_C_VERSION>());
  c.profile = trim_blanks(d.getInfo<CL_DEVICE_PROFILE>());
  c.extensions = trim_blanks(d.getInfo<CL_DEVICE_EXTENSIONS>());
  c.available = d.getInfo<CL_DEVICE_AVAILABLE>() != CL_FALSE;
  c.compiler_available = d.getInfo<CL_DEVICE_COMPILER_AVAILABLE>() != CL_FALSE;
  c.local_mem_size = d.getInfo<CL_DEVICE_LOCAL_MEM_SIZE>();
  c.max_work_group_size = d.getInfo<CL_DEVICE_MAX_WORK_GROUP_SIZE>();
  return c;
}

// The SPMD phase's per-level statistics and traffic, or the exchange plan's
// per-PE work-group bases, whichever is larger.
std::size_t required_local_mem() {
  return std::max(std::size_t(OPSILA_MAX_DEPTH) * (OPSILA_STAT_COUNT + OPSILA_TRAFFIC_MAX_PES) * sizeof(cl_uint),
                  std::size_t(OPSILA_SCATTER_PLAN_LOCAL_INTS) * sizeof(cl_int));
}

std::vector<std::string> missing_capabilities(const DeviceCapabilities& c) {
  std::vector<std::string> missing;
  if (!c.available) missing.push_back("it is not available (CL_DEVICE_AVAILABLE is false)");
  const int version = parse_version(c.version, "OpenCL");
  if (version < 12) missing.push_back("OpenCL 1.2 (it reports '" + c.version + "')");
  const int c_version = parse_version(c.opencl_c_version, "OpenCL C");
  if (c_version < 12) missing.push_back("OpenCL C 1.2 (it reports '" + c.opencl_c_version + "')");
  if (!c.compiler_available) missing.push_back("an OpenCL C compiler (CL_DEVICE_COMPILER_AVAILABLE is false)");
  if (c.local_mem_size < required_local_mem())
    missing.push_back(std::to_string(required_local_mem()) + " bytes of local memory (CL_DEVICE_LOCAL_MEM_SIZE is " +
                      std::to_string(c.local_mem_size) + ")");
  if (c.max_work_group_size < 1)
    missing.push_back("work-groups of at least 1 work-item (CL_DEVICE_MAX_WORK_GROUP_SIZE is 0)");
  // Pixel sums are 64-bit fixed point: embedded-profile devices have 64-bit
  // integers only with cles_khr_int64.
  if (c.profile == "EMBEDDED_PROFILE" && !has_word(c.extensions, "cles_khr_int64"))
    missing.push_back("64-bit integers (EMBEDDED_PROFILE without cles_khr_int64)");
  return missing;
}

namespace {

// OPSILA_KERNEL_SOURCE: the embedded kernels are about 120 KiB.
constexpr std::size_t kMaxKernelSourceBytes = std::size_t(16) << 20;

// A work-group size asked for (ClRuntimeOptions::group_size or
// OPSILA_GROUP_SIZE): a power of two from 1 to 1024.
std::size_t checked_group_size(const std::string& text, const std::string& origin) {
  const bool digits = !text.empty() && text.size() <= 4 &&
                      std::all_of(text.begin(), text.end(), [](unsigned char c) { return std::isdigit(c); });
  const std::size_t n = digits ? std::stoul(text) : 0;
  if (n < 1 || n > 1024 || (n & (n - 1)) != 0)
    throw InputError(origin + "=" + text + ": expected a power of two from 1 to 1024");
  return n;
}

}  // namespace

// The kernels' arithmetic and layouts for this device (build options).
void ClRuntime::choose_paths(const DeviceCapabilities& caps, const ClRuntimeOptions& options) {
  // The specular power: PoCL's float pow costs about 80 ns a call on this
  // project's CPUs and is 1 ulp off in about 9% of calls on [0.5, 1];
  // exp2(Ns log2 x) in doubles takes about 16 ns and rounds correctly
  // (docs/BENCHMARKS.md). A GPU may run doubles at a fraction of its float
  // rate, so it keeps its own pow unless asked.
  doubles_ = (" " + caps.extensions + " ").find(" cl_khr_fp64 ") != std::string::npos;
  using SpecularPow = ClRuntimeOptions::SpecularPow;
  if (options.specular_pow == SpecularPow::fp64 && !doubles_)
    throw ClError("device " + device_.device_name + " (" + device_.platform_name +
                  ") has no double precision (cl_khr_fp64) for the specular power in doubles");
  pow_fp64_ = options.specular_pow == SpecularPow::fp64 ||
              (options.specular_pow == SpecularPow::automatic && doubles_ && !device_.is_gpu);

  // Division and square root correctly rounded wherever the device offers
  // it (CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT): OpenCL C 1.2 lets x / y be
  // 2.5 ulp off, and NVIDIA's driver takes that licence, so its camera rays
  // and slab inverses (1 / d) differed from the host's in the last bits and
  // routing entries, hit distances and grazing hits with them. CPUs divide
  // exactly anyway (PoCL's machine code is the same with and without it).
  cl_device_fp_config single_fp = 0;
  cl_check(device_.device.getInfo(CL_DEVICE_SINGLE_FP_CONFIG, &single_fp),
           "clGetDeviceInfo(CL_DEVICE_SINGLE_FP_CONFIG)");
  exact_divide_ = (single_fp & CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT) != 0;

  // A leaf's facets tested in vector lanes (kernels/lib/bvh.cl) where a
  // work-item's vectors fill the device's own (native float width 4 or more:
  // PoCL's CPUs); a device that runs work-items in its lanes (GPUs, Mesa's
  // llvmpipe: width 1) tests them one at a time, as the lanes cost it four
  // tests' work each (llvmpipe: a frame 1.5x slower; docs/BENCHMARKS.md).
  cl_uint native_float = 0;
  cl_check(device_.device.getInfo(CL_DEVICE_NATIVE_VECTOR_WIDTH_FLOAT, &native_float),
           "clGetDeviceInfo(CL_DEVICE_NATIVE_VECTOR_WIDTH_FLOAT)");
  facet_lanes_ = native_float >= 4;
  // The bank walks' nodes quantised (BankQNode, half the bytes) on a GPU,
  // whose walks wait on memory; a CPU's caches hold the float nodes and its
  // walks pay for the decoding (docs/BENCHMARKS.md, Levers).
  using NodeLayout = ClRuntimeOptions::NodeLayout;
  quant_nodes_ = options.node_layout == NodeLayout::automatic ? device_.is_gpu
                                                               : options.node_layout == NodeLayout::quantised;
  const auto q = options.read_environment ? env_hook_number(EnvHook::quant_nodes, 0, 1, "0 or 1") : std::nullopt;
  if (q && options.node_layout == NodeLayout::automatic) quant_nodes_ = *q == 1;
}

ClRuntime::ClRuntime(const DeviceEntry& device, const ClRuntimeOptions& options) : device_(device) {
  if (!device_.is_gpu) check_cpu_driver_environment();
  const DeviceCapabilities caps = query_capabilities(device_.device);
  const std::vector<std::string> missing = missing_capabilities(caps);
  if (!missing.empty()) {
    std::string message =
        "device " + device_.device_name + " (" + device_.platform_name + ") cannot run opsila: it lacks ";
    for (std::size_t i = 0; i < missing.size(); ++i) message += (i ? "; " : "") + missing[i];
    throw ClError(message);
  }

  choose_paths(caps, options);

  source_ = options.kernel_source;
  source_origin_ = source_.empty() ? "embedded kernels"
                                   : (options.kernel_source_origin.empty() ? "kernel source given by the caller"
                                                                           : options.kernel_source_origin);
  cl_ulong limit = options.memory_limit;
  if (options.group_size) group_size_ = checked_group_size(std::to_string(options.group_size), "group size");
  if (options.read_environment) {
    // OPSILA_GROUP_SIZE=N: work-groups of N (capped by each kernel's limit).
    const char* group = env_hook(EnvHook::group_size);
    if (group && *group && options.group_size == 0) group_size_ = checked_group_size(group, "OPSILA_GROUP_SIZE");
    // OPSILA_KERNEL_SOURCE=path: build this file instead of the embedded
    // kernels (to try a kernel change without rebuilding, or to test faults).
    const char* path = env_hook(EnvHook::kernel_source);
    if (path && source_.empty()) {
      source_ = read_named_file("OPSILA_KERNEL_SOURCE=", path, kMaxKernelSourceBytes);
      if (source_.empty()) throw InputError(std::string("OPSILA_KERNEL_SOURCE=") + path + ": the file is empty");
      source_origin_ = std::string("OPSILA_KERNEL_SOURCE=") + path;
    }
    // OPSILA_DEVICE_MEMORY_LIMIT=bytes: plan as if the device had no more.
    if (limit == 0)
      limit = env_hook_number(EnvHook::device_memory_limit, 1, UINT64_MAX, "a positive number of bytes").value_or(0);
  }

  cl_int err = CL_SUCCESS;
  context_ = cl::Context(device_.device, nullptr, nullptr, nullptr, &err);
  cl_check(err, "clCreateContext");
  queue_ = cl::CommandQueue(context_, device_.device, CL_QUEUE_PROFILING_ENABLE, &err);
  cl_check(err, "clCreateCommandQueue");
  set_memory(limit);
}

// The memory plans are held to: the device's, or what a limit leaves.
void ClRuntime::set_memory(cl_ulong limit) {
  max_alloc_ = device_.device.getInfo<CL_DEVICE_MAX_MEM_ALLOC_SIZE>();
  global_mem_ = device_.device.getInfo<CL_DEVICE_GLOBAL_MEM_SIZE>();
  // A CPU device maps its buffers here: past ulimit -v, PoCL fails an assertion.
  const cl_ulong room = device_.is_gpu ? 0 : address_space_left(kDriverReserve);
  if (room > 0 && room < global_mem_ && (limit == 0 || room < limit)) limit = room;
  limit_ = limit;
  if (limit == 0) return;
  memory_source_ = limit == room ? "as the address-space limit (ulimit -v) leaves it" : "as lowered by OPSILA_DEVICE_MEMORY_LIMIT";
  max_alloc_ = std::min(max_alloc_, limit);
  global_mem_ = std::min(global_mem_, limit);
}

std::string ClRuntime::description() const {
  return device_.device_name + " (" + device_.platform_name + ", " + device_.version + ", driver " +
         device_.driver_version + ")";
}

cl::Program& ClRuntime::program(KernelProgram which) {
  const int index = static_cast<int>(which);
  cl::Program& program = programs_[index];
  if (built_[index]) return program;
  const bool render = which != KernelProgram::baselines && which != KernelProgram::baselines_uncounted &&
                      which != KernelProgram::baselines_stages;
  const std::string& source = !render ? baseline_kernel_source() : source_.empty() ? kernel_source() : source_;
  const std::string origin = render ? source_origin_ : "embedded baseline kernels";
  cl_int err = CL_SUCCESS;
  program = cl::Program(context_, source, false, &err);
  cl_check(err, "clCreateProgramWithSource");
  // No fast-math: every device must reproduce the reference's arithmetic.
  std::string options = "-cl-std=CL1.2";
  if (which == KernelProgram::measure) options += " -DOPSILA_MEASURE_COST=1";
  const bool stages = which == KernelProgram::render_stages || which == KernelProgram::baselines_stages;
  if (which == KernelProgram::render_uncounted || which == KernelProgram::baselines_uncounted || stages)
    options += " -DOPSILA_COUNT_WORK=0";
  if (stages) options += " -DOPSILA_STAGE_CYCLES=1";
  if (pow_fp64_) options += " -DOPSILA_POW_FP64=1";
  if (doubles_) options += " -DOPSILA_FP64=1";
  if (instances_) options += " -DOPSILA_INSTANCES=1";
  if (exact_divide_) options += " -cl-fp32-correctly-rounded-divide-sqrt";
  if (facet_lanes_) options += " -DOPSILA_FACET_LANES=1";
  if (quant_nodes_) options += " -DOPSILA_QUANT_NODES=1";
  err = build(program, options);
  if (err != CL_SUCCESS) {
    std::string log;
    program.getBuildInfo(device_.device, CL_PROGRAM_BUILD_LOG, &log);
    log = trim_blanks(log);
    // No diagnostic from the compiler: the build failed around it (PoCL
    // writes its kernel cache while it builds).
    if (log.find("error") == std::string::npos)
      log += (log.empty() ? "" : "\n") + std::string("(no compiler error: the driver could not finish the build; a "
             "full disk or a file-size limit (ulimit -f) where it caches kernels, e.g. POCL_CACHE_DIR, or too "
             "little memory (ulimit -v) fail it)");
    throw ClError(std::string("clBuildProgram: ") + cl_error_name(err) + " (" + std::to_string(err) + ") on " +
                  device_.device_name + " (kernel source: " + origin + "); build log:\n" +
                  log);
  }
  built_[index] = true;
  return program;
}

// clBuildProgram, timed; a build still running after half a second is a
// compile (a cached build takes a few milliseconds), and the user hears so.
cl_int ClRuntime::build(cl::Program& program, const std::string& options) {
  const auto start = std::chrono::steady_clock::now();
  std::optional<SlowNote> note;
  if (slow_build_note_ && !slow_build_noted_)
    note.emplace(std::min(0.5, progress_delay()), [this] {
      slow_build_noted_ = true;
      slow_build_note_("compiling the OpenCL kernels for " + device_.device_name +
                       " (drivers usually cache them, so later runs start sooner)");
    });
  const cl_int err = program.build({device_.device}, options.c_str());
  note.reset();
  build_seconds_ += seconds_since(start);
  return err;
}

void ClRuntime::walk_instances(bool on) {
  if (on == instances_) return;
  instances_ = on;
  for (bool& b : built_) b = false;
}

std::string ClRuntime::stage_cycles_unavailable() {
  if (stage_cycles_why_) return *stage_cycles_why_;
  std::string why;
#if defined(__x86_64__) || defined(__i386__)
  if (!(device_.device.getInfo<CL_DEVICE_TYPE>() & CL_DEVICE_TYPE_CPU)) {
    why = "the stage clocks read an x86 CPU's time-stamp counter; this is not a CPU device";
  } else {
    try {
      program(KernelProgram::render_stages);
      program(KernelProgram::baselines_stages);
    } catch (const ClError&) {
      why = "this device's compiler does not build the stage clocks (x86 inline assembly)";
    }
  }
#else
  why = "the stage clocks read an x86 CPU's time-stamp counter; this host is not x86";
#endif
  stage_cycles_why_ = why;
  return why;
}

cl::Kernel ClRuntime::kernel(const char* name, KernelProgram which) {
  cl_int err = CL_SUCCESS;
  cl::Kernel k(program(which), name, &err);
  cl_check(err, (std::string("clCreateKernel(") + name + ")").c_str());
  return k;
}

}  // namespace opsila
