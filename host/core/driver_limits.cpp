#include "core/driver_limits.h"

#include <sys/resource.h>
#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <condition_variable>
#include <cstdint>
#include <cstdlib>
#include <mutex>
#include <string>
#include <system_error>
#include <thread>
#include <vector>

#include "core/errors.h"

namespace opsila {

namespace {

// Descriptors a cold compile needs: PoCL's kernel build failed at 12, ran at
// 16 (`hundreds`' program); twice that leaves room for the models' files.
constexpr rlim_t kOpenFiles = 32;

void check_open_files() {
  struct rlimit rl {};
  if (::getrlimit(RLIMIT_NOFILE, &rl) != 0 || rl.rlim_cur >= kOpenFiles) return;
  if (rl.rlim_max > rl.rlim_cur) {
    struct rlimit raised = rl;
    raised.rlim_cur = std::min(rl.rlim_max, kOpenFiles);
    if (::setrlimit(RLIMIT_NOFILE, &raised) == 0) rl = raised;
  }
  if (rl.rlim_cur < kOpenFiles)
    throw InputError("the open-files limit (ulimit -n) is " + std::to_string(rl.rlim_cur) +
                     ": the OpenCL driver's kernel compiler needs " + std::to_string(kOpenFiles) +
                     " (--reference needs fewer)");
}

// Starts `count` threads that wait until all have started, then ends them;
// the error of the first that could not start, if any.
std::string try_threads(unsigned count) {
  std::mutex m;
  std::condition_variable cv;
  bool go = false;
  std::vector<std::thread> started;
  std::string failure;
  try {
    started.reserve(count);
    for (unsigned i = 0; i < count; ++i)
      started.emplace_back([&] {
        std::unique_lock<std::mutex> lock(m);
        cv.wait(lock, [&] { return go; });
      });
  } catch (const std::system_error& e) {
    failure = e.code().message();
  }
  {
    std::lock_guard<std::mutex> lock(m);
    go = true;
  }
  cv.notify_all();
  for (std::thread& t : started) t.join();
  return failure;
}

// POCL_MAX_PTHREAD_COUNT: the threads PoCL starts (0 or unset: one a
// core), read by atoi. A negative value, or one past the int range, made it
// crash in its first call (SIGSEGV); 65536 made it abort when the threads
// would not start. Refused beyond kMaxPoclThreads, so it never sees them.
constexpr long kMaxPoclThreads = 4096;
unsigned pocl_thread_count() {
  const char* text = std::getenv("POCL_MAX_PTHREAD_COUNT");
  if (!text) return 0;
  errno = 0;
  char* end = nullptr;
  const long long n = std::strtoll(text, &end, 10);  // what atoi reads, its overflow seen
  if (end == text) return 0;                         // no number: atoi's 0, PoCL's default
  if (n < 0 || n > kMaxPoclThreads || errno == ERANGE)
    throw InputError("POCL_MAX_PTHREAD_COUNT=" + std::string(text).substr(0, 20) +
                     ": PoCL's thread count must be 1 to " + std::to_string(kMaxPoclThreads) + " (0 or unset: one a core)");
  return unsigned(n);
}

void check_threads(unsigned pocl) {
  struct rlimit rl {};
  if (::getrlimit(RLIMIT_NPROC, &rl) != 0 || rl.rlim_cur == RLIM_INFINITY) return;
  // PoCL's workers, one a core (POCL_MAX_PTHREAD_COUNT where set), and one more.
  unsigned count = std::max(1u, std::thread::hardware_concurrency());
  if (pocl > 0) count = pocl;
  const std::string failure = try_threads(count + 1);
  if (!failure.empty())
    throw InputError("the thread limit (ulimit -u) is " + std::to_string(rl.rlim_cur) + ": the OpenCL driver starts " +
                     std::to_string(count) + " threads and this process could not start as many (" + failure +
                     "; --reference runs on the threads it can start)");
}

}  // namespace

void check_driver_preconditions() {
  if (const char* cache = std::getenv("POCL_CACHE_DIR"); cache && !*cache) {
    throw InputError("POCL_CACHE_DIR is set but empty: name a folder for PoCL's kernel cache, or unset it");
  } else if (struct stat st {}; cache && ::stat(cache, &st) == 0 && !S_ISDIR(st.st_mode)) {
    // PoCL failed every kernel build there, its own lines on stderr first.
    throw InputError(std::string("POCL_CACHE_DIR=") + cache + ": not a folder (PoCL keeps its compiled kernels in it)");
  }
  check_open_files();
  check_threads(pocl_thread_count());
}

void check_cpu_driver_environment() {
  struct rlimit rl {};
  constexpr std::uint64_t kStack = std::uint64_t(1) << 20;  // PoCL's kernels overflowed 256 KiB (instances)
  if (::getrlimit(RLIMIT_STACK, &rl) == 0 && rl.rlim_cur != RLIM_INFINITY && rl.rlim_cur < kStack)
    throw InputError("the stack limit (ulimit -s) is " + std::to_string(rl.rlim_cur >> 10) +
                     " KiB: the OpenCL driver's threads run the kernels on stacks of that size and need " +
                     std::to_string(kStack >> 10) + " KiB (--reference needs less)");
}

}  // namespace opsila
