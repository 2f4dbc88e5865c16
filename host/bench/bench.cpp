// `opsila bench SCENE [view flags] [--json FILE] [--csv DIR] [--quick] ...`
//
// Stages (each with a progress line on stderr):
//   1. the OPSILA render: warm-up, then the median of repeated runs; phases,
//      exchange share, launch overhead, PE occupancy, traffic, memory;
//   2. baselines on the same rays: the replicated-scene megakernel on the same
//      device, the sequential host reference (1 thread and all threads), and
//      Embree when built in;
//   3. the scatter curve (the paper's figure 6) with the copy ceiling.
// Compilation is never timed: the program is built and every kernel has run
// once (the warm-up) before any measurement is kept.
#include "bench/bench.h"

#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "cli/cli.h"
#include "core/image_io.h"
#include "opsila_shared.h"
#include "machine/partition.h"
#include "reference/reference.h"
#include "machine/renderer.h"
#include "input/scene_file.h"

namespace opsila {

namespace {

using nlohmann::json;

// ---------------------------------------------------------------- options

struct BenchOptions {
  std::string scene_path;
  std::vector<std::string> view_args;  // forwarded to the render-flag parser
  std::string json_path, csv_dir;
  bool quick = false, quiet = false, help = false;
  std::optional<int> repeats, warmup, threads, scatter_max_log2;
};

// View flags shared with `opsila render` (all take a value).
const char* const kViewFlags[] = {"--size",       "--eye",   "--look-at", "--up",     "--fov",
                                  "--light",      "--ambient", "--background", "--depth", "--pes",
                                  "--device",     "--bank-capacity"};
// Render flags that make no sense for a benchmark.
const char* const kRenderOnlyFlags[] = {"-o", "--output", "--item-buffer", "--stats", "--reference"};

bool in_list(const std::string& name, const char* const* begin, const char* const* end) {
  return std::any_of(begin, end, [&](const char* f) { return name == f; });
}

[[noreturn]] void bad_value(const std::string& flag, const std::string& value, const std::string& problem) {
  throw InputError(flag + " " + (value.empty() ? "''" : value) + ": " + problem);
}

int int_value(const std::string& flag, const std::string& text, long long lo, long long hi) {
  bool ok = !text.empty() && text.size() <= 12;
  for (std::size_t i = 0; ok && i < text.size(); ++i)
    ok = std::isdigit(static_cast<unsigned char>(text[i])) || (i == 0 && (text[0] == '-' || text[0] == '+'));
  if (!ok || text == "-" || text == "+") bad_value(flag, text, "not an integer");
  const long long v = std::stoll(text);
  if (v < lo || v > hi) bad_value(flag, text, "must be in " + std::to_string(lo) + ".." + std::to_string(hi));
  return static_cast<int>(v);
}

std::string lower_ext(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  const std::size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string e = path.substr(dot);
  for (char& c : e) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return e;
}

BenchOptions parse_bench_options(const std::vector<std::string>& args) {
  BenchOptions o;
  std::set<std::string> seen;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const ArgWord word = split_arg(args[i]);
    if (word.positional) {
      if (!o.scene_path.empty())
        throw InputError("unexpected argument '" + word.value + "' (one SCENE only; see 'opsila bench --help')");
      o.scene_path = word.value;
      continue;
    }
    const std::string& name = word.name;
    const bool view = in_list(name, std::begin(kViewFlags), std::end(kViewFlags));
    const bool no_value = name == "--quick" || name == "-q" || name == "--quiet" || name == "-h" || name == "--help";
    const bool bench_value = name == "--json" || name == "--csv" || name == "--repeats" || name == "--warmup" ||
                             name == "--threads" || name == "--scatter-max";
    if (!view && !no_value && !bench_value) {
      if (in_list(name, std::begin(kRenderOnlyFlags), std::end(kRenderOnlyFlags)))
        throw InputError(name + ": a render flag, not a bench flag (see 'opsila bench --help')");
      throw InputError("unknown flag '" + name + "' (see 'opsila bench --help')");
    }
    if (no_value && word.inline_value) throw InputError(name + ": takes no value");
    const std::string value = no_value ? std::string() : flag_value(args, i, word);
    if (view) {  // checked by the render parser, which also refuses repeats
      o.view_args.push_back(name);
      o.view_args.push_back(value);
      continue;
    }
    const std::string canonical = name == "--quiet" ? "-q" : name == "-h" ? "--help" : name;
    if (bench_value && !seen.insert(canonical).second) throw InputError(name + ": given more than once");
    if (canonical == "--help") {
      o.help = true;
    } else if (canonical == "-q") {
      o.quiet = true;
    } else if (canonical == "--quick") {
      o.quick = true;
    } else if (canonical == "--json") {
      if (lower_ext(value) != ".json") bad_value(name, value, "must end in .json");
      o.json_path = value;
    } else if (canonical == "--csv") {
      if (value.empty()) bad_value(name, value, "empty folder name");
      o.csv_dir = value;
    } else if (canonical == "--repeats") {
      o.repeats = int_value(name, value, 1, 1000);
    } else if (canonical == "--warmup") {
      o.warmup = int_value(name, value, 0, 100);
    } else if (canonical == "--threads") {
      o.threads = int_value(name, value, 1, 1024);
    } else if (canonical == "--scatter-max") {
      o.scatter_max_log2 = int_value(name, value, 4, 24);
    }
  }
  if (o.help) return o;
  if (o.scene_path.empty()) throw InputError("missing SCENE (see 'opsila bench --help')");
  return o;
}

// A folder for --csv: made if missing (one level), refused if not a folder.
void prepare_csv_dir(const std::string& dir) {
  struct stat st;
  if (::stat(dir.c_str(), &st) == 0) {
    if (!S_ISDIR(st.st_mode)) throw InputError("--csv " + dir + ": exists and is not a folder");
  } else if (::mkdir(dir.c_str(), 0777) != 0) {
    throw InputError("--csv " + dir + ": cannot create folder (" + std::strerror(errno) + ")");
  }
  check_output_path(dir + "/scatter.csv");
}

// ------------------------------------------------------------- utilities

bool g_quiet = false;

void progress(const char* fmt, ...) {
  if (g_quiet) return;
  char line[512];
  va_list ap;
  va_start(ap, fmt);
  std::vsnprintf(line, sizeof line, fmt, ap);
  va_end(ap);
  std::fprintf(stderr, "opsila: bench: %s\n", line);
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[(v.size() - 1) / 2];  // the lower median: always one of the runs
}

// Index of the value closest to the median (the run whose details we keep).
std::size_t median_index(const std::vector<double>& v) {
  const double m = median(v);
  std::size_t best = 0;
  for (std::size_t i = 1; i < v.size(); ++i)
    if (std::abs(v[i] - m) < std::abs(v[best] - m)) best = i;
  return best;
}

// The 1-minute load average of the host (other work skews timings).
double load_average() {
  std::ifstream in("/proc/loadavg");
  double v = -1;
  if (!(in >> v)) return -1;
  return v;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

double mrays(std::uint64_t rays, double seconds) { return seconds > 0 ? double(rays) / seconds / 1e6 : 0.0; }

// Image agreement, as the tests measure it (values clamped to [0, 1]).
struct Agreement {
  double psnr = 0, max_abs_diff = 0, identical_pixels = 0;
};

Agreement compare_images(const std::vector<float>& a, const std::vector<float>& b) {
  Agreement g;
  if (a.size() != b.size() || a.empty()) return g;
  std::vector<float> ca(a), cb(b);
  for (auto* v : {&ca, &cb})
    for (float& x : *v) x = std::isnan(x) ? 0.0f : std::min(1.0f, std::max(0.0f, x));
  g.psnr = psnr(ca, cb, 1.0);
  std::size_t same = 0;
  for (std::size_t p = 0; p + 2 < a.size(); p += 3) {
    bool eq = true;
    for (int c = 0; c < 3; ++c) {
      g.max_abs_diff = std::max(g.max_abs_diff, double(std::fabs(a[p + c] - b[p + c])));
      eq = eq && a[p + c] == b[p + c];
    }
    same += eq;
  }
  g.identical_pixels = double(same) / double(a.size() / 3);
  return g;
}

json psnr_value(double p) { return std::isfinite(p) ? json(p) : json("inf"); }

std::string human_bytes(double bytes) {
  char s[64];
  if (bytes >= 1024.0 * 1024 * 1024)
    std::snprintf(s, sizeof s, "%.2f GiB", bytes / (1024.0 * 1024 * 1024));
  else if (bytes >= 1024.0 * 1024)
    std::snprintf(s, sizeof s, "%.2f MiB", bytes / (1024.0 * 1024));
  else
    std::snprintf(s, sizeof s, "%.1f KiB", bytes / 1024.0);
  return s;
}

std::string length_label(std::size_t n) {
  if (n >= 1024 && (n & (n - 1)) == 0) {
    int k = 0;
    while ((std::size_t(1) << k) < n) ++k;
    return "2^" + std::to_string(k);
  }
  return std::to_string(n);
}

// ------------------------------------------------------ host reference run

// The sequential reference (host/reference/reference.h) with its BVH built outside the
// timing, rows split in interleaved bands as render_reference does.
BaselineImage run_reference(const Scene& scene, int threads) {
  BaselineImage out;
  auto tb = std::chrono::steady_clock::now();
  const ReferenceTracer tracer(scene);
  ReferenceImage image = make_reference_image(scene);
  out.build_seconds = seconds_since(tb);
  threads = std::max(1, std::min(threads, scene.height));
  std::vector<ReferenceCounts> counts(threads);
  constexpr int kBand = 4;
  auto t0 = std::chrono::steady_clock::now();
  auto work = [&](int w) {
    for (int y = w * kBand; y < scene.height; y += threads * kBand) tracer.render_rows(y, y + kBand, image, counts[w]);
  };
  std::vector<std::thread> pool;
  for (int w = 1; w < threads; ++w) pool.emplace_back(work, w);
  work(0);
  for (std::thread& t : pool) t.join();
  out.seconds = seconds_since(t0);
  ReferenceCounts total;
  for (const ReferenceCounts& c : counts) total += c;
  out.width = image.width;
  out.height = image.height;
  out.rgb = std::move(image.rgb);
  out.item_buffer = std::move(image.item_buffer);
  out.rays.primary = total.primary;
  out.rays.secondary = total.secondary;
  out.rays.shadow = total.shadow;
  return out;
}

// A baseline measured `repeats` times (after `warmup` runs): median seconds,
// and the image and counts of the median run.
struct BaselineRun {
  std::string name, label;
  bool present = false;
  int threads = 0, repeats = 0;
  std::vector<double> seconds_all;
  BaselineImage median_run;
  double seconds = 0, kernel_seconds = 0;
};

template <typename F>
BaselineRun measure_baseline(const std::string& name, const std::string& label, int threads, int warmup,
                             int repeats, F&& run) {
  BaselineRun b;
  b.name = name;
  b.label = label;
  b.threads = threads;
  b.repeats = repeats;
  b.present = true;
  std::vector<BaselineImage> runs;
  std::vector<double> kernel;
  for (int r = 0; r < warmup + repeats; ++r) {
    BaselineImage img = run();
    if (r < warmup) continue;
    b.seconds_all.push_back(img.seconds);
    kernel.push_back(img.kernel_seconds);
    runs.push_back(std::move(img));
  }
  const std::size_t m = median_index(b.seconds_all);
  b.seconds = median(b.seconds_all);
  b.kernel_seconds = median(kernel);
  b.median_run = std::move(runs[m]);
  return b;
}

// ------------------------------------------------------ render statistics

bool is_scatter(const std::string& name) { return name.compare(0, 8, "scatter_") == 0; }

const char* launch_mode(const std::string& name) { return name == "spmd_phase" ? "SPMD" : "SIMD"; }

struct LevelWork {
  std::vector<std::uint64_t> descriptors, tests, tri_tests, box_tests, sphere_tests;  // per PE
  std::uint64_t total_descriptors = 0, total_tests = 0, max_descriptors = 0, max_tests = 0;
};

// Per level and PE: descriptors processed and intersection tests (ray-facet
// plus ray-box tests in the bank BVH) -- the work of that PE in that SPMD phase.
std::vector<LevelWork> level_work(const RenderStats& st) {
  std::vector<LevelWork> out;
  for (const auto& level : st.counters) {
    LevelWork w;
    for (const auto& c : level) {
      const std::uint64_t tests = c[OPSILA_STAT_TRI_TESTS] + c[OPSILA_STAT_BOX_TESTS];
      w.descriptors.push_back(c[OPSILA_STAT_TRACED]);
      w.tests.push_back(tests);
      w.tri_tests.push_back(c[OPSILA_STAT_TRI_TESTS]);
      w.box_tests.push_back(c[OPSILA_STAT_BOX_TESTS]);
      w.sphere_tests.push_back(c[OPSILA_STAT_SPHERE_TESTS]);
      w.total_descriptors += c[OPSILA_STAT_TRACED];
      w.total_tests += tests;
      w.max_descriptors = std::max<std::uint64_t>(w.max_descriptors, c[OPSILA_STAT_TRACED]);
      w.max_tests = std::max(w.max_tests, tests);
    }
    out.push_back(std::move(w));
  }
  return out;
}

// mean / max over PEs; null when no PE worked.
json occupancy_of(std::uint64_t total, std::uint64_t max, std::size_t pes) {
  if (max == 0 || pes == 0) return nullptr;
  return double(total) / (double(pes) * double(max));
}

// ------------------------------------------------------------------- CSV

void write_csv(const std::string& dir, const std::string& name, const std::string& text) {
  write_text_file(dir + "/" + name, text);
}

std::string num(double v) {
  char s[64];
  std::snprintf(s, sizeof s, "%.9g", v);
  return s;
}

}  // namespace

// ------------------------------------------------------------------ usage

std::string bench_usage() {
  return "usage: opsila bench SCENE [view flags] [--json FILE] [--csv DIR] [--quick] [options]\n"
         "\n"
         "Measures, on one OpenCL device: the OPSILA render (phases, exchange share,\n"
         "launch overhead, PE occupancy, traffic, memory per bank), baselines on the\n"
         "same rays (replicated-scene megakernel on the same device, the sequential host\n"
         "reference on 1 and all threads, Embree when built in), and the scatter curve\n"
         "(speed-up and bandwidth against vector length, beside the copy bandwidth).\n"
         "Every figure is the median of repeated runs after a warm-up; compilation is\n"
         "never timed.\n"
         "\n"
         "  --json FILE        write every result as JSON (see docs/BENCHMARKS.md)\n"
         "  --csv DIR          write CSV tables: scatter, phases, levels, occupancy, traffic, baselines\n"
         "  --quick            fewer repeats and shorter scatter vectors (CI)\n"
         "  --repeats N        timed runs per measurement (default 5, --quick 2)\n"
         "  --warmup N         untimed runs before them (default 1)\n"
         "  --threads N        host threads for the host baselines (default: all)\n"
         "  --scatter-max K    longest scatter vector 2^K, 4..24 (default 24, --quick 16)\n"
         "  -q, --quiet        no progress lines\n"
         "  -h, --help         this text\n"
         "\n"
         "View flags, as for 'opsila render': --size WxH, --eye, --look-at, --up, --fov,\n"
         "--light, --ambient, --background, --depth, --pes, --device, --bank-capacity.\n";
}

// ------------------------------------------------------------------- main

int run_bench(const std::vector<std::string>& args) {
  const BenchOptions o = parse_bench_options(args);
  if (o.help) {
    std::fputs(bench_usage().c_str(), stdout);
    return kExitOk;
  }
  g_quiet = o.quiet;
  std::vector<std::string> render_args = o.view_args;
  render_args.push_back(o.scene_path);
  render_args.push_back("-o");
  render_args.push_back("bench.png");  // never written: the render parser wants an output
  const RenderOptions ro = parse_render_options(render_args);
  if (!o.json_path.empty()) check_output_path(o.json_path);
  if (!o.csv_dir.empty()) prepare_csv_dir(o.csv_dir);

  const int repeats = o.repeats.value_or(o.quick ? 2 : 5);
  const int warmup = o.warmup.value_or(1);
  const int host_threads =
      o.threads.value_or(static_cast<int>(std::max(1u, std::thread::hardware_concurrency())));
  const int host_repeats = std::min(repeats, 3);
  const int scatter_max = o.scatter_max_log2.value_or(o.quick ? 16 : 24);

  DeviceEntry chosen;
  try {
    chosen = choose_device(ro.device_spec);
  } catch (const InputError& e) {
    const std::string message = e.what();
    if (ro.device_spec.empty() || message.rfind("--device", 0) == 0) throw;
    throw InputError("--device " + ro.device_spec + ": " + message);
  }
  ClRuntime rt(chosen);
  progress("device: %s", rt.description().c_str());

  Scene scene = load_scene(o.scene_path);
  if (!o.quiet) {
    std::set<std::string> said;
    for (const std::string& w : scene.warnings)
      if (said.insert(w).second) std::fprintf(stderr, "opsila: warning: %s\n", w.c_str());
  }
  apply_render_options(scene, ro);
  RenderSettings settings;
  settings.num_pes = ro.pes.value_or(settings.num_pes);
  settings.bank_capacity = ro.bank_capacity;
  const int P = settings.num_pes;
  const std::size_t npix = std::size_t(scene.width) * scene.height;

  const double load_before = load_average();
  // Compilation, never timed.
  auto tc = std::chrono::steady_clock::now();
  progress("building the OpenCL program");
  rt.program();
  const double compile_seconds = seconds_since(tc);

  // ---------------------------------------------------------- 1. OPSILA
  progress("OPSILA render %dx%d, depth %d, %d PEs: %d warm-up + %d timed runs", scene.width, scene.height,
           scene.max_depth, P, warmup, repeats);
  std::vector<RenderResult> renders;
  std::vector<double> render_times;
  double first_render_seconds = 0;
  // The machine is prepared once (partition, uploads); every run is one frame.
  Renderer renderer(scene, settings, rt);
  for (int r = 0; r < warmup + repeats; ++r) {
    auto t0 = std::chrono::steady_clock::now();
    RenderResult res = renderer.render();
    if (r == 0) first_render_seconds = seconds_since(t0);
    if (r < warmup) continue;
    render_times.push_back(res.stats.render_seconds);
    renders.push_back(std::move(res));
  }
  bool deterministic = true;
  for (const RenderResult& r : renders) deterministic = deterministic && r.rgb == renders.front().rgb;
  const std::size_t mi = median_index(render_times);
  const RenderResult& opsila = renders[mi];
  const RenderStats& st = opsila.stats;
  const double render_seconds = median(render_times);
  const std::uint64_t rays_total = st.primary_rays + st.secondary_rays + st.shadow_rays;
  progress("OPSILA: %.3f s, %.3f Mrays/s", render_seconds, mrays(rays_total, render_seconds));

  // ------------------------------------------------------- 2. baselines
  progress("replicated megakernel: %d warm-up + %d timed runs", warmup, repeats);
  BaselineRun mega = measure_baseline("replicated_megakernel", "replicated megakernel (same device)", 0, warmup,
                                      repeats, [&] { return render_megakernel(scene, rt); });
  progress("sequential host reference, 1 thread: %d timed runs", host_repeats);
  BaselineRun seq = measure_baseline("sequential_host", "host reference, 1 thread", 1, 0, host_repeats,
                                     [&] { return run_reference(scene, 1); });
  BaselineRun par;
  if (host_threads > 1) {
    progress("host reference, %d threads: %d timed runs", host_threads, host_repeats);
    par = measure_baseline("host_threads", "host reference, " + std::to_string(host_threads) + " threads",
                           host_threads, 0, host_repeats, [&] { return run_reference(scene, host_threads); });
  }
  BaselineRun embree;
  if (embree_available()) {
    progress("Embree %s, %d threads: %d warm-up + %d timed runs", embree_version().c_str(), host_threads, warmup,
             host_repeats);
    embree = measure_baseline("embree", "Embree " + embree_version() + ", " + std::to_string(host_threads) +
                                            " threads",
                              host_threads, std::min(warmup, 1), host_repeats,
                              [&] { return render_embree(scene, host_threads); });
  }

  // ------------------------------------------------------ 3. scatter curve
  std::vector<std::size_t> lengths;
  if (o.quick) {
    for (std::size_t n : {std::size_t(16), std::size_t(256), std::size_t(4096), std::size_t(32767),
                          std::size_t(1) << 16})
      if (n <= (std::size_t(1) << scatter_max)) lengths.push_back(n);
  } else {
    for (int k = 4; k <= scatter_max; ++k) {
      if (k == 15) lengths.push_back(32767);  // the paper's longest vector
      lengths.push_back(std::size_t(1) << k);
    }
  }
  const int scatter_pes = std::max(1, P);
  std::vector<ScatterPoint> curve;
  progress("scatter curve: %zu lengths, 16 .. %s, %d PEs", lengths.size(), length_label(lengths.back()).c_str(),
           scatter_pes);
  for (std::size_t len : lengths) {
    // The longest vectors take seconds each: fewer repeats there.
    // Short vectors are cheap and noisy: more repeats there; the longest
    // take seconds each: fewer.
    const int reps = len >= (std::size_t(1) << 22) ? std::min(repeats, 3)
                     : len <= (std::size_t(1) << 16) ? 4 * repeats
                                                      : repeats;
    if (len >= (std::size_t(1) << 20)) progress("scatter %s", length_label(len).c_str());
    curve.push_back(measure_scatter(rt, len, scatter_pes, std::max(warmup, 1), reps));
  }

  // The same scatter at one length over several PE counts: how the number
  // of destination streams (PEs x 5 descriptor fields) costs bandwidth.
  std::vector<ScatterPoint> by_pes;
  if (!o.quick) {
    const std::size_t len = std::min<std::size_t>(std::size_t(1) << 20, std::size_t(1) << scatter_max);
    progress("scatter %s over 1 .. 256 PEs", length_label(len).c_str());
    for (int pes : {1, 4, 16, 64, 256})
      by_pes.push_back(measure_scatter(rt, len, pes, std::max(warmup, 1), std::min(repeats, 3)));
  }

  // ------------------------------------------------------------ analysis
  std::map<std::string, std::pair<int, double>> by_kernel;
  double kernel_seconds = 0, exchange_seconds = 0;
  for (const LaunchRecord& l : st.launches) {
    auto& e = by_kernel[l.name];
    e.first += 1;
    e.second += l.seconds;
    kernel_seconds += l.seconds;
    if (is_scatter(l.name)) exchange_seconds += l.seconds;
  }
  const double rs = st.render_seconds;
  const double overhead_seconds = std::max(0.0, rs - kernel_seconds);
  const double exchange_share = rs > 0 ? exchange_seconds / rs : 0;
  const double overhead_share = rs > 0 ? overhead_seconds / rs : 0;

  const std::vector<LevelWork> work = level_work(st);
  std::uint64_t all_tests = 0, all_max_tests = 0, all_desc = 0, all_max_desc = 0;
  for (const LevelWork& w : work) {
    all_tests += w.total_tests;
    all_max_tests += w.max_tests;
    all_desc += w.total_descriptors;
    all_max_desc += w.max_descriptors;
  }
  // The render's occupancy: work done over the work the phases would have
  // allowed if every PE had been as busy as the busiest one, level by level.
  const json occupancy = occupancy_of(all_tests, all_max_tests, std::size_t(P));
  const json occupancy_desc = occupancy_of(all_desc, all_max_desc, std::size_t(P));

  std::uint64_t bank_max = 0, bank_sum = 0;
  for (std::uint64_t b : st.bank_bytes) bank_max = std::max(bank_max, b), bank_sum += b;
  const double bank_mean = st.bank_bytes.empty() ? 0.0 : double(bank_sum) / double(st.bank_bytes.size());

  // -------------------------------------------------------------- JSON
  json j;
  j["version"] = OPSILA_VERSION;
  j["device"] = rt.description();
  j["device_info"] = {{"name", rt.device().device_name},
                      {"platform", rt.device().platform_name},
                      {"vendor", rt.device().vendor},
                      {"version", rt.device().version},
                      {"driver_version", rt.device().driver_version},
                      {"is_gpu", rt.device().is_gpu},
                      {"compute_units", rt.device().device.getInfo<CL_DEVICE_MAX_COMPUTE_UNITS>()},
                      {"global_mem_bytes", rt.global_mem()},
                      {"max_alloc_bytes", rt.max_alloc()}};
  j["host_threads"] = host_threads;
  j["host_load_average"] = {{"before", load_before}, {"after", load_average()}};
  j["scene"] = {{"path", o.scene_path},
                {"triangles", scene.triangles.size()},
                {"facets", scene.num_facets},
                {"objects", scene.num_objects},
                {"clusters", st.num_clusters},
                {"lights", scene.lights.size()}};
  j["image"] = {{"width", scene.width}, {"height", scene.height}, {"pixels", npix}};
  j["depth"] = scene.max_depth;
  j["pes"] = P;
  j["bank_capacity"] = st.bank_capacity;
  j["work_group_size"] = st.work_group_size;
  j["settings"] = {{"repeats", repeats},       {"warmup", warmup},   {"host_repeats", host_repeats},
                   {"quick", o.quick},         {"scatter_max_log2", scatter_max}};
  j["compile_seconds"] = compile_seconds;
  j["first_render_seconds"] = first_render_seconds;

  json render_j;
  render_j["rays"] = rays_total;
  render_j["rays_by_kind"] = {
      {"primary", st.primary_rays}, {"secondary", st.secondary_rays}, {"shadow", st.shadow_rays}};
  render_j["seconds"] = render_seconds;
  render_j["seconds_all"] = render_times;
  render_j["mrays_per_s"] = mrays(rays_total, render_seconds);
  render_j["mrays_per_s_by_kind"] = {{"primary", mrays(st.primary_rays, render_seconds)},
                                     {"secondary", mrays(st.secondary_rays, render_seconds)},
                                     {"shadow", mrays(st.shadow_rays, render_seconds)}};
  render_j["deterministic"] = deterministic;
  render_j["rounds"] = st.rounds;
  render_j["phase_switches"] = 2 * st.rounds;
  render_j["kernel_seconds"] = kernel_seconds;
  render_j["exchange_seconds"] = exchange_seconds;
  render_j["exchange_share"] = exchange_share;
  render_j["overhead_seconds"] = overhead_seconds;
  render_j["overhead_share"] = overhead_share;
  render_j["exchange_plus_overhead_share"] = exchange_share + overhead_share;
  render_j["descriptors"] = {{"spawned", st.descriptors_spawned},
                             {"finished", st.descriptors_finished},
                             {"forwards", st.forwards},
                             {"overflow_deferrals", st.overflow_deferrals}};
  json tk = json::object();
  for (const auto& [name, e] : by_kernel)
    tk[name] = {{"launches", e.first}, {"seconds", e.second}, {"mode", launch_mode(name)},
                {"share", rs > 0 ? e.second / rs : 0.0}};
  render_j["time_by_kernel"] = tk;
  json phases = json::array();
  for (const LaunchRecord& l : st.launches)
    phases.push_back({{"name", l.name}, {"mode", launch_mode(l.name)}, {"round", l.round}, {"seconds", l.seconds}});
  render_j["phases"] = std::move(phases);

  json levels = json::array();
  for (std::size_t l = 0; l < work.size(); ++l) {
    const LevelWork& w = work[l];
    std::uint64_t spawned_r = 0, spawned_s = 0, forwards = 0, sphere = 0, tri = 0, box = 0;
    for (const auto& c : st.counters[l]) {
      spawned_r += c[OPSILA_STAT_SPAWN_RADIANCE];
      spawned_s += c[OPSILA_STAT_SPAWN_SHADOW];
      forwards += c[OPSILA_STAT_FORWARD];
      sphere += c[OPSILA_STAT_SPHERE_TESTS];
      tri += c[OPSILA_STAT_TRI_TESTS];
      box += c[OPSILA_STAT_BOX_TESTS];
    }
    levels.push_back({{"level", l},
                      {"descriptors", w.total_descriptors},
                      {"tests", w.total_tests},
                      {"triangle_tests", tri},
                      {"box_tests", box},
                      {"sphere_tests", sphere},
                      {"spawned_radiance", spawned_r},
                      {"spawned_shadow", spawned_s},
                      {"forwards", forwards},
                      {"max_pe_descriptors", w.max_descriptors},
                      {"max_pe_tests", w.max_tests},
                      {"occupancy_descriptors", occupancy_of(w.total_descriptors, w.max_descriptors, P)},
                      {"occupancy", occupancy_of(w.total_tests, w.max_tests, P)}});
  }
  render_j["levels"] = std::move(levels);

  json pe_list = json::array();
  for (int p = 0; p < P; ++p) {
    std::uint64_t d = 0, t = 0, tri = 0, box = 0, sph = 0;
    std::vector<std::uint64_t> d_by, t_by;
    for (const LevelWork& w : work) {
      d += w.descriptors[p];
      t += w.tests[p];
      tri += w.tri_tests[p];
      box += w.box_tests[p];
      sph += w.sphere_tests[p];
      d_by.push_back(w.descriptors[p]);
      t_by.push_back(w.tests[p]);
    }
    pe_list.push_back({{"pe", p},
                       {"descriptors", d},
                       {"tests", t},
                       {"triangle_tests", tri},
                       {"box_tests", box},
                       {"sphere_tests", sph},
                       {"descriptors_by_level", d_by},
                       {"tests_by_level", t_by},
                       {"bank_bytes", p < static_cast<int>(st.bank_bytes.size()) ? st.bank_bytes[p] : 0}});
  }
  render_j["pe"] = std::move(pe_list);
  {
    std::uint64_t tri = 0, box = 0, sph = 0;
    for (const LevelWork& w : work)
      for (int p = 0; p < P; ++p) tri += w.tri_tests[p], box += w.box_tests[p], sph += w.sphere_tests[p];
    render_j["work"] = {{"descriptors", all_desc}, {"triangle_tests", tri}, {"box_tests", box}, {"sphere_tests", sph},
                        {"tests", tri + box}};
  }
  render_j["occupancy"] = occupancy;
  render_j["occupancy_descriptors"] = occupancy_desc;
  json traffic = json::array();
  for (const auto& flat : st.traffic) {
    json m = json::array();
    for (int s = 0; s < P; ++s)
      m.push_back(std::vector<std::uint64_t>(flat.begin() + std::size_t(s) * P, flat.begin() + std::size_t(s + 1) * P));
    traffic.push_back(std::move(m));
  }
  render_j["traffic"] = std::move(traffic);
  j["render"] = std::move(render_j);

  json scatter = json::array();
  for (const ScatterPoint& p : curve)
    scatter.push_back({{"length", p.length},
                       {"moved", p.moved},
                       {"waiting", p.waiting},
                       {"pes", p.pes},
                       {"bank_capacity", p.n},
                       {"repeats", p.repeats},
                       {"bytes", p.bytes()},
                       {"host_seconds", p.host_seconds},
                       {"kernel_seconds", p.kernel_seconds},
                       {"kernels", {{"scatter_count", p.count_seconds},
                                    {"scatter_scan", p.scan_seconds},
                                    {"scatter_plan", p.plan_seconds},
                                    {"scatter_move", p.move_seconds}}},
                       {"speedup", p.speedup()},
                       {"gbytes_per_s", p.gbytes_per_s()},
                       {"host_gbytes_per_s", p.host_gbytes_per_s()},
                       {"copy_kernel_seconds", p.copy_kernel_seconds},
                       {"copy_kernel_gbytes_per_s", p.copy_kernel_gbytes_per_s()},
                       {"copy_buffer_seconds", p.copy_buffer_seconds},
                       {"copy_buffer_gbytes_per_s", p.copy_buffer_gbytes_per_s()},
                       {"fraction_of_copy", p.copy_kernel_gbytes_per_s() > 0
                                                ? p.gbytes_per_s() / p.copy_kernel_gbytes_per_s()
                                                : 0.0},
                       {"verified", p.verified}});
  j["scatter"] = std::move(scatter);
  json sp = json::array();
  for (const ScatterPoint& p : by_pes)
    sp.push_back({{"pes", p.pes},
                  {"length", p.length},
                  {"kernel_seconds", p.kernel_seconds},
                  {"host_seconds", p.host_seconds},
                  {"speedup", p.speedup()},
                  {"gbytes_per_s", p.gbytes_per_s()},
                  {"host_gbytes_per_s", p.host_gbytes_per_s()},
                  {"copy_kernel_gbytes_per_s", p.copy_kernel_gbytes_per_s()},
                  {"fraction_of_copy", p.copy_kernel_gbytes_per_s() > 0
                                           ? p.gbytes_per_s() / p.copy_kernel_gbytes_per_s()
                                           : 0.0},
                  {"verified", p.verified}});
  j["scatter_by_pes"] = std::move(sp);
  // The copy ceiling: the longest vector's copy bandwidth (the asymptote).
  j["copy_gbytes_per_s"] = curve.back().copy_kernel_gbytes_per_s();
  j["copy_buffer_gbytes_per_s"] = curve.back().copy_buffer_gbytes_per_s();
  j["bytes_per_descriptor"] = DescriptorSet::kBytes;

  j["memory"] = {{"bank_bytes", st.bank_bytes},
                 {"bank_bytes_max", bank_max},
                 {"bank_bytes_mean", bank_mean},
                 {"global_bytes", st.global_bytes},
                 {"replicated_bytes", st.replicated_bytes},
                 {"per_pe_bytes_max", bank_max + st.global_bytes},
                 {"replicated_over_bank_max",
                  bank_max + st.global_bytes > 0 ? double(st.replicated_bytes) / double(bank_max + st.global_bytes)
                                                 : 0.0},
                 {"all_pes_distributed_bytes", bank_sum + std::uint64_t(P) * st.global_bytes},
                 {"all_pes_replicated_bytes", std::uint64_t(P) * st.replicated_bytes}};

  json baselines = json::object();
  std::vector<const BaselineRun*> runs_list = {&mega, &seq, &par, &embree};
  for (const BaselineRun* b : runs_list) {
    if (!b->present) continue;
    const BaselineImage& img = b->median_run;
    const Agreement g = compare_images(img.rgb, opsila.rgb);
    const bool same_rays = img.rays.primary == st.primary_rays && img.rays.secondary == st.secondary_rays &&
                           img.rays.shadow == st.shadow_rays;
    json e = {{"label", b->label},
              {"seconds", b->seconds},
              {"seconds_all", b->seconds_all},
              {"build_seconds", img.build_seconds},
              {"rays", img.rays.total()},
              {"rays_by_kind", {{"primary", img.rays.primary}, {"secondary", img.rays.secondary},
                                {"shadow", img.rays.shadow}}},
              {"mrays_per_s", mrays(img.rays.total(), b->seconds)},
              {"rays_match_opsila", same_rays},
              {"psnr_vs_opsila", psnr_value(g.psnr)},
              {"max_abs_diff_vs_opsila", g.max_abs_diff},
              {"identical_pixels_vs_opsila", g.identical_pixels}};
    if (b->threads > 0) e["threads"] = b->threads;
    if (b->name == "replicated_megakernel") {
      e["kernel_seconds"] = b->kernel_seconds;
      e["device"] = rt.description();
      e["scene_bytes_per_work_item"] = st.replicated_bytes;
      e["triangle_tests"] = img.triangle_tests;
      e["box_tests"] = img.box_tests;
      e["tests"] = img.triangle_tests + img.box_tests;
    }
    if (b->name == "embree") e["version"] = embree_version();
    baselines[b->name] = std::move(e);
  }
  j["baselines"] = std::move(baselines);

  // Targets (benchmarks, reported, never enforced).
  json targets = json::object();
  {
    const ScatterPoint* p20 = nullptr;
    for (const ScatterPoint& p : curve)
      if (p.length == (std::size_t(1) << 20)) p20 = &p;
    if (p20)
      targets["scatter_2p20_vs_copy"] = {
          {"gbytes_per_s", p20->gbytes_per_s()},
          {"copy_gbytes_per_s", p20->copy_kernel_gbytes_per_s()},
          {"fraction", p20->gbytes_per_s() / std::max(1e-30, p20->copy_kernel_gbytes_per_s())},
          {"goal", 0.6},
          {"met", p20->gbytes_per_s() >= 0.6 * p20->copy_kernel_gbytes_per_s()}};
    else
      targets["scatter_2p20_vs_copy"] = nullptr;
    targets["exchange_plus_overhead"] = {{"share", exchange_share + overhead_share},
                                         {"goal", 0.10},
                                         {"met", exchange_share + overhead_share < 0.10}};
    if (embree.present) {
      const double e = mrays(embree.median_run.rays.total(), embree.seconds);
      const double mine = mrays(rays_total, render_seconds);
      targets["opsila_vs_embree"] = {{"opsila_mrays_per_s", mine},
                                     {"embree_mrays_per_s", e},
                                     {"ratio", e > 0 ? mine / e : 0.0},
                                     {"goal", 0.5},
                                     {"met", e > 0 && mine >= 0.5 * e}};
    } else {
      targets["opsila_vs_embree"] = nullptr;
    }
  }
  j["targets"] = std::move(targets);

  if (!o.json_path.empty()) write_text_file(o.json_path, j.dump(1) + "\n");

  // --------------------------------------------------------------- CSV
  if (!o.csv_dir.empty()) {
    std::ostringstream c;
    c << "length,moved,bytes,host_seconds,kernel_seconds,speedup,gbytes_per_s,copy_kernel_gbytes_per_s,"
         "copy_buffer_gbytes_per_s,fraction_of_copy,count_seconds,scan_seconds,plan_seconds,move_seconds\n";
    for (const ScatterPoint& p : curve)
      c << p.length << ',' << p.moved << ',' << num(p.bytes()) << ',' << num(p.host_seconds) << ','
        << num(p.kernel_seconds) << ',' << num(p.speedup()) << ',' << num(p.gbytes_per_s()) << ','
        << num(p.copy_kernel_gbytes_per_s()) << ',' << num(p.copy_buffer_gbytes_per_s()) << ','
        << num(p.copy_kernel_gbytes_per_s() > 0 ? p.gbytes_per_s() / p.copy_kernel_gbytes_per_s() : 0) << ','
        << num(p.count_seconds) << ',' << num(p.scan_seconds) << ',' << num(p.plan_seconds) << ','
        << num(p.move_seconds) << '\n';
    write_csv(o.csv_dir, "scatter.csv", c.str());
    if (!by_pes.empty()) {
      std::ostringstream cp;
      cp << "pes,length,kernel_seconds,host_seconds,speedup,gbytes_per_s,copy_kernel_gbytes_per_s,fraction_of_copy\n";
      for (const ScatterPoint& p : by_pes)
        cp << p.pes << ',' << p.length << ',' << num(p.kernel_seconds) << ',' << num(p.host_seconds) << ','
           << num(p.speedup()) << ',' << num(p.gbytes_per_s()) << ',' << num(p.copy_kernel_gbytes_per_s()) << ','
           << num(p.copy_kernel_gbytes_per_s() > 0 ? p.gbytes_per_s() / p.copy_kernel_gbytes_per_s() : 0) << '\n';
      write_csv(o.csv_dir, "scatter_pes.csv", cp.str());
    }

    std::ostringstream ph;
    ph << "index,name,mode,round,seconds\n";
    for (std::size_t i = 0; i < st.launches.size(); ++i)
      ph << i << ',' << st.launches[i].name << ',' << launch_mode(st.launches[i].name) << ','
         << st.launches[i].round << ',' << num(st.launches[i].seconds) << '\n';
    write_csv(o.csv_dir, "phases.csv", ph.str());

    std::ostringstream lv;
    lv << "level,descriptors,tests,max_pe_descriptors,max_pe_tests,occupancy_descriptors,occupancy\n";
    for (std::size_t l = 0; l < work.size(); ++l) {
      const LevelWork& w = work[l];
      const json od = occupancy_of(w.total_descriptors, w.max_descriptors, P);
      const json ot = occupancy_of(w.total_tests, w.max_tests, P);
      lv << l << ',' << w.total_descriptors << ',' << w.total_tests << ',' << w.max_descriptors << ','
         << w.max_tests << ',' << (od.is_null() ? "" : num(od.get<double>())) << ','
         << (ot.is_null() ? "" : num(ot.get<double>())) << '\n';
    }
    write_csv(o.csv_dir, "levels.csv", lv.str());

    std::ostringstream oc;
    oc << "level,pe,descriptors,triangle_tests,box_tests,sphere_tests,tests\n";
    for (std::size_t l = 0; l < work.size(); ++l)
      for (int p = 0; p < P; ++p)
        oc << l << ',' << p << ',' << work[l].descriptors[p] << ',' << work[l].tri_tests[p] << ','
           << work[l].box_tests[p] << ',' << work[l].sphere_tests[p] << ',' << work[l].tests[p] << '\n';
    write_csv(o.csv_dir, "occupancy.csv", oc.str());

    std::ostringstream tr;
    tr << "level,src,dst,descriptors\n";
    for (std::size_t l = 0; l < st.traffic.size(); ++l)
      for (int s = 0; s < P; ++s)
        for (int d = 0; d < P; ++d) {
          const std::uint64_t v = st.traffic[l][std::size_t(s) * P + d];
          if (v) tr << l << ',' << s << ',' << d << ',' << v << '\n';
        }
    write_csv(o.csv_dir, "traffic.csv", tr.str());

    std::ostringstream bl;
    bl << "name,seconds,rays,mrays_per_s\n";
    bl << "opsila," << num(render_seconds) << ',' << rays_total << ',' << num(mrays(rays_total, render_seconds))
       << '\n';
    for (const BaselineRun* b : runs_list)
      if (b->present)
        bl << b->name << ',' << num(b->seconds) << ',' << b->median_run.rays.total() << ','
           << num(mrays(b->median_run.rays.total(), b->seconds)) << '\n';
    write_csv(o.csv_dir, "baselines.csv", bl.str());
  }

  // ----------------------------------------------------------- summary
  std::printf("opsila bench: %s, %dx%d, depth %d, %d PEs (bank capacity %d, work-group %zu)\n",
              o.scene_path.c_str(), scene.width, scene.height, scene.max_depth, P, st.bank_capacity,
              st.work_group_size);
  std::printf("device: %s\n", rt.description().c_str());
  std::printf("scene: %zu triangles, %d facets, %d objects, %d clusters, %zu lights\n", scene.triangles.size(),
              scene.num_facets, scene.num_objects, st.num_clusters, scene.lights.size());
  std::printf(
      "timing: median of %d runs after %d warm-up (host baselines: median of %d); compile %.2f s, not timed\n\n",
      repeats, warmup, host_repeats, compile_seconds);

  std::printf("%-40s %10s %10s %12s %10s\n", "render (same rays)", "seconds", "Mrays/s", "rays", "PSNR dB");
  std::printf("%-40s %10.4f %10.3f %12llu %10s\n", ("OPSILA, " + std::to_string(P) + " PEs").c_str(), render_seconds,
              mrays(rays_total, render_seconds), static_cast<unsigned long long>(rays_total), "-");
  for (const BaselineRun* b : runs_list) {
    if (!b->present) continue;
    const Agreement g = compare_images(b->median_run.rgb, opsila.rgb);
    char ps[32];
    if (std::isfinite(g.psnr))
      std::snprintf(ps, sizeof ps, "%.1f", g.psnr);
    else
      std::snprintf(ps, sizeof ps, "inf");
    std::printf("%-40s %10.4f %10.3f %12llu %10s\n", b->label.c_str(), b->seconds,
                mrays(b->median_run.rays.total(), b->seconds),
                static_cast<unsigned long long>(b->median_run.rays.total()), ps);
  }
  {
    std::uint64_t tri = 0, box = 0, sph = 0;
    for (const LevelWork& w : work)
      for (int p = 0; p < P; ++p) tri += w.tri_tests[p], box += w.box_tests[p], sph += w.sphere_tests[p];
    std::printf("work: OPSILA %llu descriptors, %llu ray-facet + %llu ray-box tests, %llu sphere tests;\n"
                "      megakernel %llu ray-facet + %llu ray-box tests\n",
                static_cast<unsigned long long>(all_desc), static_cast<unsigned long long>(tri),
                static_cast<unsigned long long>(box), static_cast<unsigned long long>(sph),
                static_cast<unsigned long long>(mega.median_run.triangle_tests),
                static_cast<unsigned long long>(mega.median_run.box_tests));
  }
  std::printf("rays: %llu primary, %llu secondary, %llu shadow\n\n", static_cast<unsigned long long>(st.primary_rays),
              static_cast<unsigned long long>(st.secondary_rays), static_cast<unsigned long long>(st.shadow_rays));

  std::printf("phases: %d rounds (%d phase switches), render %.4f s\n", st.rounds, 2 * st.rounds, rs);
  std::printf("  %-18s %5s %9s %10s %7s\n", "kernel", "mode", "launches", "seconds", "share");
  for (const auto& [name, e] : by_kernel)
    std::printf("  %-18s %5s %9d %10.4f %6.1f%%\n", name.c_str(), launch_mode(name), e.first, e.second,
                rs > 0 ? 100.0 * e.second / rs : 0.0);
  std::printf("  %-18s %5s %9s %10.4f %6.1f%%\n", "launch overhead", "", "", overhead_seconds, 100.0 * overhead_share);
  std::printf("  exchange (scatter) %.1f%% + launch overhead %.1f%% = %.1f%% of the frame\n\n", 100.0 * exchange_share,
              100.0 * overhead_share, 100.0 * (exchange_share + overhead_share));

  std::printf("occupancy (mean/max per PE; work = ray-facet + ray-box tests):\n");
  std::printf("  %5s %12s %14s %12s %12s\n", "level", "descriptors", "tests", "occ(desc)", "occ(tests)");
  for (std::size_t l = 0; l < work.size(); ++l) {
    const LevelWork& w = work[l];
    if (w.total_descriptors == 0) continue;
    const json od = occupancy_of(w.total_descriptors, w.max_descriptors, P);
    const json ot = occupancy_of(w.total_tests, w.max_tests, P);
    std::printf("  %5zu %12llu %14llu %12.3f %12.3f\n", l, static_cast<unsigned long long>(w.total_descriptors),
                static_cast<unsigned long long>(w.total_tests), od.is_null() ? 0.0 : od.get<double>(),
                ot.is_null() ? 0.0 : ot.get<double>());
  }
  std::printf("  overall: %.3f (tests), %.3f (descriptors)\n\n", occupancy.is_null() ? 0.0 : occupancy.get<double>(),
              occupancy_desc.is_null() ? 0.0 : occupancy_desc.get<double>());

  std::printf("memory: bank max %s, mean %s, + %s known to every PE; a replicated scene costs %s per PE (%.1fx)\n\n",
              human_bytes(double(bank_max)).c_str(), human_bytes(bank_mean).c_str(),
              human_bytes(double(st.global_bytes)).c_str(), human_bytes(double(st.replicated_bytes)).c_str(),
              bank_max + st.global_bytes > 0 ? double(st.replicated_bytes) / double(bank_max + st.global_bytes) : 0.0);

  std::printf("scatter (%d PEs, %zu bytes per descriptor, read + written):\n", scatter_pes, DescriptorSet::kBytes);
  std::printf("  %8s %11s %11s %8s %9s %9s %9s %7s\n", "length", "host ms", "kernel ms", "speedup", "GB/s",
              "copy GB/s", "cpbuf GB/s", "%copy");
  for (const ScatterPoint& p : curve)
    std::printf("  %8s %11.4f %11.4f %8.2f %9.2f %9.2f %9.2f %6.0f%%\n", length_label(p.length).c_str(),
                1e3 * p.host_seconds, 1e3 * p.kernel_seconds, p.speedup(), p.gbytes_per_s(),
                p.copy_kernel_gbytes_per_s(), p.copy_buffer_gbytes_per_s(),
                p.copy_kernel_gbytes_per_s() > 0 ? 100.0 * p.gbytes_per_s() / p.copy_kernel_gbytes_per_s() : 0.0);
  if (!by_pes.empty()) {
    std::printf("  %s descriptors over PE counts (destination streams = PEs x 5 fields):\n",
                length_label(by_pes.front().length).c_str());
    std::printf("  %8s %11s %8s %9s %9s %7s\n", "PEs", "kernel ms", "speedup", "GB/s", "copy GB/s", "%copy");
    for (const ScatterPoint& p : by_pes)
      std::printf("  %8d %11.4f %8.2f %9.2f %9.2f %6.0f%%\n", p.pes, 1e3 * p.kernel_seconds, p.speedup(),
                  p.gbytes_per_s(), p.copy_kernel_gbytes_per_s(),
                  p.copy_kernel_gbytes_per_s() > 0 ? 100.0 * p.gbytes_per_s() / p.copy_kernel_gbytes_per_s() : 0.0);
  }
  bool all_verified = true;
  for (const ScatterPoint& p : curve) all_verified = all_verified && p.verified;
  for (const ScatterPoint& p : by_pes) all_verified = all_verified && p.verified;
  std::printf("  placement %s host_scatter at every length\n", all_verified ? "matches" : "DIFFERS from");
  if (!o.json_path.empty()) progress("wrote %s", o.json_path.c_str());
  if (!o.csv_dir.empty()) progress("wrote CSV tables in %s", o.csv_dir.c_str());
  return kExitOk;
}

}  // namespace opsila
