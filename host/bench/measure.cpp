// The bench's measurement stages. Compilation is never timed: the program is
// built and every kernel has run once (the warm-up) before any measurement
// is kept.
#include "bench/measure.h"

#include <algorithm>
#include <chrono>
#include <cstdarg>
#include <cstdio>
#include <fstream>
#include <thread>

#include "core/progress.h"
#include "core/util.h"
#include "prepare/prepare_banks.h"
#include "frame/renderer.h"
#include "reference/reference.h"

namespace opsila {

namespace {

// The sequential reference (host/reference/reference.h) with its BVH built
// outside the timing, rows split in interleaved bands as render_reference does.
BaselineImage run_reference(const Scene& scene, int threads, Progress& live) {
  BaselineImage out;
  auto tb = std::chrono::steady_clock::now();
  const ReferenceTracer tracer(scene);
  ImageResult image = blank_image(scene.width, scene.height);
  out.build_seconds = seconds_since(tb);
  auto t0 = std::chrono::steady_clock::now();
  tracer.render_image(image, threads, &live);
  out.seconds = seconds_since(t0);
  live.finish();
  static_cast<ImageResult&>(out) = std::move(image);
  return out;
}

// One baseline's timed runs, gathered a run at a time: run() renders one
// frame into `image`, which every run reuses (a megakernel frame then maps
// no fresh pages, as OPSILA's does not), and record() keeps a timed run's
// times. The frames are the same but for their times: finish() keeps the
// last image with the times of the median run.
struct BaselineSeries {
  BaselineRun b;
  BaselineImage image;
  std::vector<double> build_seconds;

  BaselineSeries(const std::string& name, const std::string& label, int threads, int repeats) {
    b.name = name;
    b.label = label;
    b.threads = threads;
    b.repeats = repeats;
    b.present = true;
  }
  void record() {
    b.seconds_all.push_back(image.seconds);
    b.kernel_seconds_all.push_back(image.kernel_seconds);
    build_seconds.push_back(image.build_seconds);
  }
  BaselineRun finish() {
    const std::size_t m = median_index(b.seconds_all);
    b.seconds = median(b.seconds_all);
    b.kernel_seconds = median(b.kernel_seconds_all);
    b.median_run = std::move(image);
    b.median_run.seconds = b.seconds_all[m];
    b.median_run.kernel_seconds = b.kernel_seconds_all[m];
    b.median_run.build_seconds = build_seconds[m];
    return std::move(b);
  }
};

// A baseline's runs one after the other: `warmup` untimed, then `repeats`.
template <typename F>
BaselineRun measure_baseline(const std::string& name, const std::string& label, int threads, int warmup,
                             int repeats, F&& run) {
  BaselineSeries series(name, label, threads, repeats);
  for (int r = 0; r < warmup + repeats; ++r) {
    run(series.image);
    if (r >= warmup) series.record();
  }
  return series.finish();
}

// The scatter curve's vector lengths: powers of two from 16 and the paper's
// longest vector (32767); a handful with --quick.
std::vector<std::size_t> curve_lengths(bool quick, int scatter_max) {
  std::vector<std::size_t> lengths;
  if (quick) {
    for (std::size_t n : {std::size_t(16), std::size_t(256), std::size_t(4096), std::size_t(32767),
                          std::size_t(1) << 16})
      if (n <= (std::size_t(1) << scatter_max)) lengths.push_back(n);
  } else {
    for (int k = 4; k <= scatter_max; ++k) {
      if (k == 15) lengths.push_back(32767);
      lengths.push_back(std::size_t(1) << k);
    }
  }
  return lengths;
}


// A timed frame's statistics with the work counted in another frame of the
// same machine: the same rays, so every count but the work's is the same.
void with_work_counts(RenderStats& timed, const RenderStats& counted) {
  timed.counters = counted.counters;
  timed.traffic = counted.traffic;
  timed.forwards = counted.forwards;
}

}  // namespace

void BenchProgress::operator()(const char* fmt, ...) const {
  if (quiet) return;
  char line[512];
  va_list ap;
  va_start(ap, fmt);
  std::vsnprintf(line, sizeof line, fmt, ap);
  va_end(ap);
  std::fprintf(stderr, "opsila: bench: %s\n", line);
}

double load_average() {
  std::ifstream in("/proc/loadavg");
  double v = -1;
  if (!(in >> v)) return -1;
  return v;
}

void build_program(BenchReport& report, ClRuntime& rt, Balance balance, const BenchProgress& progress) {
  auto tc = std::chrono::steady_clock::now();
  progress("building the OpenCL programs");
  rt.program();
  rt.program(KernelProgram::render_uncounted);  // the timed frames' (rays counted only)
  rt.program(KernelProgram::baselines);
  rt.program(KernelProgram::baselines_uncounted);  // the megakernel's timed frames'
  // The pilots' program is built here too, so that the pilot frames' time
  // is theirs and not the compiler's (a cold compiler cache tripled it);
  // their kernels are compiled for their work-group sizes by a first
  // pilot frame run before the pilots' clock (RenderSettings::pilot_warm_up).
  if (balance == Balance::measured) rt.program(KernelProgram::measure);
  report.stages_skipped = rt.stage_cycles_unavailable();  // builds their programs where they can run
  report.compile_seconds = seconds_since(tc);
}

namespace {

// The baselines a bench round runs beside OPSILA's frame, on the same rays:
// the replicated megakernel, the traversal alone and Embree (each when
// present). Prepared after OPSILA's preparation, whose host peak the
// report gives; every round runs one frame of each, in turn, since the
// machine's speed drifts over seconds and the ratios are what the report
// is for.
struct Baselines {
  std::unique_ptr<Megakernel> mega;
  std::unique_ptr<TraversalBatch> batch;
  std::unique_ptr<BaselineSeries> mega_runs, embree_runs;
  int host_threads = 0;

