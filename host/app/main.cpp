// opsila: command-line entry point. Every failure ends here as one
// "opsila: error: ..." line and an exit code (see cli.h); nothing escapes.
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

#include "app/cli.h"

#include "bench/bench.h"
#include "core/util.h"
#include "mpi/ranks.h"

namespace {

// A listing or report that could not be written (a full disk, a closed
// pipe) is a failure, not a success with nothing shown.
int checked_stdout(int code) {
  errno = 0;
  if (std::fflush(stdout) == 0 && !std::ferror(stdout)) return code;
  std::fprintf(stderr, "opsila: error: standard output: write failed (%s)\n",
               errno ? std::strerror(errno) : "stream error");
  return code == opsila::kExitOk ? opsila::kExitUsage : code;
}

}  // namespace

int main(int argc, char** argv) {
  opsila::return_large_frees_to_system();
  // A closed pipe on stdout or stderr is a write error (stdout's is
  // reported: checked_stdout), not a death by SIGPIPE.
  std::signal(SIGPIPE, SIG_IGN);
  // The one read of the run's process group: every command is handed it.
  opsila::Ranks& world = opsila::Ranks::world();
  try {
    // Under an MPI launcher, join the job first: a bad flag is then one
    // error line from the lowest rank, not one per rank.
    if (opsila::launched_by_mpi()) world.start();
    const std::vector<std::string> args(argv + 1, argv + argc);
    if (!args.empty() && args[0] == "bench") {
      return checked_stdout(opsila::run_bench(std::vector<std::string>(args.begin() + 1, args.end()), world));
    }
    return checked_stdout(opsila::run_cli(args, world));
  } catch (...) {
    return opsila::report_rank_failure(std::current_exception(), world);
  }
}
