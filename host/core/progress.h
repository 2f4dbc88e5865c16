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


namespace opsila {

// A count for people: "12.3 M", "4.56 G".
std::string count_text(double n);

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

}  // namespace opsila
