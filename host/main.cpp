// opsila: command-line entry point. Every failure ends here as one
// "opsila: error: ..." line and an exit code (see cli.h); nothing escapes.
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "cli.h"

#if __has_include("bench.h")
#include "bench.h"
#define OPSILA_HAVE_BENCH 1
#endif

int main(int argc, char** argv) {
  try {
    const std::vector<std::string> args(argv + 1, argv + argc);
    if (!args.empty() && args[0] == "bench") {
#ifdef OPSILA_HAVE_BENCH
      return opsila::run_bench(std::vector<std::string>(args.begin() + 1, args.end()));
#else
      std::fputs("opsila: error: bench: not built\n", stderr);
      return opsila::kExitFailure;
#endif
    }
    return opsila::run_cli(args);
  } catch (...) {
    return opsila::report_exception(std::current_exception());
  }
}
