#include "cli/cli.h"

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
#include <thread>

#include "machine/cl_runtime.h"
#include "core/image_io.h"
#include "opsila_shared.h"
#include "reference/reference.h"
#include "machine/renderer.h"
#include "input/scene_file.h"
#include "machine/stats.h"

namespace opsila {

namespace {

[[noreturn]] void bad_flag(const std::string& flag, const std::string& value, const std::string& problem) {
  throw InputError(flag + " " + (value.empty() ? "''" : value) + ": " + problem);
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

std::string extension_of(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  const std::size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  return lower(path.substr(dot));
}

// Strict number parsing: the whole text, no spaces, finite.
bool parse_float(const std::string& text, float& out) {
  if (text.empty() || std::isspace(static_cast<unsigned char>(text[0]))) return false;
  errno = 0;
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (end != text.c_str() + text.size() || errno == ERANGE || !std::isfinite(value)) return false;
  if (std::fabs(value) > 3.0e38) return false;  // beyond float
  out = static_cast<float>(value);
  return true;
}

bool parse_int(const std::string& text, long long& out) {
  if (text.empty()) return false;
  std::size_t i = (text[0] == '-' || text[0] == '+') ? 1 : 0;
  if (i == text.size()) return false;
  for (std::size_t k = i; k < text.size(); ++k)
    if (!std::isdigit(static_cast<unsigned char>(text[k]))) return false;
  errno = 0;
  out = std::strtoll(text.c_str(), nullptr, 10);
  return errno != ERANGE;
}

int int_in_range(const std::string& flag, const std::string& text, long long lo, long long hi) {
  long long value;
  if (!parse_int(text, value)) bad_flag(flag, text, "not an integer");
  if (value < lo || value > hi)
    bad_flag(flag, text, "must be in " + std::to_string(lo) + ".." + std::to_string(hi));
  return static_cast<int>(value);
}

std::vector<float> parse_floats(const std::string& flag, const std::string& text, std::size_t n1,
                                std::size_t n2, const char* shape) {
  std::vector<float> values;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = text.find(',', start);
    const std::string part = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    float v;
    if (!parse_float(part, v)) bad_flag(flag, text, std::string("expected ") + shape + " (finite numbers)");
    values.push_back(v);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  if (values.size() != n1 && values.size() != n2)
    bad_flag(flag, text, std::string("expected ") + shape + ", got " + std::to_string(values.size()) + " numbers");
  return values;
}

Vec3 parse_vec3(const std::string& flag, const std::string& text) {
  const std::vector<float> v = parse_floats(flag, text, 3, 3, "X,Y,Z");
  return Vec3{v[0], v[1], v[2]};
}

Vec3 parse_colour(const std::string& flag, const std::string& text) {
  const std::vector<float> v = parse_floats(flag, text, 3, 3, "R,G,B");
  for (float c : v)
    if (c < 0) bad_flag(flag, text, "colour components must be >= 0");
  return Vec3{v[0], v[1], v[2]};
}

void parse_size(const std::string& text, int& width, int& height) {
  const std::size_t x = text.find_first_of("xX");
  long long w = 0, h = 0;
  const auto digits = [](const std::string& s) {
    return !s.empty() && s.size() <= 12 &&
           std::all_of(s.begin(), s.end(), [](unsigned char c) { return std::isdigit(c); });
  };
  if (x == std::string::npos || !digits(text.substr(0, x)) || !digits(text.substr(x + 1)))
    bad_flag("--size", text, "expected WxH with positive integers");
  w = std::stoll(text.substr(0, x));
  h = std::stoll(text.substr(x + 1));
  if (w <= 0 || h <= 0) bad_flag("--size", text, "width and height must be positive");
  if (w > kMaxImageSide || h > kMaxImageSide)
    bad_flag("--size", text, "each side must be at most " + std::to_string(kMaxImageSide));
  if (w * h > kMaxImagePixels)
    bad_flag("--size", text, std::to_string(w * h) + " pixels exceeds the limit of " +
                                 std::to_string(kMaxImagePixels) + " (2^26)");
  width = static_cast<int>(w);
  height = static_cast<int>(h);
}

std::string format_vec(const Vec3& v) {
  std::ostringstream out;
  out << v[0] << "," << v[1] << "," << v[2];
  return out.str();
}

// The camera basis exists: eye != look-at, up non-zero and not parallel to
// the view direction. Sources name the flags or the file for the message.
void check_camera(const CameraDesc& c, const std::string& eye_source, const std::string& up_source) {
  double f[3], u[3];
  for (int i = 0; i < 3; ++i) {
    f[i] = static_cast<double>(c.look_at[i]) - c.eye[i];
    u[i] = c.up[i];
  }
  const double f_len = std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
  const double u_len = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
  if (!(f_len > 0) || !std::isfinite(f_len))
    throw InputError(eye_source + ": eye and look-at are the same point (" + format_vec(c.eye) + ")");
  if (!(u_len > 0) || !std::isfinite(u_len)) throw InputError(up_source + ": up vector is zero");
  const double cross[3] = {f[1] * u[2] - f[2] * u[1], f[2] * u[0] - f[0] * u[2], f[0] * u[1] - f[1] * u[0]};
  const double sine = std::sqrt(cross[0] * cross[0] + cross[1] * cross[1] + cross[2] * cross[2]) / (f_len * u_len);
  if (sine < 1e-4)  // nearly parallel: the float basis would be noise
    throw InputError(up_source + " (" + format_vec(c.up) + ") is parallel to the view direction (from eye " +
                     format_vec(c.eye) + " to look-at " + format_vec(c.look_at) + ")");
}

void print_line(const std::string& kind, const std::string& text) {
  std::fprintf(stderr, "opsila: %s: %s\n", kind.c_str(), text.c_str());
}

// Flags and whether they take a value.
struct FlagInfo {
  const char* name;
  bool takes_value;
};
const FlagInfo kRenderFlags[] = {
    {"-o", true},        {"--output", true},   {"--size", true},       {"--eye", true},
    {"--look-at", true}, {"--up", true},       {"--fov", true},        {"--light", true},
    {"--ambient", true}, {"--background", true}, {"--depth", true},    {"--pes", true},
    {"--device", true},  {"--item-buffer", true}, {"--stats", true},   {"--bank-capacity", true},
    {"--reference", false}, {"-q", false},     {"--quiet", false},     {"-h", false},
    {"--help", false},
};

const FlagInfo* find_flag(const std::string& name) {
  for (const FlagInfo& f : kRenderFlags)
    if (name == f.name) return &f;
  return nullptr;
}

void check_scene_file(const std::string& path) {
  struct stat st;
  if (::stat(path.c_str(), &st) != 0) throw InputError(path + ": cannot open scene (" + std::strerror(errno) + ")");
  if (S_ISDIR(st.st_mode)) throw InputError(path + ": is a folder, not a scene file");
  if (!S_ISREG(st.st_mode)) throw InputError(path + ": not a regular file");
  if (::access(path.c_str(), R_OK) != 0)
    throw InputError(path + ": cannot read scene (" + std::strerror(errno) + ")");
}

void print_warnings(const Scene& scene, bool quiet) {
  if (quiet) return;
  std::set<std::string> seen;
  for (const std::string& w : scene.warnings)
    if (seen.insert(w).second) print_line("warning", w);
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

std::string human_bytes(unsigned long long bytes) {
  char text[64];
  if (bytes >= (1ULL << 30))
    std::snprintf(text, sizeof text, "%.1f GiB", static_cast<double>(bytes) / (1ULL << 30));
  else
    std::snprintf(text, sizeof text, "%.1f MiB", static_cast<double>(bytes) / (1ULL << 20));
  return text;
}

}  // namespace

// ------------------------------------------------------------------- usage

std::string main_usage() {
  return "opsila " OPSILA_VERSION
         " - a ray tracer that splits the scene into banks over OpenCL processing elements\n"
         "\n"
         "usage:\n"
         "  opsila render SCENE -o OUT.(png|pfm) [options]   render an image\n"
         "  opsila devices                                  list OpenCL platforms and devices\n"
         "  opsila bench [options]                          run the benchmarks\n"
         "  opsila --help | --version\n"
         "\n"
         "Run 'opsila render --help' for the render options.\n"
         "Exit codes: 0 success, 1 unexpected failure, 2 bad input or flag, 3 OpenCL device or driver error.\n";
}

std::string render_usage() {
  return "usage: opsila render SCENE -o OUT.(png|pfm) [options]\n"
         "\n"
         "SCENE is a scene file or a bare .obj (its .mtl found as OBJ says).\n"
         "Flags override the scene file; both '--flag value' and '--flag=value' work.\n"
         "\n"
         "  -o, --output OUT       output image: .png (sRGB, 8 bits) or .pfm (linear float)\n"
         "  --size WxH             image size (each side <= 16384, at most 2^26 pixels)\n"
         "  --eye X,Y,Z            camera position\n"
         "  --look-at X,Y,Z        point the camera looks at\n"
         "  --up X,Y,Z             camera up vector (not parallel to the view direction)\n"
         "  --fov DEG              vertical field of view, 0 < DEG < 180\n"
         "  --light X,Y,Z[,R,G,B]  point light (repeatable; replaces the scene's lights)\n"
         "  --ambient R,G,B        ambient intensity\n"
         "  --background R,G,B     colour of rays that hit nothing\n"
         "  --depth N              ray tree levels, 1..31 (1 = local shading only)\n"
         "  --pes N                processing elements (OpenCL work-groups), 1..1024\n"
         "  --bank-capacity N      descriptor slots per bank (0 = from the device's memory)\n"
         "  --device SPEC          device index, platform:device, or name substring (see 'opsila devices')\n"
         "  --item-buffer OUT.npy  (object, facet) of each pixel's primary hit, int32 (H, W, 2)\n"
         "  --stats OUT.json       ray counts, per-PE work, kernel times, memory, traffic\n"
         "  --reference            render with the sequential host reference instead of OpenCL\n"
         "  -q, --quiet            no device line, warnings or summary\n"
         "  -h, --help             this text\n"
         "\n"
         "A scene without a camera (a bare .obj) is framed to its bounding box; with no\n"
         "light at all, one white light sits at the eye.\n";
}

// ------------------------------------------------------------------ parsing

ArgWord split_arg(const std::string& arg) {
  ArgWord w;
  if (arg.size() < 2 || arg[0] != '-') {
    w.positional = true;
    w.value = arg;
    return w;
  }
  w.name = arg;
  if (const std::size_t eq = arg.find('='); eq != std::string::npos && arg.compare(0, 2, "--") == 0) {
    w.name = arg.substr(0, eq);
    w.value = arg.substr(eq + 1);
    w.inline_value = true;
  } else if (arg.compare(0, 3, "-o=") == 0) {
    w.name = "-o";
    w.value = arg.substr(3);
    w.inline_value = true;
  }
  return w;
}

std::string flag_value(const std::vector<std::string>& args, std::size_t& i, const ArgWord& word) {
  if (word.inline_value) return word.value;
  if (i + 1 >= args.size() || args[i + 1].compare(0, 2, "--") == 0) throw InputError(word.name + ": missing value");
  return args[++i];
}

RenderOptions parse_render_options(const std::vector<std::string>& args) {
  RenderOptions o;
  std::set<std::string> seen;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const ArgWord word = split_arg(args[i]);
    if (word.positional) {
      if (!o.scene_path.empty())
        throw InputError("unexpected argument '" + word.value + "' (one SCENE only; see 'opsila render --help')");
      o.scene_path = word.value;
      continue;
    }
    const std::string& name = word.name;
    const FlagInfo* flag = find_flag(name);
    if (!flag) throw InputError("unknown flag '" + name + "' (see 'opsila render --help')");
    if (!flag->takes_value && word.inline_value) throw InputError(name + ": takes no value");
    const std::string value = flag->takes_value ? flag_value(args, i, word) : std::string();
    std::string canonical = name == "--output" ? "-o" : name == "--quiet" ? "-q" : name == "-h" ? "--help" : name;
    if (canonical != "--light" && flag->takes_value && !seen.insert(canonical).second)
      throw InputError(name + ": given more than once");

    if (canonical == "--help") {
      o.help = true;
    } else if (canonical == "-q") {
      o.quiet = true;
    } else if (canonical == "--reference") {
      o.reference = true;
    } else if (canonical == "-o") {
      const std::string ext = extension_of(value);
      if (ext != ".png" && ext != ".pfm") bad_flag(name, value, "output must end in .png or .pfm");
      o.output_path = value;
    } else if (canonical == "--item-buffer") {
      if (extension_of(value) != ".npy") bad_flag(name, value, "item buffer must end in .npy");
      o.item_buffer_path = value;
    } else if (canonical == "--stats") {
      if (extension_of(value) != ".json") bad_flag(name, value, "stats must end in .json");
      o.stats_path = value;
    } else if (canonical == "--size") {
      int w, h;
      parse_size(value, w, h);
      o.width = w;
      o.height = h;
    } else if (canonical == "--eye") {
      o.eye = parse_vec3(name, value);
    } else if (canonical == "--look-at") {
      o.look_at = parse_vec3(name, value);
    } else if (canonical == "--up") {
      o.up = parse_vec3(name, value);
      const Vec3& u = *o.up;
      if (u[0] == 0 && u[1] == 0 && u[2] == 0) bad_flag(name, value, "up vector is zero");
    } else if (canonical == "--fov") {
      float fov;
      if (!parse_float(value, fov)) bad_flag(name, value, "not a number");
      if (!(fov > 0 && fov < 180)) bad_flag(name, value, "must be strictly between 0 and 180 degrees");
      o.fov = fov;
    } else if (canonical == "--light") {
      const std::vector<float> v = parse_floats(name, value, 3, 6, "X,Y,Z or X,Y,Z,R,G,B");
      LightDesc light;
      light.position = Vec3{v[0], v[1], v[2]};
      if (v.size() == 6) {
        light.intensity = Vec3{v[3], v[4], v[5]};
        if (v[3] < 0 || v[4] < 0 || v[5] < 0) bad_flag(name, value, "intensity must be >= 0");
      }
      o.lights.push_back(light);
      if (o.lights.size() > OPSILA_MAX_LIGHTS)
        throw InputError("--light: more than " + std::to_string(OPSILA_MAX_LIGHTS) + " lights");
    } else if (canonical == "--ambient") {
      o.ambient = parse_colour(name, value);
    } else if (canonical == "--background") {
      o.background = parse_colour(name, value);
    } else if (canonical == "--depth") {
      o.depth = int_in_range(name, value, 1, OPSILA_MAX_DEPTH);
    } else if (canonical == "--pes") {
      o.pes = int_in_range(name, value, 1, OPSILA_MAX_PES);
    } else if (canonical == "--bank-capacity") {
      o.bank_capacity = int_in_range(name, value, 0, kMaxBankCapacity);
    } else if (canonical == "--device") {
      if (value.empty()) bad_flag(name, value, "empty device name");
      o.device_spec = value;
    }
  }
  if (o.help) return o;
  if (o.scene_path.empty()) throw InputError("missing SCENE (see 'opsila render --help')");
  if (o.output_path.empty()) throw InputError("-o: missing output file OUT.png or OUT.pfm");
  // Camera flags that contradict each other on their own are caught now;
  // the rest is checked against the scene's camera after loading.
  if (o.eye && o.look_at) {
    CameraDesc flags_only;
    flags_only.eye = *o.eye;
    flags_only.look_at = *o.look_at;
    if (o.up) flags_only.up = *o.up;
    if (o.up || *o.eye == *o.look_at) check_camera(flags_only, "--eye/--look-at", "--up");
  }
  check_distinct_outputs(o);
  return o;
}

// --------------------------------------------------------- scene overrides

void apply_render_options(Scene& scene, const RenderOptions& o) {
  if (o.width) scene.width = *o.width;
  if (o.height) scene.height = *o.height;
  if (o.depth) scene.max_depth = *o.depth;
  if (o.ambient) scene.ambient = *o.ambient;
  if (o.background) scene.background = *o.background;
  if (o.fov) scene.camera.fov_deg = *o.fov;

  const std::string& file = o.scene_path.empty() ? std::string("scene") : o.scene_path;
  // Checks the scene file's own values too, so the renderer never sees bad ones.
  if (scene.width <= 0 || scene.height <= 0 || scene.width > kMaxImageSide || scene.height > kMaxImageSide ||
      static_cast<long long>(scene.width) * scene.height > kMaxImagePixels)
    throw InputError(file + ": image size " + std::to_string(scene.width) + "x" + std::to_string(scene.height) +
                     " is outside 1..16384 per side and 2^26 pixels");
  if (scene.max_depth < 1 || scene.max_depth > OPSILA_MAX_DEPTH)
    throw InputError(file + ": depth " + std::to_string(scene.max_depth) + " is outside 1..31");
  if (!(scene.camera.fov_deg > 0 && scene.camera.fov_deg < 180))
    throw InputError(file + ": field of view " + std::to_string(scene.camera.fov_deg) +
                     " is not strictly between 0 and 180 degrees");

  // A scene without a camera frames its bounding box; flags given still win.
  if (!scene.has_camera && !scene.triangles.empty()) {
    Vec3 lo, hi;
    scene.bounds(lo, hi);
    const float fov = scene.camera.fov_deg;
    scene.camera = frame_bounds(lo, hi, fov, static_cast<float>(scene.width) / scene.height);
    scene.camera.fov_deg = fov;
  }
  if (o.eye) scene.camera.eye = *o.eye;
  if (o.look_at) scene.camera.look_at = *o.look_at;
  if (o.up) scene.camera.up = *o.up;

  check_camera(scene.camera, (o.eye || o.look_at) ? "--eye/--look-at" : file + ": camera",
               o.up ? "--up" : file + ": camera up");

  if (!o.lights.empty()) {
    scene.lights = o.lights;
    scene.has_lights = true;
  } else if (!scene.has_lights && scene.lights.empty()) {
    // SPEC: with no light given anywhere, one white light sits at the eye.
    LightDesc light;
    light.position = scene.camera.eye;
    light.intensity = Vec3{1, 1, 1};
    scene.lights.push_back(light);
  }
}

// ------------------------------------------------------------------ render

int run_render(const std::vector<std::string>& args) {
  const RenderOptions o = parse_render_options(args);
  if (o.help) {
    std::fputs(render_usage().c_str(), stdout);
    return kExitOk;
  }
  // Everything that can be checked without rendering is checked first.
  check_output_path(o.output_path);
  if (!o.item_buffer_path.empty()) check_output_path(o.item_buffer_path);
  if (!o.stats_path.empty()) check_output_path(o.stats_path);
  check_scene_file(o.scene_path);

  std::optional<ClRuntime> runtime;
  if (!o.reference) {
    DeviceEntry chosen;
    try {
      chosen = choose_device(o.device_spec);
    } catch (const InputError& e) {
      const std::string message = e.what();
      if (o.device_spec.empty() || message.rfind("--device", 0) == 0) throw;
      throw InputError("--device " + o.device_spec + ": " + message);
    }
    runtime.emplace(chosen);
  } else if (!o.device_spec.empty() && !o.quiet) {
    print_line("warning", "--device is ignored with --reference");
  }

  Scene scene = load_scene(o.scene_path);
  print_warnings(scene, o.quiet);
  apply_render_options(scene, o);

  RenderSettings settings;
  if (o.pes) settings.num_pes = *o.pes;
  settings.bank_capacity = o.bank_capacity;

  RenderResult result;
  std::string device;
  if (o.reference) {
    const int threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    device = "host reference (" + std::to_string(threads) + " threads)";
    if (!o.quiet) print_line("device", device);
    const auto start = std::chrono::steady_clock::now();
    ReferenceImage image = render_reference(scene, threads);
    result.stats.render_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    result.width = image.width;
    result.height = image.height;
    result.rgb = std::move(image.rgb);
    result.item_buffer = std::move(image.item_buffer);
    RenderStats& s = result.stats;
    s.primary_rays = image.counts.primary;
    s.primary_hits = image.counts.primary_hits;
    s.secondary_rays = image.counts.secondary;
    s.shadow_rays = image.counts.shadow;
    // One processor: every primary hit and spawned ray is a "descriptor"
    // that finishes at once, as RenderStats counts them.
    s.descriptors_spawned = s.primary_hits + s.secondary_rays + s.shadow_rays;
    s.descriptors_finished = s.descriptors_spawned;
    s.num_pes = 1;
    settings.num_pes = 1;
  } else {
    device = runtime->description();
    if (!o.quiet) print_line("device", device);
    result = render(scene, settings, *runtime);
  }

  if (extension_of(o.output_path) == ".png")
    write_png(o.output_path, result.width, result.height, result.rgb);
  else
    write_pfm(o.output_path, result.width, result.height, result.rgb);
  if (!o.item_buffer_path.empty())
    write_npy_item_buffer(o.item_buffer_path, result.height, result.width, result.item_buffer);
  if (!o.stats_path.empty())
    write_text_file(o.stats_path, stats_json(result, scene, settings, device).dump(2) + "\n");

  if (!o.quiet) {
    const RenderStats& s = result.stats;
    char line[256];
    std::snprintf(line, sizeof line, "%s (%dx%d, depth %d, %llu rays in %.3f s)", o.output_path.c_str(),
                  result.width, result.height, scene.max_depth,
                  static_cast<unsigned long long>(s.primary_rays + s.secondary_rays + s.shadow_rays),
                  s.render_seconds);
    std::fprintf(stderr, "opsila: wrote %s\n", line);
  }
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
                human_bytes(memory).c_str(), max_wg);
  }
  return kExitOk;
}

