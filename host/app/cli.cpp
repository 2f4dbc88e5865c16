#include "app/cli.h"
#include "prepare/prepare_banks.h"
#include "prepare/prepare.h"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <new>
#include <set>
#include <sstream>
#include <system_error>
#include <thread>

#include "device/cl_runtime.h"
#include "formats/image/image_io.h"
#include "core/env_hooks.h"
#include "core/host_memory.h"
#include "core/driver_limits.h"
#include "core/progress.h"
#include "core/stage_clock.h"
#include "formats/image/output_files.h"
#include "core/util.h"
#include "opsila_shared.h"
#include "reference/reference.h"
#include "partition/pe_group.h"
#include "mpi/ranks.h"
#include "frame/renderer.h"
#include "formats/json/scene_file.h"
#include "frame/stats.h"

namespace opsila {

namespace {

void print_line(const std::string& kind, const std::string& text) {
  std::fprintf(stderr, "opsila: %s: %s\n", kind.c_str(), shown_text(text).c_str());
}

// Same path written twice would lose one of the outputs.
void check_distinct_outputs(const RenderOptions& o) {
  const std::pair<const char*, const std::string*> outputs[] = {
      {"-o", &o.output_path}, {"--item-buffer", &o.item_buffer_path}, {"--stats", &o.stats_path}};
  for (std::size_t i = 0; i < 3; ++i)
    for (std::size_t j = i + 1; j < 3; ++j)
      if (!outputs[i].second->empty() && *outputs[i].second == *outputs[j].second)
        throw InputError(std::string(outputs[j].first) + " " + *outputs[j].second + ": same file as " +
                         outputs[i].first);
}

// The -o file's bytes, in the format its extension names.
std::string encode_output(const RenderOptions& o, const ImageResult& r) {
  const std::string ext = extension_of(o.output_path);
  if (ext == ".png") return encode_png(r.width, r.height, r.rgb);
  if (ext == ".exr") return encode_exr(r.width, r.height, r.rgb, o.exr_half);
  return encode_pfm(r.width, r.height, r.rgb);
}

}  // namespace

// ------------------------------------------------------------------- usage

std::string main_usage() {
  return "opsila " OPSILA_VERSION
         " - a ray tracer that splits the scene into banks over OpenCL processing elements\n"
         "\n"
         "usage:\n"
         "  opsila render SCENE -o OUT.(png|pfm|exr) [options]   render an image\n"
         "  opsila devices                                      list OpenCL platforms and devices\n"
         "  opsila bench SCENE [options]                        run the benchmarks\n"
         "  opsila --help | --version\n"
         "\n"
         "Run 'opsila render --help' for the render options.\n"
         "Exit codes: 0 success, 1 unexpected failure, 2 bad input or flag, 3 OpenCL device or driver error,\n"
         "128 + N ended by signal N: 130 SIGINT, 143 SIGTERM, 129 SIGHUP (nothing written).\n";
}

std::string render_usage() {
  return "usage: opsila render SCENE -o OUT.(png|pfm|exr) [options]\n"
         "\n"
         "SCENE is a scene file, a bare .obj (its .mtl found as OBJ says), or a model\n"
         "in another format the Open Asset Import Library reads (.ply, .stl, .gltf, .glb,\n"
         ".fbx, .dae, .3ds, ...).\n"
         "Flags override the scene file; both '--flag value' and '--flag=value' work.\n"
         "\n"
         "  -o, --output OUT       output image: .png (sRGB, 8 bits), .pfm (linear float) or .exr\n"
         "                         (OpenEXR, linear RGB, 32-bit float)\n"
         "  --exr-half             .exr output in 16-bit half floats\n"
         "  --size WxH             image size (each side <= 16384, at most 2^26 pixels)\n"
         "  --eye X,Y,Z            camera position\n"
         "  --look-at X,Y,Z        point the camera looks at\n"
         "  --up X,Y,Z             camera up vector (not parallel to the view direction)\n"
         "  --fov DEG              vertical field of view, 0 < DEG < 180\n"
         "  --light X,Y,Z[,R,G,B]  point light (repeatable; replaces the scene's lights)\n"
         "  --ambient R,G,B        ambient intensity\n"
         "  --background R,G,B     colour of rays that hit nothing\n"
         "  --depth N              ray tree levels, 1..31 (1 = local shading only)\n"
         "  --spp N                samples per pixel on a k x k grid: 1, 4, 9, 16, ..., 1024\n"
         "  --smooth               smooth shading: interpolate the model's vertex normals\n"
         "  --pes N                processing elements (OpenCL work-groups), 1..1024\n"
         "  --bank-capacity N      descriptor slots per bank on average: P*N in flight, shared by demand\n"
         "                         (0 = from the device)\n"
         "  --work-groups-per-pe K at most K work-groups serve one PE's bank per round (0 = as many\n"
         "                         as its descriptors need; 1 = the paper's one processor per PE)\n"
         "  --routing MODE         destination choice: boxes (cluster boxes under a BVH, default)\n"
         "                         or spheres (the paper's bounding spheres); same image\n"
         "  --balance MODE         how the scene is split over the PEs: facets (equal banks, default),\n"
         "                         work (by the frame's rays, sampled on the host first: busy\n"
         "                         regions get more PEs, banks differ in size) or measured (by\n"
         "                         the work five small pilot frames measure per cluster on the\n"
         "                         device, level by level); same image\n"
         "  --device SPEC          device index, platform:device, or name substring (see 'opsila devices')\n"
         "  --host-memory SIZE     host memory this process may use while preparing the scene (8G, 512M,\n"
         "                         bytes; default: what the host has available, shared by its ranks)\n"
         "  --item-buffer OUT.npy  (object, facet) of each pixel's primary hit, int32 (H, W, 2)\n"
         "  --stats OUT.json       ray counts, per-PE work, kernel times, memory, traffic\n"
         "  --reference            render with the sequential host reference instead of OpenCL\n"
         "  -q, --quiet            no device line, warnings, progress or summary (errors still show)\n"
         "  -h, --help             this text\n"
         "\n"
         "A scene without a camera (a bare model) is framed to its bounding box; with no\n"
         "light at all, one white light sits at the eye. A render that takes more than\n"
         "about two seconds shows its progress on stderr.\n";
}

// ------------------------------------------------------------------ parsing

namespace {

CommandSyntax render_syntax() {
  CommandSyntax syntax;
  syntax.command = "render";
  syntax.flags = {{"-o", "-o", true},          {"--output", "-o", true},     {"--item-buffer", "--item-buffer", true},
                  {"--stats", "--stats", true}, {"--reference", "--reference", false}, {"--exr-half", "--exr-half", false}, {"-q", "-q", false},
                  {"--quiet", "-q", false},     {"-h", "--help", false},       {"--help", "--help", false}};
  syntax.flags.insert(syntax.flags.end(), view_flags().begin(), view_flags().end());
  return syntax;
}

}  // namespace

RenderOptions parse_render_options(const std::vector<std::string>& args) {
  RenderOptions o;
  walk_scene_command(args, render_syntax(), o, [&](const std::string& flag, const std::string& name,
                                                   const std::string& value) {
    if (flag == "-o") {
      const std::string ext = extension_of(value);
      if (ext != ".png" && ext != ".pfm" && ext != ".exr") bad_flag(name, value, "output must end in .png, .pfm or .exr");
      if (ext == ".exr" && !exr_available())
        bad_flag(name, value, "this build has no OpenEXR (install libopenexr-dev and rebuild)");
      o.output_path = value;
    } else if (flag == "--item-buffer") {
      o.item_buffer_path = path_ending_in(name, value, ".npy", "item buffer must end in .npy");
    } else if (flag == "--stats") {
      o.stats_path = path_ending_in(name, value, ".json", "stats must end in .json");
    } else if (flag == "--reference") {
      o.reference = true;
    } else if (flag == "--exr-half") {
      o.exr_half = true;
    }
  });
  if (o.help) return o;
  if (o.output_path.empty()) throw InputError("-o: missing output file OUT.png, OUT.pfm or OUT.exr");
  if (o.exr_half && extension_of(o.output_path) != ".exr")
    throw InputError("--exr-half: the output " + o.output_path + " is not .exr");
  check_view_flags(o);
  check_distinct_outputs(o);
  return o;
}

// ------------------------------------------------------------------ render

namespace {

// --reference: the sequential host renderer. One processor: every primary
// hit and spawned ray is a "descriptor" that finishes at once, as
// RenderStats counts them.
RenderResult render_on_host(const Scene& scene, bool quiet, Progress& progress, std::string& device) {
  const int threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  device = "host reference (" + std::to_string(threads) + " threads)";
  if (!quiet) print_line("device", device);
  const auto start = std::chrono::steady_clock::now();
  RenderResult result;
  static_cast<ImageResult&>(result) = render_reference(scene, threads, &progress);
  RenderStats& s = result.stats;
  s.render_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  s.prepare = prepare_times();  // reading and parsing: nothing else to prepare
  s.descriptors_spawned = result.rays.primary_hits + result.rays.secondary + result.rays.shadow;
  s.descriptors_finished = s.descriptors_spawned;
  s.num_pes = 1;
  return result;
}

// The image, item buffer and statistics, all together or none; then the
// summary line.
void write_render_outputs(const RenderOptions& o, OutputFiles& outputs, const RenderResult& result,
                          const Scene& scene, const RenderSettings& settings, const std::string& device) {
  outputs.write(o.output_path, encode_output(o, result));
  if (!o.item_buffer_path.empty())
    outputs.write(o.item_buffer_path, encode_npy_item_buffer(result.height, result.width, result.item_buffer));
  if (!o.stats_path.empty())
    outputs.write(o.stats_path, stats_json(result, scene, settings, device).dump(2) + "\n");
  outputs.commit();
  if (o.quiet) return;
  // The kernels' compile (a first run on a device) is said apart from the frame's time.
  char compile[96] = "";
  if (result.stats.kernel_compile_seconds >= 0.5)
    std::snprintf(compile, sizeof compile, "; kernel compile %.1f s, not counted", result.stats.kernel_compile_seconds);
  char line[512];
  std::snprintf(line, sizeof line, "%s (%dx%d, depth %d, %llu rays in %.3f s%s)", o.output_path.c_str(), result.width,
                result.height, scene.max_depth, static_cast<unsigned long long>(result.rays.total()),
                result.stats.render_seconds, compile);
  std::fprintf(stderr, "opsila: wrote %s\n", line);
}
// The machine's flags, which the sequential reference has no use for:
// each named, as the image is the same without them.
void warn_reference_ignores(const RenderOptions& o) {
  if (!o.device_spec.empty()) print_line("warning", "--device is ignored with --reference");
  const char* machine = " is ignored with --reference (one processor, no banks)";
  if (o.balance) print_line("warning", std::string("--balance") + machine);
  if (o.pes) print_line("warning", std::string("--pes") + machine);
  if (o.bank_capacity != 0) print_line("warning", std::string("--bank-capacity") + machine);
  if (o.work_groups_per_pe != 0) print_line("warning", std::string("--work-groups-per-pe") + machine);
  if (o.routing) print_line("warning", std::string("--routing") + machine);
}


}  // namespace

int run_render(const std::vector<std::string>& args, Ranks& ranks) {
  const RenderOptions o = parse_render_options(args);
  if (answered_help(o, render_usage())) return kExitOk;
  // Under mpirun every rank renders its group of PEs; rank 0 alone writes.
  ranks.start();
  const bool writer = ranks.rank() == 0;
  // Everything that can be checked without rendering is checked first;
  // nothing is created until every output is ready.
  install_interrupt_cleanup();
  OutputFiles outputs;
  if (writer) {
    outputs.declare("-o", o.output_path);
    if (!o.item_buffer_path.empty()) outputs.declare("--item-buffer", o.item_buffer_path);
    if (!o.stats_path.empty()) outputs.declare("--stats", o.stats_path);
  }
  check_scene_file(o.scene_path);
  // Each rank's own checks end here (rank 0's outputs, this rank's copy of
  // the scene): a rank that failed one meets the others in this agreement
  // from its error handler, before any other collective.
  ranks.checkpoint();
  check_started_alike(ranks, args, o.scene_path);
  outputs.refuse_inputs({o.scene_path});
  outputs.refuse_inputs(env_hook_inputs());
  if (o.reference && ranks.size() > 1)
    throw InputError("--reference is the sequential host renderer: run it as one process, without mpirun");

  std::optional<ClRuntime> runtime;
  if (!o.reference) {
    runtime.emplace(choose_device_flag(o.device_spec, ranks));
    if (!o.quiet && writer) runtime->on_slow_build([](const std::string& note) { print_line("note", note); });
  }
  // --host-memory is taken as given; past the machine's memory a scene it
  // admits can still run out while it loads.
  if (!o.quiet && writer && o.host_memory > physical_memory() && physical_memory() > 0) {
    char text[160];
    std::snprintf(text, sizeof text, "--host-memory %.1f GiB is more than this machine's %.1f GiB: a scene it "
                  "admits may run out of memory while loading", double(o.host_memory) / (1 << 30),
                  double(physical_memory()) / (1 << 30));
    print_line("warning", text);
  }
  if (!o.quiet && writer)
    for (const std::string& w : unknown_env_hooks()) print_line("warning", w);
  if (o.reference && !o.quiet) warn_reference_ignores(o);

  Progress progress("render", !o.quiet && writer);
  PrepareRequest request;
  request.view = o;
  request.quiet = o.quiet || !writer;
  request.reference = o.reference;
  request.ranks = &ranks;
  request.outputs = &outputs;
  request.note = [](const std::string& note) { print_line("note", note); };
  request.progress = &progress;
  request.count_work = !o.stats_path.empty();  // only --stats reads the work counters
  request.launch_records = !o.stats_path.empty();  // and the launches' times
  request.item_buffer_output = !o.item_buffer_path.empty();
  PreparedScene prepared = prepare_scene(request, runtime ? &*runtime : nullptr);
  // Said once the scene is read, so that bad input gets its error line alone.
  std::string device;
  if (runtime) {
    device = runtime->description();
    if (!o.quiet) print_line("device", device_text(ranks, prepared.settings.num_pes, device));
    if (ranks.size() > 1 && writer) device = std::to_string(ranks.size()) + " MPI ranks; rank 0: " + device;
  }

  RenderResult result;
  if (o.reference) {
    result = render_on_host(prepared.scene, o.quiet, progress, device);
    prepared.settings.num_pes = 1;
  } else {
    result = Renderer(prepared.scene, std::move(*prepared.banks), prepared.settings, *runtime).render();
  }
  progress.finish();
  if (writer) write_render_outputs(o, outputs, result, prepared.scene, prepared.settings, device);
  ranks.checkpoint();  // rank 0 writes the outputs; a failure there ends every rank alike
  return kExitOk;
}

// ----------------------------------------------------------------- devices

int run_devices(const std::vector<std::string>& args) {
  for (const std::string& a : args) {
    if (a == "-h" || a == "--help") {
      std::fputs("usage: opsila devices\nLists OpenCL platforms and devices; '*' marks the default.\n", stdout);
      return kExitOk;
    }
    throw InputError("devices: unexpected argument '" + a + "'");
  }
  check_driver_preconditions();
  const std::vector<DeviceEntry> devices = list_devices();
  int default_index = -1;
  try {
    default_index = choose_device("").flat_index;
  } catch (const InputError&) {
    // No usable default: list anyway.
  }
  if (devices.empty()) {
    std::puts("no OpenCL devices");
    return kExitOk;
  }
  for (const DeviceEntry& d : devices) {
    cl_int err = CL_SUCCESS;
    const cl_device_type type = d.device.getInfo<CL_DEVICE_TYPE>(&err);
    cl_check(err, "clGetDeviceInfo(CL_DEVICE_TYPE)");
    std::string type_name = (type & CL_DEVICE_TYPE_GPU)           ? "GPU"
                            : (type & CL_DEVICE_TYPE_CPU)         ? "CPU"
                            : (type & CL_DEVICE_TYPE_ACCELERATOR) ? "accelerator"
                                                                  : "other";
    const cl_uint units = d.device.getInfo<CL_DEVICE_MAX_COMPUTE_UNITS>(&err);
    cl_check(err, "clGetDeviceInfo(CL_DEVICE_MAX_COMPUTE_UNITS)");
    const cl_ulong memory = d.device.getInfo<CL_DEVICE_GLOBAL_MEM_SIZE>(&err);
    cl_check(err, "clGetDeviceInfo(CL_DEVICE_GLOBAL_MEM_SIZE)");
    const std::size_t max_wg = d.device.getInfo<CL_DEVICE_MAX_WORK_GROUP_SIZE>(&err);
    cl_check(err, "clGetDeviceInfo(CL_DEVICE_MAX_WORK_GROUP_SIZE)");
    std::printf("%c [%d] %d:%d  %s%s\n", d.flat_index == default_index ? '*' : ' ', d.flat_index,
                d.platform_index, d.device_index, d.device_name.c_str(),
                d.flat_index == default_index ? "  (default)" : "");
    std::printf("      platform: %s\n", d.platform_name.c_str());
    std::printf("      type: %s, vendor: %s, version: %s, driver: %s\n", type_name.c_str(), d.vendor.c_str(),
                d.version.c_str(), d.driver_version.c_str());
    std::printf("      compute units: %u, global memory: %s, max work-group size: %zu\n", units,
                format_bytes(double(memory), 1, 2).c_str(), max_wg);
  }
  for (const std::string& name : platforms_without_devices()) {
    const std::string hint = no_devices_hint(name);
    std::printf("  platform %s: no devices%s\n", name.c_str(), hint.empty() ? "" : (" (" + hint + ")").c_str());
  }
  return kExitOk;
}

// ---------------------------------------------------------------- dispatch

int run_cli(const std::vector<std::string>& args, Ranks& ranks) {
  if (args.empty()) throw InputError("no command (see 'opsila --help')");
  const std::string& command = args[0];
  const std::vector<std::string> rest(args.begin() + 1, args.end());
  const bool bare = command == "--help" || command == "-h" || command == "help" || command == "--version" ||
                    command == "-V";
  if (bare && !rest.empty()) throw InputError(command + ": takes no argument, not '" + rest[0] + "'");
  if (command == "--help" || command == "-h" || command == "help") {
    std::fputs(main_usage().c_str(), stdout);
    return kExitOk;
  }
  if (command == "--version" || command == "-V") {
    std::puts("opsila " OPSILA_VERSION);
    return kExitOk;
  }
  if (command == "render") return run_render(rest, ranks);
  if (command == "devices") return run_devices(rest);
  throw InputError("unknown command '" + command + "' (see 'opsila --help')");
}

int report_exception(std::exception_ptr error, const Ranks& ranks) {
  std::string message;
  const int code = describe_exception(error, message);
  // One error line; a kernel build log, the one message of several lines,
  // follows it indented. Any other line break is a name's or a value's own
  // and is shown escaped on the line (shown_text).
  const std::size_t log = message.find("build log:\n");
  const std::size_t head = log == std::string::npos ? message.size() : log + 10;
  print_line("error", ranks.label() + (message.empty() ? "unknown failure" : message.substr(0, head)));
  std::istringstream lines(message.substr(std::min(message.size(), head + 1)));
  for (std::string line; log != std::string::npos && std::getline(lines, line);)
    std::fprintf(stderr, "    %s\n", shown_text(line).c_str());
  std::fflush(stderr);
  return code;
}

int report_rank_failure(std::exception_ptr error, Ranks& ranks) {
  try {
    std::rethrow_exception(error);
  } catch (const OtherRankFailed& e) {
    return e.code;  // that rank printed the message
  } catch (...) {
  }
  if (ranks.size() == 1) return report_exception(error, ranks);
  // The others may wait for this rank in a collective: end them all.
  std::string message;
  int code = describe_exception(error, message);
  if (ranks.in_collective()) ranks.abort(code, [&] { report_exception(error, ranks); });
  if (ranks.agree(code) == ranks.rank()) report_exception(error, ranks);
  return code;
}

int describe_exception(std::exception_ptr error, std::string& message) {
  int code = kExitFailure;
  try {
    std::rethrow_exception(error);
  } catch (const InputError& e) {
    message = e.what();
    code = kExitUsage;
  } catch (const ClError& e) {
    message = std::string("OpenCL: ") + e.what();
    code = kExitDevice;
  }
  catch (const std::bad_alloc&) {
    // The loaders name the file they were reading; what is left is the
    // host running out while the scene is banked or the frame prepared.
    message = "out of host memory while preparing the render: the scene's meshes and texture maps with the "
              "frame's buffers do not fit (use a smaller --size, fewer --pes or smaller models and images)";
    code = kExitUsage;
  } catch (const std::system_error& e) {
    message = e.what();
    // A host thread that cannot start (ulimit -v, -u): the host's limits,
    // as running out of memory is, not a fault of opsila's.
    if (e.code() == std::errc::resource_unavailable_try_again || e.code() == std::errc::not_enough_memory) {
      message = std::string("cannot start a host thread (") + e.code().message() +
                "): the process's memory or thread limit (ulimit -v, ulimit -u) is too low for this render";
      code = kExitUsage;
    }
  } catch (const std::exception& e) {
    message = e.what();
  } catch (...) {
    message = "unknown failure";
  }
  return code;
}

}  // namespace opsila
