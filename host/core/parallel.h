// A small pool of host threads for the preparation stages (OBJ chunks, bank
// BVHs): tasks 0..n-1 taken in turn by up to threads() workers. Results must
// not depend on which thread ran a task, nor in which order: each task writes
// only what is its own, and the caller merges in task order.
#pragma once

#include <cstddef>
#include <functional>

namespace opsila {

// Worker threads for host preparation: the machine's cores, or
// OPSILA_THREADS=N (environment) when set to a positive number.
int host_threads();

// Runs task(i) for i in [0, n) on up to `threads` threads (the calling one
// among them) and returns when all have finished. If tasks throw, the
// exception of the lowest-numbered failing task is rethrown, so the error a
// user sees does not depend on scheduling; tasks still unstarted after a
// failure are skipped unless numbered below it.
void parallel_for(std::size_t n, const std::function<void(std::size_t)>& task, int threads = host_threads());

// Runs fn(begin, end) over [0, n) cut into contiguous ranges of at least
// `grain` items, one range a thread (fewer threads when n is small), for
// loops whose items are independent, such as decoding an image's pixels.
void parallel_ranges(std::size_t n, std::size_t grain, const std::function<void(std::size_t, std::size_t)>& fn,
                     int threads = host_threads());

}  // namespace opsila