// ---------------------------------------------------------------- dispatch

int run_cli(const std::vector<std::string>& args) {
  if (args.empty()) throw InputError("no command (see 'opsila --help')");
  const std::string& command = args[0];
  const std::vector<std::string> rest(args.begin() + 1, args.end());
  if (command == "--help" || command == "-h" || command == "help") {
    std::fputs(main_usage().c_str(), stdout);
    return kExitOk;
  }
  if (command == "--version" || command == "-V") {
    std::puts("opsila " OPSILA_VERSION);
    return kExitOk;
  }
  if (command == "render") return run_render(rest);
  if (command == "devices") return run_devices(rest);
  throw InputError("unknown command '" + command + "' (see 'opsila --help')");
}

int report_exception(std::exception_ptr error) {
  std::string message;
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
#ifdef CL_HPP_ENABLE_EXCEPTIONS
  catch (const cl::Error& e) {
    message = std::string("OpenCL: ") + e.what() + ": " + cl_error_name(e.err()) + " (" + std::to_string(e.err()) + ")";
    code = kExitDevice;
  }
#endif
  catch (const std::bad_alloc&) {
    message = "out of memory";
  } catch (const std::exception& e) {
    message = e.what();
  } catch (...) {
    message = "unknown failure";
  }
  // One error line; a multi-line message (a kernel build log) follows it indented.
  std::istringstream lines(message);
  std::string line;
  std::getline(lines, line);
  print_line("error", line.empty() ? "unknown failure" : line);
  while (std::getline(lines, line)) std::fprintf(stderr, "    %s\n", line.c_str());
  return code;
}

}  // namespace opsila
