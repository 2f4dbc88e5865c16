// The command line (SPEC "Command line"): `opsila render`, `opsila devices`,
// help and version. host/cli/main.cpp dispatches to run_cli (and to the bench).
#pragma once

#include <exception>
#include <optional>
#include <string>
#include <vector>

#include "core/scene.h"

namespace opsila {

// Exit codes.
constexpr int kExitOk = 0;
constexpr int kExitFailure = 1;  // anything unexpected
constexpr int kExitUsage = 2;    // bad flag, bad input file, unwritable output
constexpr int kExitDevice = 3;   // OpenCL device or driver fault

// Limits checked before any work is done.
constexpr int kMaxImageSide = 16384;
constexpr long long kMaxImagePixels = 1LL << 26;
constexpr int kMaxBankCapacity = 1 << 24;

// `opsila render` arguments, parsed and checked one by one. Unset optionals
// leave the scene file's value alone.
struct RenderOptions {
  std::string scene_path;
  std::string output_path;       // -o, .png or .pfm
  std::string item_buffer_path;  // --item-buffer, .npy
  std::string stats_path;        // --stats, .json
  std::string device_spec;       // --device
  std::optional<int> width, height, depth, pes;
  std::optional<Vec3> eye, look_at, up, ambient, background;
  std::optional<float> fov;
  std::vector<LightDesc> lights;  // --light, in order; replace the scene's lights
  int bank_capacity = 0;          // 0 = automatic
  bool reference = false;         // sequential host reference instead of OpenCL
  bool quiet = false;
  bool help = false;
};

// Parses the arguments after "render". Throws InputError with a one-line
// message naming the flag and the problem.
// One command-line word: a positional argument, or a flag whose value may be
// given inline (--flag=value, -o=value).
struct ArgWord {
  bool positional = false;
  std::string name, value;
  bool inline_value = false;
};
ArgWord split_arg(const std::string& arg);
// The flag's value: inline, else the next word (advancing i). A next word
// starting with "--" is the next flag, so the value is missing (InputError).
std::string flag_value(const std::vector<std::string>& args, std::size_t& i, const ArgWord& word);

RenderOptions parse_render_options(const std::vector<std::string>& args);

// Applies the flags to a loaded scene (flags win), frames a scene that has no
// camera, adds the default light at the eye when there is no light at all,
// then checks the final camera, size and depth. Throws InputError.
void apply_render_options(Scene& scene, const RenderOptions& options);

std::string main_usage();
std::string render_usage();

int run_render(const std::vector<std::string>& args);
int run_devices(const std::vector<std::string>& args);
// Everything but `bench`: args are argv[1..].
int run_cli(const std::vector<std::string>& args);

// Prints "opsila: error: ..." (one line) for the exception and returns its
// exit code. Used by main() around every command.
int report_exception(std::exception_ptr error);

}  // namespace opsila
