// The bench's measurement stages, in the order run_bench calls them. Each
// fills its part of the BenchReport and says what it does on stderr.
#pragma once

#include "bench/report.h"
#include "core/scene.h"
#include "machine/cl_runtime.h"
#include "machine/render_types.h"

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
// 1. The OPSILA render: warm-up, then the median of the timed runs. A
//    scene read in shares gives up its facets to the partition.
void measure_opsila(BenchReport& report, Scene& scene, const RenderSettings& settings, ClRuntime& runtime,
                    const BenchProgress& progress);
// 2. Baselines on the same rays: megakernel, host reference on 1 and all
//    threads, Embree when built in.
void measure_baselines(BenchReport& report, const Scene& scene, ClRuntime& runtime, const BenchProgress& progress);
// 3. The scatter curve (the paper's figure 6), and one length over PE counts.
void measure_scatter_curve(BenchReport& report, ClRuntime& runtime, const BenchProgress& progress);

}  // namespace opsila
