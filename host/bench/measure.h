// The bench's measurement stages, in the order run_bench calls them. Each
// fills its part of the BenchReport and says what it does on stderr.
#pragma once

#include "bench/report.h"
#include "scene/scene.h"
#include "device/cl_runtime.h"
#include "scene/render_types.h"

namespace opsila {

// Progress lines on stderr ("opsila: bench: ..."), unless quiet.
struct BenchProgress {
  bool quiet = false;
  void operator()(const char* fmt, ...) const __attribute__((format(printf, 2, 3)));
};

// The 1-minute load average of the host (other work skews timings); -1 when unknown.
double load_average();

// 0. Compiles the programs (never timed: the renderer's, the timed frames',
//    the baselines' and, for --balance measured, the pilots') and records
//    the compile time.
void build_program(BenchReport& report, ClRuntime& runtime, Balance balance, const BenchProgress& progress);
// 1. The renders on the same rays, in rounds: each round runs one frame of
//    OPSILA, then (`baselines`: one process) of the replicated megakernel,
//    the traversal alone and Embree when built in, so that the machine's
//    drift over the run weighs on all of them alike. Warm-up rounds, then
//    the median of the timed rounds, each renderer's own. A scene read in
//    shares gives up its facets to the partition.
void measure_renders(BenchReport& report, Scene& scene, const RenderSettings& settings, ClRuntime& runtime,
                     bool baselines, const BenchProgress& progress);
// 2. The host reference on 1 and all threads (one process), after the renders.
void measure_host_references(BenchReport& report, const Scene& scene, const BenchProgress& progress);
// 3. The scatter curve (the paper's figure 6), and one length over PE counts.
void measure_scatter_curve(BenchReport& report, ClRuntime& runtime, const BenchProgress& progress);

}  // namespace opsila
