// Device-side descriptor vectors and the SIMD scatter that moves them
// between banks. Shared by the renderer, the tests and the benchmarks.
#pragma once

#include <string>
#include <vector>

#include "machine/cl_runtime.h"
#include "opsila_shared.h"

namespace opsila {

struct LaunchRecord;

// Checked buffer creation: refuses (with the numbers) what the device cannot hold.
cl::Buffer device_buffer(ClRuntime& rt, std::size_t bytes, const char* what);

// Sets the first `bytes` of a buffer to zero with plain writes (enqueued, not
// waited for). Not clEnqueueFillBuffer: Oclgrind's uninitialized-value check
// does not count a fill as a write, and the kernels must stay checkable
// (docs/RELIABILITY.md).
void zero_buffer(ClRuntime& rt, const cl::Buffer& b, std::size_t bytes, const char* what);

template <typename T>
cl::Buffer upload(ClRuntime& rt, const std::vector<T>& v, const char* what) {
  cl::Buffer b = device_buffer(rt, std::max<std::size_t>(1, v.size()) * sizeof(T), what);
  if (!v.empty())
    cl_check(rt.queue().enqueueWriteBuffer(b, CL_TRUE, 0, v.size() * sizeof(T), v.data()),
             (std::string("clEnqueueWriteBuffer(") + what + ")").c_str());
  return b;
}

// One set of descriptor vectors, structure of arrays (see kernels/lib/descriptor.cl):
// org (float4), dir (float4), wgt (float4), ids (int4), dest (int).
struct DescriptorSet {
  cl::Buffer org, dir, wgt, ids, dest;
  std::size_t capacity = 0;
  static constexpr std::size_t kBytes = 3 * sizeof(cl_float4) + sizeof(cl_int4) + sizeof(cl_int);
  void allocate(ClRuntime& rt, std::size_t n, const char* what);
  int set_args(cl::Kernel& k, int at) const;
  void copy_prefix_to(ClRuntime& rt, DescriptorSet& to, std::size_t count) const;
};

// Enqueues kernels, keeps their events, and turns them into named,
// OpenCL-profiled launch records once the queue has drained.
class Launcher {
 public:
  Launcher(ClRuntime& rt, std::vector<LaunchRecord>& sink) : rt_(rt), sink_(sink) {}
  // Enqueues `k`, after the events in `wait` when given.
  void run(cl::Kernel& k, const char* name, std::size_t global, std::size_t local, int round,
           const std::vector<cl::Event>* wait = nullptr);
  // Call with the result of anything that waited for the launches (a blocking
  // read, clFinish) before trusting what it returned. A kernel can fail on
  // the device after its enqueue succeeded (CL_OUT_OF_RESOURCES, a GPU
  // watchdog reset), and some drivers still answer the read with CL_SUCCESS:
  // throws ClError naming the kernel and round whose command failed, or, when
  // `err` is an error, naming `what` and the last kernel launched.
  void check(cl_int err, const char* what);
  void harvest();  // also checks, as check(CL_SUCCESS, ...)

 private:
  struct Pending {
    const char* name;
    int round;
    cl::Event ev;
  };
  ClRuntime& rt_;
  std::vector<LaunchRecord>& sink_;
  std::vector<Pending> pending_;
  std::size_t checked_ = 0;  // pending_[0, checked_) are known to have completed
};

// The scatter Vd(I'(i)) = Vs(i) over source = [SPMD outputs | queue].
class ScatterPass {
 public:
  static constexpr int kBlock = OPSILA_SCATTER_BLOCK;
  ScatterPass(ClRuntime& rt, int num_pes);
  struct Args {
    int out_len = 0, queue_len = 0, n = 1, spawn_slots = 1;
    const cl::Buffer* processed = nullptr;  // per-PE count of slots used in the output area
    const DescriptorSet* outputs = nullptr;
    const DescriptorSet* queue = nullptr;
    const DescriptorSet* banks = nullptr;
    const DescriptorSet* next_queue = nullptr;  // overflow: entries that found no bank slot
    const cl::Buffer* traffic = nullptr;
    int traffic_levels = 0;
  };
  void enqueue(Launcher& launch, const Args& a, int round);
  cl::Buffer bank_count, pe_total, overflow_base, counts;  // counts = {waiting, placed}

 private:
  ClRuntime& rt_;
  int num_pes_;
  cl::Kernel count_, scan_, plan_, move_;
  cl::Buffer rank_, hist_;
  std::size_t rank_cap_ = 0;
};

inline std::size_t round_up(std::size_t x, std::size_t m) { return (x + m - 1) / m * m; }

}  // namespace opsila
