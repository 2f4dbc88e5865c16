#include "core/stage_clock.h"

#include <sys/resource.h>

#include "core/progress.h"

namespace opsila {

namespace {

std::mutex g_lock;  // guards g_times
PrepareTimes g_times;
std::atomic<bool> g_show{false};
// The innermost running stage of this thread, and whether the pilot frames
// are running on it (their stages count as theirs).
thread_local StageClock* t_innermost = nullptr;
thread_local int t_pilot_depth = 0;

// How often the watcher looks whether a line is due.
constexpr std::chrono::milliseconds kWatchEvery{50};

}  // namespace

const char* stage_key(PrepareStage s) {
  static const char* const keys[kPrepareStages] = {"read", "parse", "partition", "bank_build", "upload", "pilot"};
  return keys[static_cast<int>(s)];
}

const char* stage_label(PrepareStage s) {
  static const char* const labels[kPrepareStages] = {"reading",           "parsing",   "partitioning",
                                                     "building bank BVHs", "uploading", "pilot frames"};
  return labels[static_cast<int>(s)];
}

PrepareTimes prepare_times() {
  std::lock_guard<std::mutex> hold(g_lock);
  PrepareTimes t = g_times;
  t.peak_host_bytes = host_peak_bytes();
  return t;
}

void reset_prepare_times() {
  std::lock_guard<std::mutex> hold(g_lock);
  g_times = PrepareTimes{};
}

PrepareTimes stages_since(const PrepareTimes& start) {
  PrepareTimes t = prepare_times();
  for (PrepareStage s : {PrepareStage::partition, PrepareStage::bank_build, PrepareStage::upload, PrepareStage::pilots})
    t[s] -= start[s];
  return t;
}

void show_prepare_progress(bool enabled) { g_show = enabled; }

std::uint64_t host_peak_bytes() {
  struct rusage usage {};
  if (getrusage(RUSAGE_SELF, &usage) != 0) return 0;
  return std::uint64_t(usage.ru_maxrss) * 1024;  // Linux: KiB
}

StageClock::StageClock(PrepareStage stage) : stage_(stage) {
  if (t_pilot_depth > 0) {
    counted_ = false;
    return;
  }
  if (stage == PrepareStage::pilots) ++t_pilot_depth;
  outer_ = t_innermost;
  if (outer_) outer_->pause();
  t_innermost = this;
  since_ = Clock::now();
  if (g_show) {
    line_ = std::make_unique<Progress>(stage_label(stage), true);
    watcher_ = std::thread([this] { watch(); });
  }
}

StageClock::~StageClock() {
  if (!counted_) return;
  if (watcher_.joinable()) {
    {
      std::lock_guard<std::mutex> hold(lock_);
      done_ = true;
    }
    wake_.notify_all();
    watcher_.join();
    // A stage that showed progress says when it ended; so does one whose
    // line is due (as the render's last line).
    if (shown_ || line_->due()) line_->report(1.0);
    line_->finish();
  }
  seconds_ += std::chrono::duration<double>(Clock::now() - since_).count();
  {
    std::lock_guard<std::mutex> hold(g_lock);
    g_times[stage_] += seconds_;
    g_times.peak_at_end[static_cast<int>(stage_)] = host_peak_bytes();
  }

  if (stage_ == PrepareStage::pilots) --t_pilot_depth;
  t_innermost = outer_;
  if (outer_) outer_->resume();
}

void StageClock::pause() {
  seconds_ += std::chrono::duration<double>(Clock::now() - since_).count();
  std::lock_guard<std::mutex> hold(lock_);
  paused_ = true;
}

void StageClock::resume() {
  since_ = Clock::now();
  std::lock_guard<std::mutex> hold(lock_);
  paused_ = false;
}

void StageClock::watch() {
  std::unique_lock<std::mutex> hold(lock_);
  while (!done_) {
    wake_.wait_for(hold, kWatchEvery);
    if (!done_ && !paused_ && line_->due()) {
      line_->report(fraction_.load(std::memory_order_relaxed));
      shown_ = true;
    }
  }
}

}  // namespace opsila
