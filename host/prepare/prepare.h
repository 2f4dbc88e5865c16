// The one entry before the first frame: from what a command asks (the
// scene file, the view flags, the balance, this process's place among the
// ranks) to the scene and the banks ready for the renderer. `opsila render`
// and `opsila bench` parse their flags, call prepare_scene, and write what
// the frames give; nothing here parses a flag or writes an output.
//
//   read     this rank's share of the scene, or all of it (formats/)
//   view     the view flags applied, the limits checked once (prepare/view.h)
//   maps     texture maps settled over the ranks (prepare/map_checks.h)
//   banks    partitioned by the balance, this rank's banks built
//            (prepare/prepare_banks.h: the pilots and ray sample run here)
#pragma once

#include <functional>
#include <optional>
#include <string>

#include "device/cl_runtime.h"
#include "formats/image/output_files.h"
#include "mpi/ranks.h"
#include "partition/banks.h"
#include "prepare/view.h"
#include "scene/render_types.h"
#include "scene/scene.h"

namespace opsila {

class Progress;

struct PrepareRequest {
  ViewOptions view;  // the scene file and the view group; view.balance unset: `balance`
  Balance balance = kDefaultBalance;
  bool quiet = false;      // no progress, notes or warnings on stderr (errors still throw)
  bool reference = false;  // the host reference renders: one processor, no banks
  // This process's place among the ranks (null: one process alone, OneProcess).
  Ranks* ranks = nullptr;
  // The run's outputs: no input file may be one of them.
  OutputFiles* outputs = nullptr;
  // Said to the user (unless quiet): a large frame, a model read whole.
  std::function<void(const std::string&)> note;
  // What the frame is asked for beyond the view (the command's outputs).
  Progress* progress = nullptr;
  bool count_work = false;          // --stats: the work counters
  bool launch_records = true;       // --stats: every launch's time (RenderSettings::launch_records)
  bool item_buffer_output = false;  // --item-buffer
};

struct PreparedScene {
  Scene scene;  // the view applied; a share keeps its place, without its facets once banked
  RenderSettings settings;
  std::optional<PreparedBanks> banks;  // with a runtime and not for the reference
};

// Reads, views and checks the scene, then (given a device runtime, and not
// for the reference) partitions it into this rank's banks. Throws
// InputError naming the file, key or flag for anything the request or the
// scene cannot do, before any frame work.
PreparedScene prepare_scene(const PrepareRequest& request, ClRuntime* runtime);

// The settings alone (machine flags, the balance's sampler, the frame's
// outputs), for a caller that prepares its banks itself (the bench).
RenderSettings prepared_settings(const PrepareRequest& request);

// What this rank reads of a scene: under several ranks only its share, the
// ranks adding up a terrain's windows and decoding texture maps only where
// their banks use them (docs/DISTRIBUTED.md); one process: all of it.
SceneShare scene_share_for(Ranks& ranks);

// "DEVICE", or under mpirun "rank R of N (HOST), PEs A..B: DEVICE" for this
// rank's group of num_pes PEs.
std::string device_text(Ranks& ranks, int num_pes, const std::string& description);

}  // namespace opsila
