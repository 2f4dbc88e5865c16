// Everything one `opsila bench` run measured, in one struct: the stages
// (bench/measure.cpp) fill it, analyse() derives the shares, occupancy and
// memory figures, and the writers (report_text.cpp, report_json.cpp,
// report_csv.cpp) only format it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "bench/bench.h"
#include "formats/image/output_files.h"
#include "scene/render_types.h"
#include "frame/stats.h"

namespace opsila {

// A baseline measured `repeats` times (after a warm-up): median seconds, and
// the image and counts of the median run.
struct BaselineRun {
  std::string name, label;
  bool present = false;
  int threads = 0, repeats = 0;
  std::vector<double> seconds_all, kernel_seconds_all;
  BaselineImage median_run;
  double seconds = 0, kernel_seconds = 0;
};

// Image agreement, as the tests measure it (values clamped to [0, 1]).
struct Agreement {
  double psnr = 0, max_abs_diff = 0, identical_pixels = 0;
};
Agreement compare_images(const std::vector<float>& a, const std::vector<float>& b);

// Per level: each PE's descriptors and intersection tests (ray-facet plus
// ray-box tests in the bank BVH) -- the work of that PE in that SPMD phase.
struct LevelWork {
  std::vector<std::uint64_t> descriptors, tests, tri_tests, box_tests, sphere_tests;  // per PE
  std::uint64_t total_descriptors = 0, total_tests = 0, max_descriptors = 0, max_tests = 0;
  std::uint64_t spawned_radiance = 0, spawned_shadow = 0, forwards = 0;  // over PEs
  std::uint64_t triangle_total = 0, box_total = 0, sphere_total = 0;     // over PEs
  std::uint64_t route_total = 0;  // PE-box and routing-node tests (destination choice), over PEs
};

// mean / max over PEs; none when no PE worked.
std::optional<double> occupancy_of(std::uint64_t total, std::uint64_t max, std::size_t pes);

// Where and when the run happened, in the spirit of Google Benchmark's
// context block: whoever reads a saved run knows what it was measured on.
struct BenchContext {
  std::string date;        // ISO 8601, UTC
  std::string host_name;
  int num_cpus = 0;
  double mhz_per_cpu = 0;  // 0 when the host does not say
  std::string cpu_model;
  double load_avg[3] = {-1, -1, -1};  // 1, 5, 15 minutes, at the start
  std::string build_type;             // "release", "debug", ...
};
BenchContext gather_context();

// The device as the report names it.
struct DeviceFacts {
  std::string description, name, platform, vendor, version, driver_version;
  bool is_gpu = false;
  unsigned compute_units = 0;
  std::uint64_t global_mem_bytes = 0, max_alloc_bytes = 0;
};

struct BenchReport {
  // What was asked.
  std::string scene_path;
  bool quick = false;
  int repeats = 0, warmup = 0, host_repeats = 0, host_threads = 0, scatter_max_log2 = 0;
  std::uint64_t host_memory = 0;  // --host-memory (0: not given): the scatter curve stops within it
  // Where and on what.
  DeviceFacts device;
  BenchContext context;
  double load_before = -1, load_after = -1;  // 1-minute load average of the host
  std::size_t triangles = 0, lights = 0;
  int facets = 0, objects = 0, width = 0, height = 0, depth = 0, pes = 0, spp = 1;

  // 1. the OPSILA render.
  double compile_seconds = 0, first_render_seconds = 0;
  std::vector<double> render_times;  // the timed runs
  double render_seconds = 0;         // their median
  RenderResult opsila;               // the median run
  bool deterministic = true;         // every timed run gave the same image

  // MPI ranks of the run (1: one process). With several, the per-rank
  // reports are in stats().ranks and stages 2 and 3 are not run.
  int ranks = 1;
  // Descriptors that crossed from one rank's PEs to another's, per level
  // (from the PE x PE traffic and the PE groups); empty with one rank.
  std::vector<std::uint64_t> cross_rank_by_level;

  // Why stages 2 and 3 were not run (several ranks), or empty.
  std::string single_process_only;
  // 2. baselines on the same rays.
  BaselineRun megakernel, sequential, threads, embree;
  // The megakernel's rays through its BVH with nothing else: what the
  // renders spend per ray beyond it is shading, accumulation and exchange.
  TraversalAlone traversal;
  // Where the SPMD phase's and the megakernel's time goes: cycles per stage
  // (OPSILA_STAGES, kernels/opsila_shared.h), summed over the work-items,
  // then the clock readings that entered each stage (OPSILA_STAGE_COUNTERS),
  // from untimed frames of each built with stage cycles
  // (kernels/lib/stage_cycles.cl), as many as the timed rounds, the one with
  // the median clocked time kept (measure_stage_cycles). Empty, with the reason in
  // stages_skipped, where they cannot run (a device other than an x86 CPU,
  // several ranks).
  std::vector<std::uint64_t> spmd_stage_cycles, megakernel_stage_cycles;
  std::string stages_skipped;
  // The clocked frames' kernel seconds: over the timed ones', what the
  // clocks' readings cost (they inflate the stages that switch most).
  double spmd_clocked_seconds = 0, megakernel_clocked_seconds = 0;

