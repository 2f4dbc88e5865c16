// The launcher: enqueues the frame's kernels with their work-group sizes,
// keeps their events, checks how they ended, and turns them into named,
// OpenCL-profiled launch records (scene/render_types.h). Sparse, it keeps
// events only for the watched launches (a GPU's launch costs about 4 us more
// with one: docs/BENCHMARKS.md, "Levers kept").
#pragma once

#include <cstddef>
#include <vector>

#include "device/cl_runtime.h"

namespace opsila {

struct LaunchRecord;

inline std::size_t round_up(std::size_t x, std::size_t m) { return (x + m - 1) / m * m; }

// Enqueues kernels, keeps their events, and turns them into named,
// OpenCL-profiled launch records once the queue has drained.
class Launcher {
 public:
  // Records kept one per launch in `sink`; past `record_cap` of them, each
  // kernel's later launches are folded into one record
  // (LaunchRecord::kFoldedRound), about 50 bytes a kernel.
  static constexpr std::size_t kRecordCap = std::size_t(1) << 18;
  Launcher(ClRuntime& rt, std::vector<LaunchRecord>& sink, std::size_t record_cap = kRecordCap)
      : rt_(rt), sink_(sink), record_cap_(record_cap) {}
  // Enqueues `k`, after the events in `wait` when given. A watched launch
  // keeps its event even when sparse: the long kernels (the item buffer's,
  // the SPMD phase), where a GPU's watchdog or a lack of resources strikes.
  enum class Watch { when_timed, always };
  void run(cl::Kernel& k, const char* name, std::size_t global, std::size_t local, int round,
           const std::vector<cl::Event>* wait = nullptr, Watch watch = Watch::when_timed);
  // Sparse: the other launches go without an event. Their records count them
  // with no time (seconds 0, queued and started -1), and a failure among them
  // is found by the next read, which names the last kernel launched.
  void set_sparse(bool sparse) { sparse_ = sparse; }
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
  std::size_t record_cap_;
  std::vector<Pending> pending_;
  void record(const char* name, int round, double seconds, double queued, double started);
  cl_ulong base_ns_ = 0;  // CL_PROFILING_COMMAND_QUEUED of the first launch harvested
  bool based_ = false;
  bool sparse_ = false;
  std::size_t checked_ = 0;  // pending_[0, checked_) are known to have completed
};

// The device's waits of more than 5 ms before launches in `launches` (a
// frame's records, in launch order): a launch's start less the later of its
// enqueue and the previous launch's end. A warm launch waits microseconds;
// PoCL compiles a kernel for each work-group size at its first launch, so a
// machine's first frame finds its compile here.
double compile_waits(const std::vector<LaunchRecord>& launches);

}  // namespace opsila
