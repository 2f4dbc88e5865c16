// opsila: command-line entry point. Every failure ends here as one
// "opsila: error: ..." line and an exit code (see cli.h); nothing escapes.
#include <sys/resource.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
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

// A library that ends the process itself (LLVM inside an OpenCL driver
// calls exit(1) on a failed write while it compiles) leaves its own line;
// this says what it was and turns the status into a device error's.
volatile std::sig_atomic_t g_main_returned = 0;

extern "C" void driver_ended_the_process() {
  // Under an MPI launcher the library may end a rank on purpose (MPICH's
  // MPI_Abort calls exit): the job's own line has been said.
  if (g_main_returned || opsila::launched_by_mpi()) return;
  static const char kLine[] =
      "opsila: error: the OpenCL driver ended the process (its message is above; a full disk or a file-size "
      "limit where it caches kernels, or too little memory, are the usual causes)\n";
  if (::write(STDERR_FILENO, kLine, sizeof kLine - 1) < 0) {
  }
  ::_exit(opsila::kExitDevice);
}

int run(int argc, char** argv) {
  opsila::return_large_frees_to_system();
  // A closed pipe on stdout or stderr is a write error (stdout's is
  // reported: checked_stdout), not a death by SIGPIPE.
  std::signal(SIGPIPE, SIG_IGN);
  // Past a file-size limit (ulimit -f) a write fails with EFBIG and is
  // reported, as a full disk is, rather than killing the process: also the
  // driver's own writes (PoCL's kernel cache) while it builds.
  std::signal(SIGXFSZ, SIG_IGN);
  std::atexit(driver_ended_the_process);
  // A CPU-time limit whose soft and hard values are one (a shell's plain
  // `ulimit -t`) ends the run with SIGKILL, which leaves temporary files:
  // a second less of soft limit brings SIGXCPU first, which removes them.
  struct rlimit cpu {};
  if (::getrlimit(RLIMIT_CPU, &cpu) == 0 && cpu.rlim_cur == cpu.rlim_max && cpu.rlim_max != RLIM_INFINITY &&
      cpu.rlim_max >= 2) {
    cpu.rlim_cur = cpu.rlim_max - 1;
    ::setrlimit(RLIMIT_CPU, &cpu);
  }
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

}  // namespace

int main(int argc, char** argv) {
  const int code = run(argc, argv);
  g_main_returned = 1;
  return code;
}
