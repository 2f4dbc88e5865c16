#include "core/progress.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "core/env_hooks.h"

namespace opsila {

namespace {

double seconds_between(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

std::string duration_text(double s) {
  char text[32];
  if (s < 60)
    std::snprintf(text, sizeof text, "%.1f s", s);
  else if (s < 3600)
    std::snprintf(text, sizeof text, "%dm%02ds", int(s / 60), int(s) % 60);
  else if (s < 1e7)
    std::snprintf(text, sizeof text, "%dh%02dm", int(s / 3600), int(s / 60) % 60);
  else
    std::snprintf(text, sizeof text, "%.0f days", s / 86400);
  return text;
}


}  // namespace

std::string count_text(double n) {
  char text[32];
  if (n >= 1e12)
    std::snprintf(text, sizeof text, "%.3g T", n / 1e12);
  else if (n >= 1e9)
    std::snprintf(text, sizeof text, "%.3g G", n / 1e9);
  else if (n >= 1e6)
    std::snprintf(text, sizeof text, "%.3g M", n / 1e6);
  else if (n >= 1e4)
    std::snprintf(text, sizeof text, "%.3g k", n / 1e3);
  else
    std::snprintf(text, sizeof text, "%.0f", n);
  return text;
}

double progress_delay() {
  if (const char* env = env_hook(EnvHook::progress_after)) {
    char* end = nullptr;
    const double v = std::strtod(env, &end);
    if (end != env && *end == '\0' && v >= 0 && std::isfinite(v)) return v;
  }
  return 2.0;
}

SlowNote::SlowNote(double after, std::function<void()> say) {
  watcher_ = std::thread([this, after, say = std::move(say)] {
    std::unique_lock<std::mutex> hold(lock_);
    if (!wake_.wait_for(hold, std::chrono::duration<double>(after), [this] { return done_; })) say();
  });
}

SlowNote::~SlowNote() {
  {
    std::lock_guard<std::mutex> hold(lock_);
    done_ = true;
  }
  wake_.notify_all();
  watcher_.join();
}

Progress::Progress(std::string label, bool enabled) : label_(std::move(label)), enabled_(enabled) {
  tty_ = ::isatty(STDERR_FILENO) == 1;
  every_ = tty_ ? 0.25 : 5.0;
  after_ = progress_delay();
  start_ = Clock::now();
  next_ = start_ + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(after_));
}

Progress::~Progress() { finish(); }

void Progress::restart(std::string label) {
  label_ = std::move(label);
  start();
}

void Progress::start() {
  finish();
  shown_fraction_ = 0;
  start_ = Clock::now();
  next_ = start_ + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(after_));
}

bool Progress::due() { return enabled_ && Clock::now() >= next_; }

void Progress::report(double fraction, std::uint64_t rays) {
  if (!enabled_) return;
  const double elapsed = seconds_between(start_, Clock::now());
  const double rate = elapsed > 0 ? double(rays) / elapsed : 0;
  show(fraction, count_text(rate).c_str());
}

void Progress::report(double fraction) { show(fraction, nullptr); }

void Progress::show(double fraction, const char* rays_per_s) {
  if (!enabled_) return;
  const Clock::time_point now = Clock::now();
  next_ = now + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(every_));
  shown_fraction_ = std::max(shown_fraction_, std::clamp(fraction, 0.0, 1.0));
  const double elapsed = seconds_between(start_, now);
  std::string left = "time left unknown";
  if (shown_fraction_ > 0) left = "about " + duration_text(elapsed * (1 - shown_fraction_) / shown_fraction_) + " left";
  const std::string rate = rays_per_s ? std::string(rays_per_s) + " rays/s, " : std::string();
  std::fprintf(stderr, "%sopsila: %s: %5.1f%% done, %s%s elapsed, %s%s", tty_ ? "\r" : "", label_.c_str(),
               100 * shown_fraction_, rate.c_str(), duration_text(elapsed).c_str(), left.c_str(),
               tty_ ? "\033[K" : "\n");
  std::fflush(stderr);
  drawn_ = tty_;
}

void Progress::finish() {
  if (drawn_) std::fputc('\n', stderr);
  drawn_ = false;
}

}  // namespace opsila