  Baselines() = default;
  Baselines(BenchReport& report, const Scene& scene, ClRuntime& rt, bool embree, const BenchProgress& progress)
      : host_threads(report.host_threads) {
    mega = std::make_unique<Megakernel>(scene, rt, 1 << 16, false);  // images only, as OPSILA's frames
    mega->count_work(false);  // timed without the test counters, as OPSILA's frames
    mega_runs = std::make_unique<BaselineSeries>("replicated_megakernel", "replicated megakernel (same device)", 0,
                                                 report.repeats);
    batch = std::make_unique<TraversalBatch>(scene, rt, report.traversal);
    if (!report.traversal.present) {
      progress("traversal alone: not measured: %s", report.traversal.skipped.c_str());
      batch.reset();
    }
    if (embree)
      embree_runs = std::make_unique<BaselineSeries>(
          "embree", "Embree " + embree_version() + ", " + std::to_string(host_threads) + " threads", host_threads,
          report.repeats);
  }
  // One frame of each; recorded when the round is timed.
  void round(BenchReport& report, const Scene& scene, bool timed) {
    if (mega) {
      mega->frame(mega_runs->image);
      if (timed) mega_runs->record();
    }
    if (batch) {
      const auto seconds = batch->run();
      if (timed) record_traversal_run(report.traversal, seconds);
    }
    if (embree_runs) {
      embree_runs->image = render_embree(scene, host_threads);
      if (timed) embree_runs->record();
    }
  }
  // The megakernel's tests, from one more frame that counts them (not timed).
  void count_megakernel_work(BenchReport& report) {
    if (!mega) return;
    mega->count_work(true);
    BaselineImage counted;
    mega->frame(counted);
    mega_runs->image.triangle_tests = counted.triangle_tests;
    mega_runs->image.box_tests = counted.box_tests;
    report.deterministic = report.deterministic && counted.rgb == mega_runs->image.rgb &&
                           counted.rays.same_rays(mega_runs->image.rays);
  }
  void finish(BenchReport& report) {
    if (mega_runs) report.megakernel = mega_runs->finish();
    if (batch) finish_traversal(report.traversal);
    if (batch && report.traversal.keep_rays) batch->write_rays_file(report.traversal);
    if (embree_runs) report.embree = embree_runs->finish();
  }
};

// Cycles by stage: as many clocked frames of each as timed rounds, and of
// each the frame whose clocked kernel time is the median (one frame alone
// would carry whatever else the machine did meanwhile into the readings'
// cost, stage_times).
void measure_stage_cycles(BenchReport& report, Renderer& renderer, Megakernel* mega) {
  struct Clocked {
    double seconds = 0;
    std::vector<std::uint64_t> counters;
  };
  auto median_of = [](std::vector<Clocked> runs, double& seconds) {
    std::sort(runs.begin(), runs.end(), [](const Clocked& a, const Clocked& b) { return a.seconds < b.seconds; });
    seconds = runs[runs.size() / 2].seconds;
    return runs[runs.size() / 2].counters;
  };
  const int n = std::max(1, report.repeats);
  std::vector<Clocked> spmd(n), kernel(mega ? n : 0);
  renderer.count_stage_cycles(true);
  for (int i = 0; i < n; ++i) {
    RenderResult clocked;
    renderer.render(clocked);
    report.deterministic = report.deterministic && clocked.rgb == report.opsila.rgb;
    spmd[i].counters = renderer.stage_cycles();
    for (const LaunchRecord& l : clocked.stats.launches)
      if (l.name == "spmd_phase") spmd[i].seconds += l.seconds;
    if (mega) kernel[i].counters = mega->stage_cycles(kernel[i].seconds);
  }
  report.spmd_stage_cycles = median_of(spmd, report.spmd_clocked_seconds);
  if (mega) report.megakernel_stage_cycles = median_of(kernel, report.megakernel_clocked_seconds);
}

}  // namespace

void measure_renders(BenchReport& report, Scene& scene, const RenderSettings& settings, ClRuntime& rt,
                     bool baselines, const BenchProgress& progress) {
  const int warmup = report.warmup, repeats = report.repeats;
  const int host_threads = report.host_threads;
  const bool embree = baselines && embree_available();
  std::string others;
  if (baselines)
    others = embree ? ", the megakernel, the traversal alone and Embree " + embree_version() + " (" +
                          std::to_string(host_threads) + " threads) in turn"
                    : ", the megakernel and the traversal alone in turn";
  progress("OPSILA render %dx%d, depth %d, %d PEs%s: %d warm-up + %d timed rounds", scene.width, scene.height,
           scene.max_depth, settings.num_pes, others.c_str(), warmup, repeats);
  // The machine is prepared once (partition, uploads); every run is one frame.
  // The timed frames run the program a plain render runs, which counts only
  // rays; one more frame, not timed, counts the work (tests, forwards,
  // traffic) that the report gives beside them. Every frame renders into the
  // same result, whose image storage is then reused (Renderer::render); each
  // timed frame's image is compared with the first's, outside the timing.
  Progress live("bench", !progress.quiet);
  RenderSettings with_progress = settings;
  with_progress.progress = &live;
  with_progress.count_work = false;
  with_progress.item_buffer_output = false;  // the image is what the renderers are compared on
  with_progress.switch_counting = true;
  const bool several_ranks = settings.ranks && settings.ranks->size() > 1;
  if (several_ranks && report.stages_skipped.empty()) report.stages_skipped = "several ranks: one process only";
  with_progress.stage_cycles = report.stages_skipped.empty();
  RenderSettings prepare = settings;
  prepare.pilot_warm_up = true;  // as the timed frames follow a warm-up frame
  // The baselines read the scene's facets after the banks are made.
  Renderer renderer(scene, prepare_banks_consuming(scene, prepare, rt, baselines ? Facets::kept : Facets::released),
                    with_progress, rt);
  Baselines base;
  if (baselines) base = Baselines(report, scene, rt, embree, progress);
  RenderResult frame, first;
  std::vector<RenderStats> stats;
  report.deterministic = true;
  for (int r = 0; r < warmup + repeats; ++r) {
    const bool timed = r >= warmup;
    auto t0 = std::chrono::steady_clock::now();
    live.restart("bench: round " + std::to_string(r + 1) + "/" + std::to_string(warmup + repeats) + ", OPSILA");
    renderer.render(frame);
    live.finish();
    if (r == 0) report.first_render_seconds = seconds_since(t0);
    if (timed) {
      report.render_times.push_back(frame.stats.render_seconds);
      stats.push_back(frame.stats);
      if (r == warmup)
        first = frame;
      else
        report.deterministic = report.deterministic && frame.rgb == first.rgb && frame.rays.same_rays(first.rays);
    }
    base.round(report, scene, timed);
  }
  live.restart("bench: OPSILA, the work counted");
  renderer.count_work(true);
  renderer.render(frame);
  live.finish();
  report.deterministic = report.deterministic && frame.rgb == first.rgb && frame.rays.same_rays(first.rays);
  base.count_megakernel_work(report);
  report.opsila = std::move(first);
  report.opsila.stats = stats[median_index(report.render_times)];
  with_work_counts(report.opsila.stats, frame.stats);
  report.render_seconds = median(report.render_times);
  if (report.stages_skipped.empty()) {
    live.restart("bench: OPSILA and the megakernel, cycles by stage");
    measure_stage_cycles(report, renderer, base.mega.get());
    live.finish();
  }
  progress("OPSILA: %.3f s, %.3f Mrays/s", report.render_seconds, mrays(report.rays_total(), report.render_seconds));
  base.finish(report);
}

void measure_host_references(BenchReport& report, const Scene& scene, const BenchProgress& progress) {
  const int host_repeats = report.host_repeats, host_threads = report.host_threads;
  Progress live("bench", !progress.quiet);
  progress("sequential host reference, 1 thread: %d timed runs", host_repeats);
  report.sequential = measure_baseline("sequential_host", "host reference, 1 thread", 1, 0, host_repeats,
                                       [&](BaselineImage& img) {
                                         live.restart("bench: host reference, 1 thread");
                                         img = run_reference(scene, 1, live);
                                       });
  if (host_threads > 1) {
    progress("host reference, %d threads: %d timed runs", host_threads, host_repeats);
    report.threads = measure_baseline("host_threads", "host reference, " + std::to_string(host_threads) + " threads",
                                      host_threads, 0, host_repeats,
                                      [&](BaselineImage& img) {
                                        live.restart("bench: host reference, " + std::to_string(host_threads) +
                                                     " threads");
                                        img = run_reference(scene, host_threads, live);
                                      });
  }
}

void measure_scatter_curve(BenchReport& report, ClRuntime& rt, const BenchProgress& progress) {
  const int warmup = report.warmup, repeats = report.repeats, scatter_max = report.scatter_max_log2;
  const std::vector<std::size_t> lengths = curve_lengths(report.quick, scatter_max);
  report.scatter_pes = std::max(1, report.pes);
  progress("scatter curve: %zu lengths, 16 .. %s, %d PEs", lengths.size(), length_label(lengths.back()).c_str(),
           report.scatter_pes);
  for (std::size_t len : lengths) {
    // The curve stops where the device cannot hold a point (2^24 needs a
    // 2.2 GB buffer, more than PoCL allows on a 24 GB machine).
    // Nor past --host-memory: 2^23 took 5.6 GB of a CPU device's host memory.
    const ScatterFootprint need = scatter_footprint(len, report.scatter_pes);
    const bool host = report.host_memory && need.total > report.host_memory;
    if (need.largest > rt.max_alloc() || need.total > rt.global_mem() || host) {
      report.scatter_limit = "the curve stops at " + length_label(report.curve.empty() ? 0 : report.curve.back().length) +
                             ": " + length_label(len) + " needs a buffer of " + format_size(need.largest) + " and " +
                             format_size(need.total) + " in all, " +
                             (host ? "--host-memory allows " + format_size(report.host_memory)
                                   : "the device allows " + format_size(rt.max_alloc()) + " and " +
                                         format_size(rt.global_mem()));
      progress("scatter: %s", report.scatter_limit.c_str());
      break;
    }
    // Short vectors are cheap and noisy: more repeats there; the longest
    // take seconds each: fewer.
    const int reps = len >= (std::size_t(1) << 22) ? std::min(repeats, 3)
                     : len <= (std::size_t(1) << 16) ? 4 * repeats
                                                      : repeats;
    if (len >= (std::size_t(1) << 20)) progress("scatter %s", length_label(len).c_str());
    report.curve.push_back(measure_scatter(rt, len, report.scatter_pes, std::max(warmup, 1), reps));
  }

  // The same scatter at one length over several PE counts: how the number
  // of destination streams (PEs x 5 descriptor fields) costs bandwidth.
  if (!report.quick) {
    const std::size_t longest = report.curve.empty() ? 16 : report.curve.back().length;
    const std::size_t len = std::min<std::size_t>({std::size_t(1) << 20, std::size_t(1) << scatter_max, longest});
    progress("scatter %s over 1 .. 256 PEs", length_label(len).c_str());
    for (int pes : {1, 4, 16, 64, 256})
      report.by_pes.push_back(measure_scatter(rt, len, pes, std::max(warmup, 1), std::min(repeats, 3)));
  }
}

}  // namespace opsila
