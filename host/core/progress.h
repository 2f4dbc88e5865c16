// Progress of a long render, bench or preparation stage on stderr: fraction
// done, rays/s (where rays are cast), elapsed and estimated time left. Silent for the first couple of seconds (a
// short run prints nothing), then redrawn in place on a terminal, or one
// plain line every few seconds when stderr is a file or a pipe.
//
// The loop that owns the work calls due() at its natural boundaries (a round,
// a band of rows): a clock read, nothing more. Only when it returns true does
// the caller gather its counts and call report(). Nothing here touches the
// work itself, so an image never depends on whether progress is shown.
//
// OPSILA_PROGRESS_AFTER=SECONDS (environment) replaces the two-second delay,
// e.g. 0 to see (or test) progress on a small scene.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>
#include <thread>

#include "core/scene.h"

namespace opsila {

class Progress {
 public:
  // `label` names the stage ("render", "bench: OPSILA run 3/5"). A disabled
  // reporter (-q) never prints.
  Progress(std::string label, bool enabled);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  // Starts the clock again for a new stage with a new label.
  void restart(std::string label);
  // Starts the clock again, same label: the work itself begins now (after
  // loading, partitioning and kernel builds).
  void start();
  // True when a line is due now.
  bool due();
  // fraction in [0, 1], a lower bound of the work done (the caller says what
  // it counts); rays cast so far. Monotone: a smaller fraction than the last
  // one shown is shown as the last one.
  void report(double fraction, std::uint64_t rays);
  // The same line for a stage that casts no rays (core/stage_clock.h).
  void report(double fraction);
  // Ends the stage: a line redrawn in place gets its newline.
  void finish();

 private:
  using Clock = std::chrono::steady_clock;
  std::string label_;
  bool enabled_ = false, tty_ = false, drawn_ = false;
  double after_ = 2.0, every_ = 5.0;
  double shown_fraction_ = 0;
  Clock::time_point start_, next_;
  void show(double fraction, const char* rays_per_s);
};

// The delay before a progress line first shows: two seconds, or
// OPSILA_PROGRESS_AFTER seconds when set to a valid value.
double progress_delay();

// Calls `say` once, from a thread of its own, if it is still alive `after`
// seconds from now: a long blocking call (a kernel build) is not silent,
// and a short one prints nothing.
class SlowNote {
 public:
  SlowNote(double after, std::function<void()> say);
  ~SlowNote();  // cancels the note if it has not been said
  SlowNote(const SlowNote&) = delete;
  SlowNote& operator=(const SlowNote&) = delete;

 private:
  std::mutex lock_;
  std::condition_variable wake_;
  bool done_ = false;
  std::thread watcher_;
};

// Upper bound of the rays a render can cast: pixels x spp x the largest ray
// tree (a radiance ray per level per reflective/transmissive branch, each
// with a shadow ray per light). Worth saying up front when it is large.
struct WorkBound {
  double rays = 0;           // the bound (double: 2^31-node trees overflow 64 bits)
  double rays_per_sample = 0;
  int branches = 0;          // 0, 1 or 2: reflected and/or transmitted children possible
};
WorkBound work_bound(const Scene& scene);
// One line for stderr when the bound is at least kLargeWork rays, else "".
constexpr double kLargeWork = 1e9;
std::string large_work_note(const Scene& scene);

}  // namespace opsila
