// The preparation of a render, stage by stage: reading input files, parsing
// them (and generating the scene file's shapes), partitioning the scene into
// banks, building the bank BVHs, uploading to the device, and the pilot
// frames of --balance measured. Each stage is timed by a StageClock, which
// also shows a progress line on stderr once the stage passes the two-second
// mark (as the render does, core/progress.h): the fraction done, then the
// time. Nothing here touches the work itself.
//
// Time goes to the innermost running stage of the thread (a texture read
// while parsing a scene file is reading, not parsing); inside the pilot
// frames every stage counts as the pilots' own, and stays quiet.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <thread>

namespace opsila {

enum class PrepareStage { read, parse, partition, bank_build, upload, pilots };
constexpr int kPrepareStages = 6;
// "read", "parse", "partition", "bank_build", "upload", "pilot" (the --stats keys, less "_seconds").
const char* stage_key(PrepareStage s);
// What a progress line calls it: "reading", "parsing", ...
const char* stage_label(PrepareStage s);

struct PrepareTimes {
  double seconds[kPrepareStages] = {};
  std::uint64_t peak_host_bytes = 0;  // peak resident set of the process when taken
  // The peak resident set when each stage last ended (0: it never ran):
  // where the memory went, stage by stage (a stage nested in another, the
  // bank BVHs in the partition, ends first).
  std::uint64_t peak_at_end[kPrepareStages] = {};
  double& operator[](PrepareStage s) { return seconds[static_cast<int>(s)]; }
  double operator[](PrepareStage s) const { return seconds[static_cast<int>(s)]; }
};

// The stages' times so far in this process, summed over every run of each
// (several OBJ files, several renderers), with the peak resident set now.
PrepareTimes prepare_times();
void reset_prepare_times();
// What one renderer's preparation took, from prepare_times() taken as it
// began: reading and parsing so far (the scene is loaded once, before),
// the other stages since then; with the peak resident set now.
PrepareTimes stages_since(const PrepareTimes& start);
// Whether stages show progress lines (the CLI: unless -q, and on rank 0
// only). Off by default, so a library user sees nothing.
void show_prepare_progress(bool enabled);
// Peak resident memory of this process so far, in bytes (0 where unknown).
std::uint64_t host_peak_bytes();

class Progress;

class StageClock {
 public:
  explicit StageClock(PrepareStage stage);
  ~StageClock();
  StageClock(const StageClock&) = delete;
  StageClock& operator=(const StageClock&) = delete;
  // The fraction of the stage done, a lower bound in [0, 1]: one atomic
  // store, callable from any thread (the line is drawn by the clock's own
  // thread when due).
  void progress(double fraction) { fraction_.store(fraction, std::memory_order_relaxed); }

 private:
  using Clock = std::chrono::steady_clock;
  void pause();
  void resume();
  void watch();

  PrepareStage stage_;
  bool counted_ = true;  // false inside the pilot frames
  StageClock* outer_ = nullptr;
  double seconds_ = 0;
  Clock::time_point since_;
  std::atomic<double> fraction_{0.0};
  // The progress line: drawn by `watcher_` while this is the innermost stage.
  std::unique_ptr<Progress> line_;
  std::mutex lock_;
  std::condition_variable wake_;
  bool done_ = false, paused_ = false, shown_ = false;
  std::thread watcher_;
};

}  // namespace opsila
