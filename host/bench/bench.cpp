// `opsila bench SCENE [view flags] [--json FILE] [--csv DIR] [--quick] ...`
//
// Stages (each with a progress line on stderr, see bench/measure.h):
//   1. the OPSILA render: warm-up, then the median of repeated runs; phases,
//      exchange share, launch overhead, PE occupancy, traffic, memory;
//   2. baselines on the same rays: the replicated-scene megakernel on the same
//      device, the sequential host reference (1 thread and all threads), and
//      Embree when built in;
//   3. the scatter curve (the paper's figure 6) with the copy ceiling.
// One BenchReport holds the results; the writers format it as text, JSON, CSV.
#include "bench/bench.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <string>

#include "bench/compare.h"
#include "bench/measure.h"
#include "bench/options.h"
#include "bench/report.h"
#include "prepare/prepare.h"
#include "prepare/scene_limits.h"
#include "core/env_hooks.h"
#include "core/progress.h"
#include "core/stage_clock.h"
#include "formats/image/image_io.h"
#include "formats/image/output_files.h"
#include "formats/json/scene_file.h"
#include "partition/pe_group.h"
#include "mpi/ranks.h"

namespace opsila {

namespace {

DeviceFacts device_facts(ClRuntime& rt) {
  DeviceFacts d;
  d.description = rt.description();
  d.name = rt.device().device_name;
  d.platform = rt.device().platform_name;
  d.vendor = rt.device().vendor;
  d.version = rt.device().version;
  d.driver_version = rt.device().driver_version;
  d.is_gpu = rt.device().is_gpu;
  cl_int err = CL_SUCCESS;
  d.compute_units = rt.device().device.getInfo<CL_DEVICE_MAX_COMPUTE_UNITS>(&err);
  cl_check(err, "clGetDeviceInfo(CL_DEVICE_MAX_COMPUTE_UNITS)");
  d.global_mem_bytes = rt.global_mem();
  d.max_alloc_bytes = rt.max_alloc();
  return d;
}

// What was asked and what the scene is, before anything is measured.
// Why a run under mpirun leaves out stages 2 and 3 (said in every report).
constexpr const char* kSingleProcessOnly =
    "the baselines (megakernel, host reference, Embree) trace the whole scene in one process, and under mpirun "
    "a rank reads only its share of it; the scatter curve measures one "
    "device alone: run `opsila bench` without mpirun for them";

BenchReport start_report(const BenchOptions& o, const Scene& scene, int pes) {
  BenchReport r;
  r.scene_path = o.scene_path;
  r.quick = o.quick;
  r.repeats = o.timed_repeats();
  r.warmup = o.warmup_runs();
  r.host_repeats = o.host_repeats();
  r.host_threads = o.host_threads();
  r.scatter_max_log2 = o.scatter_max();
  r.host_memory = o.host_memory;
  r.triangles = scene.total_triangles();  // every rank's, for a share
  r.lights = scene.lights.size();
  r.facets = scene.num_facets;
  r.objects = scene.num_objects;
  r.width = scene.width;
  r.height = scene.height;
  r.depth = scene.max_depth;
  r.spp = scene.spp;
  r.pes = pes;
  return r;
}

// What the bench asks the preparation for: the view group, balanced by
// measured work unless told otherwise.
PrepareRequest bench_request(const BenchOptions& o, bool silent, Ranks& ranks, OutputFiles& outputs,
                             const BenchProgress& progress) {
  PrepareRequest request;
  request.view = static_cast<const ViewOptions&>(o);
  request.balance = kBenchBalance;
  request.quiet = o.quiet || silent;
  request.ranks = &ranks;
  request.outputs = &outputs;
  request.note = [progress](const std::string& text) { progress("note: %s", text.c_str()); };
  return request;
}

// Stages 1-3: OPSILA's frames, and where one process renders a scene of
// its own facets, the baselines on the same rays and the scatter curve.
void measure_all(BenchReport& report, Scene& scene, const RenderSettings& settings, ClRuntime& rt, Ranks& ranks,
                 const BenchProgress& progress) {
  const bool baselines = ranks.size() == 1;
  measure_renders(report, scene, settings, rt, baselines, progress);
  report.ranks = ranks.size();
  if (baselines) {
    measure_host_references(report, scene, progress);
    measure_scatter_curve(report, rt, progress);
  } else {
    report.single_process_only = kSingleProcessOnly;
    progress("%d MPI ranks: %s", ranks.size(), kSingleProcessOnly);
  }
}

// Checked, not created: the CSV folder, its tables, the JSON file and the
// rays file appear together at the end, or not at all. Rank 0 writes; the
// rays file needs the traversal alone, which one process measures.
void declare_outputs(const BenchOptions& o, bool writer, Ranks& ranks, OutputFiles& outputs) {
  if (writer && !o.json_path.empty()) outputs.declare("--json", o.json_path);
  if (writer && !o.csv_dir.empty())
    outputs.declare_folder("--csv", o.csv_dir, bench_csv_tables(o.quick, ranks.size()));
  if (!o.rays_path.empty()) {
    if (ranks.size() > 1)
      bad_flag("--rays-out", o.rays_path, "the traversal alone runs in one process, not under several ranks");
    outputs.declare("--rays-out", o.rays_path);
  }
  outputs.refuse_inputs({o.scene_path});
  outputs.refuse_inputs(env_hook_inputs());
}

void write_outputs(const BenchOptions& o, const BenchReport& report, const nlohmann::json& results,
                   OutputFiles& outputs) {
  if (!o.json_path.empty()) outputs.write(o.json_path, results.dump(1) + "\n");
  if (!o.csv_dir.empty()) write_bench_csv(report, o.csv_dir, outputs);
  if (!o.rays_path.empty()) {
    if (report.traversal.rays_file.empty())
      bad_flag("--rays-out", o.rays_path, "the traversal alone was not measured: " + report.traversal.skipped);
    outputs.write(o.rays_path, report.traversal.rays_file);
  }
  outputs.commit();
}

// The report goes out before the files: one that cannot be written (a full
// disk, a closed pipe) fails the run with nothing written. Written whole
// (fwrite, not fputs): a saved run's strings may hold a NUL.
void print_report(const std::string& text) {
  errno = 0;
  if (std::fwrite(text.data(), 1, text.size(), stdout) == text.size() && std::fflush(stdout) == 0) return;
  throw InputError(std::string("standard output: write failed (") + (errno ? std::strerror(errno) : "stream error") +
                   "); nothing written");
}

}  // namespace

int run_bench(const std::vector<std::string>& args, Ranks& ranks) {
  const BenchOptions o = parse_bench_options(args);
  if (answered_help(o, bench_usage())) return kExitOk;
  // Under mpirun every rank drives its device and its group of PEs through
  // the OPSILA render; rank 0 alone reports and writes. The baselines and the
  // scatter curve need one process: with several ranks they are left out
  // (kSingleProcessOnly says why in the report).
  if (launched_by_mpi()) ranks.start();
  const bool writer = ranks.rank() == 0;
  install_interrupt_cleanup();
  OutputFiles outputs;
  declare_outputs(o, writer, ranks, outputs);
  nlohmann::json saved;  // read first, so a bad file fails before any work
  if (!o.compare_path.empty()) {
    outputs.refuse_inputs({o.compare_path});
    saved = read_saved_bench(o.compare_path);
  }
  // As render does: each rank's own checks, then one agreement, then the
  // first collective.
  ranks.checkpoint();
  check_started_alike(ranks, args, o.scene_path);
  const BenchProgress progress{o.quiet || !writer};

  ClRuntime rt(choose_device_flag(o.device_spec, ranks));
  // The bench measures the scheme with its PEs balanced by measured work
  // unless told otherwise, on one process or on ranks that each read only
  // their share of the scene (docs/DISTRIBUTED.md).
  PrepareRequest request = bench_request(o, !writer, ranks, outputs, progress);
  // The bench prepares the banks of each measured renderer itself (measure.cpp).
  Scene scene = std::move(prepare_scene(request, nullptr).scene);
  // Every rank names its device (as render does), each on its own line,
  // once the scene is read: bad input gets its error line alone.
  const std::string device = device_text(ranks, o.pes.value_or(RenderSettings().num_pes), rt.description());
  if (ranks.size() > 1) {
    if (!o.quiet) std::fprintf(stderr, "opsila: bench: device: %s\n", device.c_str());
  } else {
    progress("device: %s", device.c_str());
  }
  for (const std::string& w : unknown_env_hooks()) progress("warning: %s", w.c_str());
  // Pilot frames measure the scene's own facets only: an instanced scene's
  // banks are balanced by the frame's sampled rays unless --balance says.
  if (!scene.instances.empty() && !o.balance) request.balance = Balance::work;
  const RenderSettings settings = prepared_settings(request);
  check_device_room(scene, o.scene_path, ranks, rt);
  if (!o.rays_path.empty() && !scene.instances.empty())
    bad_flag("--rays-out", o.rays_path, "the scene places instances; the file holds plain triangles only");
  if (settings.balance == Balance::work) progress("sampling the frame's rays for --balance work");
  if (settings.balance == Balance::measured) progress("pilot frames for --balance measured");

  BenchReport report = start_report(o, scene, settings.num_pes);
  report.traversal.keep_rays = !o.rays_path.empty();
  report.device = device_facts(rt);
  report.context = gather_context();
  report.load_before = load_average();
  rt.walk_instances(!scene.instances.empty());  // the programs the renderer will run
  build_program(report, rt, settings.balance, progress);
  measure_all(report, scene, settings, rt, ranks, progress);
  report.load_after = load_average();
  if (!writer) {
    ranks.checkpoint();  // rank 0 reports; a failure there ends every rank alike
    return kExitOk;
  }
  report.analyse();

  const nlohmann::json results = bench_json(report);
  // Everything that reads the saved run is done before anything is written.
  const std::string compared = o.compare_path.empty() ? "" : compare_text(results, saved, o.compare_path);
  print_report(bench_text(report) + compared);
  write_outputs(o, report, results, outputs);
  if (!o.json_path.empty()) progress("wrote %s", o.json_path.c_str());
  if (!o.csv_dir.empty()) progress("wrote CSV tables in %s", o.csv_dir.c_str());
  if (!o.rays_path.empty()) progress("wrote %s", o.rays_path.c_str());
  ranks.checkpoint();
  return kExitOk;
}

}  // namespace opsila
