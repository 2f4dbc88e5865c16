// Argument groups shared by `opsila render` and `opsila bench`: the word
// splitter, strict value parsers, and the view group (what to render, with
// which camera, lights and machine). Each command adds its own flags on top.
// Every problem is one InputError line naming the flag.
#pragma once

#include <cstddef>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "prepare/view.h"
#include "device/cl_runtime.h"

namespace opsila {

// Exit codes.
constexpr int kExitOk = 0;
constexpr int kExitFailure = 1;  // anything unexpected
constexpr int kExitUsage = 2;    // bad flag, bad input file, unwritable output
constexpr int kExitDevice = 3;   // OpenCL device or driver fault

// Limits checked before any work is done (image limits: scene/scene.h).
constexpr int kMaxBankCapacity = 1 << 24;

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

// "FLAG VALUE: problem" (VALUE shown as '' when empty).
[[noreturn]] void bad_flag(const std::string& flag, const std::string& value, const std::string& problem);
// An integer in lo..hi, else bad_flag.
int int_in_range(const std::string& flag, const std::string& text, long long lo, long long hi);
// The lower-case extension of a file name, with its dot ("" when none).
std::string extension_of(const std::string& path);
// The path when its extension is `ext`, else bad_flag(problem).
std::string path_ending_in(const std::string& flag, const std::string& path, const std::string& ext,
                           const std::string& problem);

// A command's flags: name, the name repeats are counted under, whether it
// takes a value and whether it may be given several times.
struct FlagSpec {
  const char* name;
  const char* canonical;
  bool takes_value;
  bool repeatable = false;
};

// The command-independent walk over the words: one SCENE positional, known
// flags only, "--flag=value" for value flags only, value flags at most once
// unless repeatable. `on_flag(canonical, name, value)` handles each flag;
// `foreign` lists another command's flags, refused with a pointer to it.
struct CommandSyntax {
  const char* command;  // "render" or "bench", for the messages
  std::vector<FlagSpec> flags;
  std::vector<const char*> foreign;
  const char* foreign_kind = "";  // "a render flag, not a bench flag"
};
template <typename OnFlag>
std::string walk_args(const std::vector<std::string>& args, const CommandSyntax& syntax, OnFlag&& on_flag);

// The view group's flags (all but --smooth take a value; --light repeats).
const std::vector<FlagSpec>& view_flags();
// Parses one view flag (canonical name) into `o`; false when `name` is not a
// view flag.
bool parse_view_flag(const std::string& name, const std::string& value, ViewOptions& o);
// --help and -q, which every command takes; false for any other flag.
template <class Options>
bool parse_common_flag(const std::string& name, Options& o) {
  if (name == "--help")
    o.help = true;
  else if (name == "-q")
    o.quiet = true;
  else
    return false;
  return true;
}
// The words of a command that renders a scene (render, bench): its SCENE
// (required but with --help), the view group's and the common flags into
// `o`, and each of the command's own flags to own(canonical, name, value).
template <class Options, typename OnFlag>
void walk_scene_command(const std::vector<std::string>& args, const CommandSyntax& syntax, Options& o,
                        OnFlag&& own) {
  o.scene_path = walk_args(args, syntax, [&](const std::string& flag, const std::string& name,
                                             const std::string& value) {
    if (!parse_view_flag(flag, value, o) && !parse_common_flag(flag, o)) own(flag, name, value);
  });
  if (!o.help && o.scene_path.empty())
    throw InputError(std::string("missing SCENE (see 'opsila ") + syntax.command + " --help')");
}
// With --help: prints the command's usage on stdout and says so.
template <class Options>
bool answered_help(const Options& o, const std::string& usage) {
  if (o.help) std::fputs(usage.c_str(), stdout);
  return o.help;
}
// Camera flags that contradict each other on their own (the rest is checked
// against the scene's camera after loading).
void check_view_flags(const ViewOptions& o);

// The device --device names (the default when empty: under mpirun, the
// ranks of a machine take its GPUs in turn); a problem with the name
// becomes "--device SPEC: problem".
DeviceEntry choose_device_flag(const std::string& spec, const Ranks& ranks);

// Under mpirun, before any other collective: every rank was given the same
// arguments (but --device, each rank's own) and reads the same scene file
// (its size and its first and last MiB; the readers compare what they
// stream, SceneShare::reads). Ranks started unalike (mpirun's ':'
// programs, folders with their own copies) went on to exchange what did
// not match. InputError naming the difference.
void check_started_alike(Ranks& ranks, const std::vector<std::string>& args, const std::string& scene_path);

// ------------------------------------------------------------ walk_args

void walk_positional(const std::string& value, std::string& scene_path, const CommandSyntax& syntax);
const FlagSpec& find_flag_spec(const std::string& name, const CommandSyntax& syntax);

template <typename OnFlag>
std::string walk_args(const std::vector<std::string>& args, const CommandSyntax& syntax, OnFlag&& on_flag) {
  std::string scene_path;
  std::vector<std::string> seen;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const ArgWord word = split_arg(args[i]);
    if (word.positional) {
      walk_positional(word.value, scene_path, syntax);
      continue;
    }
    const FlagSpec& flag = find_flag_spec(word.name, syntax);
    if (!flag.takes_value && word.inline_value) throw InputError(word.name + ": takes no value");
    const std::string value = flag.takes_value ? flag_value(args, i, word) : std::string();
    const std::string canonical = flag.canonical;
    if (flag.takes_value && !flag.repeatable) {
      for (const std::string& s : seen)
        if (s == canonical) throw InputError(word.name + ": given more than once");
      seen.push_back(canonical);
    }
    on_flag(canonical, word.name, value);
  }
  return scene_path;
}

}  // namespace opsila