  // 3. the scatter curve, and one length over several PE counts.
  int scatter_pes = 0;
  std::vector<ScatterPoint> curve, by_pes;
  std::string scatter_limit;  // why the curve stopped short of --scatter-max, if it did

  // ---- derived by analyse()
  struct KernelTime {
    int launches = 0;
    double seconds = 0;
  };
  std::map<std::string, KernelTime> by_kernel;
  int launches_per_frame = 0;  // kernel launches of the median frame
  double kernel_seconds = 0, exchange_seconds = 0, overhead_seconds = 0;
  double exchange_share = 0, overhead_share = 0;
  // Of the overhead: the device idle between one kernel's end and the next
  // one's start, and of that the part before the host had enqueued the next
  // (the device waiting on the host); the rest is the driver's, from enqueue
  // to start. From the launches' profiled times (LaunchRecord::queued).
  double idle_seconds = 0, host_late_seconds = 0;
  std::vector<LevelWork> work;
  std::uint64_t all_descriptors = 0, all_triangle_tests = 0, all_box_tests = 0, all_sphere_tests = 0;
  std::uint64_t all_route_tests = 0;  // destination choice: all_sphere_tests + all_route_tests in all
  std::optional<double> occupancy, occupancy_descriptors;
  std::uint64_t bank_max = 0, bank_sum = 0;
  double bank_mean = 0;

  void analyse();
  const RenderStats& stats() const { return opsila.stats; }
  std::uint64_t rays_total() const;
  // The baselines that ran, in report order.
  std::vector<const BaselineRun*> baselines() const;
  bool all_verified() const;  // every scatter point placed like host_scatter
  // Mrays/s of the OPSILA frame or a baseline over Embree's (none without Embree).
  std::optional<double> vs_embree(double mrays_per_s) const;
  // OPSILA's preparation of the scene: reading and parsing through the
  // upload (the pilot frames of --balance measured apart, a choice of
  // balance), to set beside the baselines' builds (build_seconds).
  double prepare_seconds() const;
  double replicated_over_bank_max() const;
  // Seconds per ray of a render over those of the traversal alone (none
  // when it was not measured).
  std::optional<double> over_traversal(double seconds, std::uint64_t rays) const;
};

// Several MPI ranks: what the exchange between them costs, from the
// per-rank reports (each share is the largest over the ranks).
struct RankFigures {
  RankTraffic traffic;
  double frame_seconds = 0;  // the slowest rank's
  double exchange_share = 0, exposed_share = 0, mpi_share = 0;  // of a rank's frame
  double seconds_per_descriptor = 0;  // largest exchange time over the descriptors sent
  double seconds_per_ray = 0;         // largest exchange time over the rays of the frame
  double descriptors_per_ray = 0;     // crossing ranks
};
RankFigures rank_figures(const BenchReport& report);

// One kernel's cycles by stage (BenchReport::spmd_stage_cycles, ...): each
// stage with cycles, its share of their sum, and that share of `seconds`
// (the kernel's time in the median timed frame). The clocked frame took
// `clocked` seconds: the readings' own cost, (1 - seconds / clocked) of
// the cycles, is shared out evenly over the readings and taken from the
// stages they entered (StageTime::share); raw_share keeps the stage's share
// of the cycles as counted. Without the entries (counters of
// OPSILA_STAGE_COUNT only) or a clocked time, share is raw_share.
struct StageTime {
  std::string name;
  std::uint64_t cycles = 0, entries = 0;
  double raw_share = 0, share = 0, seconds = 0;
};
struct StageClockCost {
  double cycles_per_entry = 0;  // what one reading of the clock cost
  double share = 0;             // of the counted cycles
};
std::vector<StageTime> stage_times(const std::vector<std::uint64_t>& counters, double seconds, double clocked = 0,
                                   StageClockCost* cost = nullptr);

// "launch" mode of a kernel in the paper's terms.
const char* launch_mode(const std::string& kernel_name);
double mrays(std::uint64_t rays, double seconds);
// "2^20" for powers of two from 1024, else the number.
std::string length_label(std::size_t n);

// The writers.
std::string bench_text(const BenchReport& report);
nlohmann::json bench_json(const BenchReport& report);  // the --json file (docs/BENCHMARKS.md)
// Into `outputs` (declared folder `dir`), renamed into place with the rest.
void write_bench_csv(const BenchReport& report, const std::string& dir, OutputFiles& outputs);
// The names of the tables it may write, for checking them before the run.
std::vector<std::string> bench_csv_tables(bool quick, int ranks);

}  // namespace opsila
