#include "core/parallel.h"

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <exception>
#include <mutex>
#include <system_error>
#include <thread>
#include <vector>

#include "core/env_hooks.h"

namespace opsila {

int host_threads() {
  if (const char* env = env_hook(EnvHook::threads)) {
    char* end = nullptr;
    const long v = std::strtol(env, &end, 10);
    if (*end == '\0' && v > 0 && v <= 1024) return static_cast<int>(v);
  }
  // Asked once: the C library reads it from a system file each time, and
  // the median cuts ask at every cut (on a small scene that was a third of
  // the partition). The variable above is read each time (tests set it).
  static const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  return cores;
}

void parallel_for(std::size_t n, const std::function<void(std::size_t)>& task, int threads) {
  const std::size_t workers = std::min<std::size_t>(n, static_cast<std::size_t>(std::max(1, threads)));
  if (workers <= 1) {
    for (std::size_t i = 0; i < n; ++i) task(i);
    return;
  }
  std::atomic<std::size_t> next{0};
  std::mutex lock;
  std::size_t failed_task = n;  // lowest failing task so far (under `lock`)
  std::exception_ptr error;
  auto work = [&] {
    for (std::size_t i = next++; i < n; i = next++) {
      {
        std::lock_guard<std::mutex> hold(lock);
        if (i > failed_task) return;  // a lower task failed: later ones cannot matter
      }
      try {
        task(i);
      } catch (...) {
        std::lock_guard<std::mutex> hold(lock);
        if (i < failed_task) failed_task = i, error = std::current_exception();
      }
    }
  };
  std::vector<std::thread> pool;
  try {
    for (std::size_t w = 1; w < workers; ++w) pool.emplace_back(work);
  } catch (const std::system_error&) {
    // A thread the system will not start (ulimit -u, -v): the tasks are
    // taken in turn, so the threads there are (this one at least) do them all.
  }
  work();
  for (std::thread& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}

void parallel_ranges(std::size_t n, std::size_t grain, const std::function<void(std::size_t, std::size_t)>& fn,
                     int threads) {
  const std::size_t most = (n + std::max<std::size_t>(grain, 1) - 1) / std::max<std::size_t>(grain, 1);
  const std::size_t ranges = std::max<std::size_t>(1, std::min<std::size_t>(most, std::size_t(std::max(1, threads))));
  parallel_for(ranges, [&](std::size_t r) { fn(n * r / ranges, n * (r + 1) / ranges); }, int(ranges));
}

}  // namespace opsila
