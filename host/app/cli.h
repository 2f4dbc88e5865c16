// The command line (CONTRACT "Command line"): `opsila render`, `opsila devices`,
// help and version. host/app/main.cpp dispatches to run_cli (and to the bench).
#pragma once

#include <exception>
#include <optional>
#include <string>
#include <vector>

#include "app/args.h"
#include "scene/scene.h"

namespace opsila {

// `opsila render` arguments: the view group (app/args.h) and the outputs.
struct RenderOptions : ViewOptions {
  std::string output_path;       // -o, .png, .pfm or .exr
  bool exr_half = false;         // --exr-half: .exr in 16-bit half floats
  std::string item_buffer_path;  // --item-buffer, .npy
  std::string stats_path;        // --stats, .json
  bool reference = false;        // sequential host reference instead of OpenCL
  bool quiet = false;
  bool help = false;
};

// Parses the arguments after "render". Throws InputError with a one-line
// message naming the flag and the problem.
RenderOptions parse_render_options(const std::vector<std::string>& args);

std::string main_usage();
std::string render_usage();

int run_render(const std::vector<std::string>& args, Ranks& ranks);
int run_devices(const std::vector<std::string>& args);
// Everything but `bench`: args are argv[1..].
int run_cli(const std::vector<std::string>& args, Ranks& ranks);

// Prints "opsila: error: ..." (one line) for the exception and returns its
// exit code. Used by main() around every command.
int report_exception(std::exception_ptr error, const Ranks& ranks);
// The exit code for the exception and its message, printing nothing.
int describe_exception(std::exception_ptr error, std::string& message);
// main()'s handler: report_exception for one process. With several MPI
// ranks, a failure in set-up is agreed on (the lowest failing rank prints,
// every rank exits with its code); a failure while ranks wait on each other
// prints and ends every rank (MPI_Abort). Never a hang.
int report_rank_failure(std::exception_ptr error, Ranks& ranks);

}  // namespace opsila
