#include "app/args.h"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <set>
#include <sstream>

#include "scene/camera.h"
#include "core/driver_limits.h"
#include "core/host_memory.h"
#include "core/util.h"
#include "formats/json/scene_file.h"
#include "formats/image/texture_file.h"
#include "prepare/map_checks.h"
#include "mpi/ranks.h"
#include "opsila_shared.h"
#include "reference/reference.h"

namespace opsila {

namespace {

// Strict number parsing: the whole text, decimal (no hexadecimal, which
// strtod takes and the scene and model files do not), finite.
bool parse_float(const std::string& text, float& out) {
  if (text.empty() || text.find_first_not_of("0123456789+-.eE") != std::string::npos) return false;
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

}  // namespace

// ------------------------------------------------------------------ words

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

void bad_flag(const std::string& flag, const std::string& value, const std::string& problem) {
  throw InputError(flag + " " + (value.empty() ? "''" : value) + ": " + problem);
}

int int_in_range(const std::string& flag, const std::string& text, long long lo, long long hi) {
  long long value;
  if (!parse_int(text, value)) bad_flag(flag, text, "not an integer");
  if (value < lo || value > hi)
    bad_flag(flag, text, "must be in " + std::to_string(lo) + ".." + std::to_string(hi));
  return static_cast<int>(value);
}

std::string extension_of(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  const std::size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  return lower(path.substr(dot));
}

std::string path_ending_in(const std::string& flag, const std::string& path, const std::string& ext,
                           const std::string& problem) {
  if (extension_of(path) != ext) bad_flag(flag, path, problem);
  return path;
}

void walk_positional(const std::string& value, std::string& scene_path, const CommandSyntax& syntax) {
  if (!scene_path.empty())
    throw InputError("unexpected argument '" + value + "' (one SCENE only; see 'opsila " + syntax.command +
                     " --help')");
  scene_path = value;
}

const FlagSpec& find_flag_spec(const std::string& name, const CommandSyntax& syntax) {
  for (const FlagSpec& f : syntax.flags)
    if (name == f.name) return f;
  for (const char* f : syntax.foreign)
    if (name == f)
      throw InputError(name + ": " + syntax.foreign_kind + " (see 'opsila " + syntax.command + " --help')");
  throw InputError("unknown flag '" + name + "' (see 'opsila " + syntax.command + " --help')");
}

// ------------------------------------------------------------- view group

const std::vector<FlagSpec>& view_flags() {
  static const std::vector<FlagSpec> flags = {
      {"--size", "--size", true},     {"--eye", "--eye", true},
      {"--look-at", "--look-at", true}, {"--up", "--up", true},
      {"--fov", "--fov", true},       {"--light", "--light", true, true},
      {"--ambient", "--ambient", true}, {"--background", "--background", true},
      {"--depth", "--depth", true},   {"--pes", "--pes", true},
      {"--device", "--device", true}, {"--bank-capacity", "--bank-capacity", true},
      {"--routing", "--routing", true}, {"--work-groups-per-pe", "--work-groups-per-pe", true},
      {"--balance", "--balance", true},
      {"--spp", "--spp", true},
      {"--smooth", "--smooth", false},
      {"--host-memory", "--host-memory", true},
  };
  return flags;
}

bool parse_view_flag(const std::string& name, const std::string& value, ViewOptions& o) {
  if (name == "--size") {
    int w, h;
    parse_size(value, w, h);
    o.width = w;
    o.height = h;
  } else if (name == "--eye") {
    o.eye = parse_vec3(name, value);
  } else if (name == "--look-at") {
    o.look_at = parse_vec3(name, value);
  } else if (name == "--up") {
    o.up = parse_vec3(name, value);
    const Vec3& u = *o.up;
    if (u[0] == 0 && u[1] == 0 && u[2] == 0) bad_flag(name, value, "up vector is zero");
  } else if (name == "--fov") {
    float fov;
    if (!parse_float(value, fov)) bad_flag(name, value, "not a number");
    if (!(fov > 0 && fov < 180)) bad_flag(name, value, "must be strictly between 0 and 180 degrees");
    o.fov = fov;
  } else if (name == "--light") {
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
  } else if (name == "--ambient") {
    o.ambient = parse_colour(name, value);
  } else if (name == "--background") {
    o.background = parse_colour(name, value);
  } else if (name == "--depth") {
    o.depth = int_in_range(name, value, 1, OPSILA_MAX_DEPTH);
  } else if (name == "--spp") {
    long long n;
    if (!parse_int(value, n)) bad_flag(name, value, "not an integer");
    if (const std::string problem = spp_problem(n); !problem.empty()) bad_flag(name, value, problem);
    o.spp = static_cast<int>(n);
  } else if (name == "--pes") {
    o.pes = int_in_range(name, value, 1, OPSILA_MAX_PES);
  } else if (name == "--bank-capacity") {
    o.bank_capacity = int_in_range(name, value, 0, kMaxBankCapacity);
  } else if (name == "--work-groups-per-pe") {
    o.work_groups_per_pe = int_in_range(name, value, 0, kMaxBankCapacity);
  } else if (name == "--routing") {
    if (value == "boxes")
      o.routing = OPSILA_ROUTING_BOXES;
    else if (value == "spheres")
      o.routing = OPSILA_ROUTING_SPHERES;
    else
      bad_flag(name, value, "must be boxes or spheres");
  } else if (name == "--balance") {
    if (value == "facets")
      o.balance = Balance::facets;
    else if (value == "work")
      o.balance = Balance::work;
    else if (value == "measured")
      o.balance = Balance::measured;
    else
      bad_flag(name, value, "must be facets, work or measured");
  } else if (name == "--device") {
    if (value.empty()) bad_flag(name, value, "empty device name");
    o.device_spec = value;
  } else if (name == "--smooth") {
    o.smooth = true;
  } else if (name == "--host-memory") {
    const std::optional<std::uint64_t> bytes = parse_memory_size(value);
    if (!bytes) bad_flag(name, value, "expected a size such as 8G, 512M, 1.5G or a number of bytes");
    o.host_memory = *bytes;
  } else {
    return false;
  }
  return true;
}

void check_view_flags(const ViewOptions& o) {
  if (o.eye && o.look_at) {
    CameraDesc flags_only;
    flags_only.eye = *o.eye;
    flags_only.look_at = *o.look_at;
    if (o.up) flags_only.up = *o.up;
    if (o.up || *o.eye == *o.look_at) check_camera(flags_only, "--eye/--look-at", "--up");
  }
}

namespace {

std::uint64_t fnv1a(std::uint64_t h, const char* data, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) h = (h ^ static_cast<unsigned char>(data[i])) * 0x100000001b3ull;
  return h;
}

// The file's size and its first and last MiB, hashed: cheap on a model of
// gigabytes. 0 for a file that cannot be read (the reader says why).
std::uint64_t file_print(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return 0;
  std::vector<char> buf(std::size_t(1) << 20);
  std::uint64_t h = 0xcbf29ce484222325ull;
  std::size_t n = std::fread(buf.data(), 1, buf.size(), f);
  h = fnv1a(h, buf.data(), n);
  if (std::fseek(f, 0, SEEK_END) == 0) {
    const long size = std::ftell(f);
    h = fnv1a(h, reinterpret_cast<const char*>(&size), sizeof size);
    if (size > long(buf.size()) && std::fseek(f, size - long(buf.size()), SEEK_SET) == 0)
      h = fnv1a(h, buf.data(), std::fread(buf.data(), 1, buf.size(), f));
  }
  std::fclose(f);
  return h;
}

}  // namespace

void check_started_alike(Ranks& ranks, const std::vector<std::string>& args, const std::string& scene_path) {
  if (ranks.size() == 1) return;
  // --device may differ: ranks on one host each take their own GPU.
  std::uint64_t words = 0xcbf29ce484222325ull;
  for (std::size_t k = 0; k < args.size(); ++k) {
    if (args[k] == "--device") {
      ++k;
      continue;
    }
    if (args[k].rfind("--device=", 0) != 0) words = fnv1a(words, args[k].c_str(), args[k].size() + 1);  // NUL parts them
  }
  // Alike when the largest of each value is the smallest's (two collectives).
  std::vector<std::uint64_t> high = {words, file_print(scene_path)}, low = {~high[0], ~high[1]};
  ranks.max(high);
  ranks.max(low);
  if (high[0] != ~low[0])
    throw InputError("the ranks were given different arguments: every rank of a run takes the same command line");
  if (high[1] != ~low[1])
    throw InputError(scene_path + ": the ranks did not read the same file (its size or contents differ between "
                                  "ranks): they see different copies, or it changed while they started");
}

DeviceEntry choose_device_flag(const std::string& spec, const Ranks& ranks) {
  check_driver_preconditions();
  try {
    return choose_rank_device(spec, ranks.local_rank());
  } catch (const InputError& e) {
    const std::string message = e.what();
    if (spec.empty() || message.rfind("--device", 0) == 0) throw;
    throw InputError("--device " + spec + ": " + message);
  }
}

}  // namespace opsila
