// OpenCL set-up: device listing and choice, checked calls, program build.
#pragma once

#include <CL/opencl.hpp>

#include <cstdint>
#include <functional>
#include <map>
#include <stdexcept>
#include <optional>
#include <string>
#include <vector>

#include "core/host_memory.h"

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
// Platforms that list no device (Mesa's Clover without a GPU; Rusticl unless
// RUSTICL_ENABLE names a driver), by name; and what to do about one, if
// anything is known ("" otherwise).
std::vector<std::string> platforms_without_devices();
std::string no_devices_hint(const std::string& platform_name);

// CONTRACT: empty -> first GPU, else first CPU, else first device. Otherwise an
// index ("2"), "platform:device" ("0:1") or a case-insensitive substring of
// platform/device/vendor name ("pocl", "nvidia"); digits and colons alone
// that are neither index form ("0:", ":") are refused. Throws InputError if none.
DeviceEntry choose_device(const std::string& spec);
// For one of several MPI ranks: a given spec applies as above; without one,
// the ranks on a machine take its GPUs in turn (local rank modulo the GPU
// count), or else its first CPU device.
DeviceEntry choose_rank_device(const std::string& spec, int local_rank);

// What opsila needs from a device, as the device reports it.
struct DeviceCapabilities {
  std::string name, version, opencl_c_version, profile, extensions;
  bool available = true, compiler_available = true;
  cl_ulong local_mem_size = 0;
  std::size_t max_work_group_size = 0;
};
DeviceCapabilities query_capabilities(const cl::Device& device);
// Local memory a work-group needs: the SPMD kernel's (its per-level stats) or
// the exchange plan's, whichever is larger.
std::size_t required_local_mem();
// What the device lacks for opsila, one phrase each; empty when it can run it.
std::vector<std::string> missing_capabilities(const DeviceCapabilities& caps);

// How a runtime is set up. The defaults are what the command line uses.
struct ClRuntimeOptions {
  // Non-empty: OpenCL C source to build instead of the embedded kernels
  // (tests use it); `kernel_source_origin` names it in messages.
  std::string kernel_source, kernel_source_origin;
  // Non-zero: believe the device has at most this many bytes of global
  // memory and of single allocation (tests use it to provoke refusals).
  cl_ulong memory_limit = 0;
  // Non-zero: the work-group size the kernels ask for instead of 64 (a power
  // of two up to 1024), still capped by what each kernel allows.
  std::size_t group_size = 0;
  // How the kernels raise the specular base to Ns (kernels/lib/shading.cl,
  // OPSILA_POW_FP64): automatic takes double precision on a CPU device
  // with cl_khr_fp64 and the device's float pow elsewhere; fp64 is refused
  // (ClError) by a device without doubles.
  enum class SpecularPow { automatic, fp32, fp64 };
  SpecularPow specular_pow = SpecularPow::automatic;
  // The bank walks' node layout (BankQNode or BankNode, quantised_nodes()):
  // automatic takes the quantised one on a GPU, unless OPSILA_QUANT_NODES
  // says otherwise.
  enum class NodeLayout { automatic, floats, quantised };
  NodeLayout node_layout = NodeLayout::automatic;
  // Honour OPSILA_KERNEL_SOURCE=path (a file replacing the embedded kernels),
  // OPSILA_DEVICE_MEMORY_LIMIT=bytes and OPSILA_GROUP_SIZE=N, read when the
  // runtime is created.
  bool read_environment = true;
};

// The OpenCL programs, each built on first use: the renderer's stages, the
// bench's baselines (megakernel, copy, traversal alone), the renderer's
// stages counting each cluster's tests (OPSILA_MEASURE_COST) for the pilot
// frames of --balance measured, and the renderer's stages without the work
// counters (OPSILA_COUNT_WORK=0) for a render that neither --stats nor the
// bench reads them from; and the baselines without them, for the bench's
// timed megakernel frames (as its timed OPSILA frames run without them).
// The two *_stages programs count cycles per stage instead
// (OPSILA_STAGE_CYCLES, kernels/lib/stage_cycles.cl): the bench's breakdown
// frames, where stage_cycles_unavailable() is empty.
enum class KernelProgram {
  render = 0,
  baselines = 1,
  measure = 2,
  render_uncounted = 3,
  baselines_uncounted = 4,
  render_stages = 5,
  baselines_stages = 6
};
constexpr int kKernelPrograms = 7;

class ClRuntime {
 public:
  // Checks the device (missing_capabilities) and throws ClError naming the
  // device and what it lacks; throws InputError for a bad OPSILA_* variable.
  explicit ClRuntime(const DeviceEntry& device, const ClRuntimeOptions& options = {});
  const DeviceEntry& device() const { return device_; }
  cl::Context& context() { return context_; }
  cl::CommandQueue& queue() { return queue_; }
  // Built on first use; throws ClError with the build log.
  cl::Program& program(KernelProgram which = KernelProgram::render);
  cl::Kernel kernel(const char* name, KernelProgram which = KernelProgram::render);
  // Why the stage clocks cannot run here, or empty: they read an x86
  // processor's time-stamp counter, so they need a CPU device on an x86
  // host whose compiler takes the inline assembly (builds both programs).
  std::string stage_cycles_unavailable();
  // Whether the programs walk instances (OPSILA_INSTANCES, set from the
  // banks before their kernels are made): a scene without them keeps the
  // walks it always ran. A change rebuilds each program on its next use.
  void walk_instances(bool on);
  // Limits read from the device (never assumed).
  // The work-group size the kernels ask for (each capped by what it allows):
  // 64, where PoCL measured fastest and a GPU runs two warps or one
  // wavefront; or ClRuntimeOptions::group_size / OPSILA_GROUP_SIZE, to check
  // the kernels with GPU-sized groups (.ci/oclgrind.sh runs 256).
  std::size_t group_size() const { return group_size_; }
  // Whether the kernels take the specular power in double precision
  // (ClRuntimeOptions::specular_pow).
  bool specular_pow_fp64() const { return pow_fp64_; }
  // Whether the kernels are built with -cl-fp32-correctly-rounded-divide-sqrt
  // (the device reports CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT).
  bool exact_divide() const { return exact_divide_; }
  // Whether the device has doubles (cl_khr_fp64): the kernels are built with
  // OPSILA_FP64=1 and the image can be resolved on the device (kernels/resolve.cl).
  bool doubles() const { return doubles_; }
  // Whether the bank walks read BankQNode (walk_nodes, partition/bank_qnode.h)
  // rather than BankNode (ClRuntimeOptions::node_layout).
  bool quantised_nodes() const { return quant_nodes_; }
  cl_ulong max_alloc() const { return max_alloc_; }
  // Device bytes asked for through device_buffer (device/descriptors.h)
  // since the runtime was made: what the memory plan is checked against.
  std::uint64_t allocated_bytes() const { return allocated_; }
  // The same, by the name each buffer was given (several buffers may share one).
  const std::map<std::string, std::uint64_t>& allocations() const { return by_name_; }
  void count_allocation(std::size_t bytes, const std::string& what) {
    allocated_ += bytes;
    by_name_[what] += bytes;
  }
  cl_ulong global_mem() const { return global_mem_; }
  cl_ulong memory_limit() const { return limit_; }  // 0, or the limit that lowered the two above
  // What set global_mem(): "CL_DEVICE_GLOBAL_MEM_SIZE", or the limit that lowered it.
  const std::string& global_mem_source() const { return memory_source_; }
  // global_mem(), or what the address space ulimit -v leaves a CPU device
  // now, where that is less (the host's buffers made since count): what a
  // plan is held to just before it is allocated. Its source, likewise.
  cl_ulong memory_now() const {
    const cl_ulong room = device_.is_gpu ? 0 : address_space_left(kDriverReserve);
    return room > 0 && room < global_mem_ ? room : global_mem_;
  }
  std::string memory_now_source() const {
    return memory_now() < global_mem_ ? "as the address-space limit (ulimit -v) leaves it" : memory_source_;
  }
  // Address space kept for the driver's own mappings (its compiler, the
  // kernels it loads) when ulimit -v bounds a CPU device.
  static constexpr cl_ulong kDriverReserve = cl_ulong(64) << 20;
  std::string description() const;  // "device (platform, driver)"
  // "embedded kernels", or where the replacement source of the render
  // program came from (the baselines are always the embedded ones).
  const std::string& kernel_source_origin() const { return source_origin_; }
  // Seconds spent in clBuildProgram so far (the driver compiling the
  // kernels, or taking them from its cache).
  double build_seconds() const { return build_seconds_; }
  // `note` is told once when a program build takes longer than half a
  // second (or OPSILA_PROGRESS_AFTER, if lower): the driver is compiling,
  // not finding the kernels in its cache. The command line prints it.
  void on_slow_build(std::function<void(const std::string&)> note) { slow_build_note_ = std::move(note); }

 private:
  DeviceEntry device_;
  cl::Context context_;
  cl::CommandQueue queue_;
  cl::Program programs_[kKernelPrograms];
  bool built_[kKernelPrograms] = {};
  bool instances_ = false;  // walk_instances
  std::optional<std::string> stage_cycles_why_;  // stage_cycles_unavailable, once asked
  std::size_t group_size_ = 64;
  bool pow_fp64_ = false;
  bool facet_lanes_ = false;  // -DOPSILA_FACET_LANES: a leaf's facets in vector lanes
  bool quant_nodes_ = false;  // -DOPSILA_QUANT_NODES: the bank walks' nodes quantised
  bool exact_divide_ = false;
  bool doubles_ = false;
  void choose_paths(const DeviceCapabilities& caps, const ClRuntimeOptions& options);
  void set_memory(cl_ulong limit);  // 0: the device's own
  cl_ulong max_alloc_ = 0, global_mem_ = 0, limit_ = 0;
  std::string memory_source_ = "CL_DEVICE_GLOBAL_MEM_SIZE";
  std::uint64_t allocated_ = 0;
  std::map<std::string, std::uint64_t> by_name_;
  std::string source_, source_origin_;  // source_ empty: the embedded kernels
  double build_seconds_ = 0;
  std::function<void(const std::string&)> slow_build_note_;
  bool slow_build_noted_ = false;
  cl_int build(cl::Program& program, const std::string& options);
};

// Throws ClError("<what>: <ERROR_NAME> (<code>)") when code != CL_SUCCESS.
void cl_check(cl_int code, const char* what);

}  // namespace opsila
