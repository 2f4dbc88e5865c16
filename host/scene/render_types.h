// The renderer's vocabulary that other rooms share: what a frame is asked
// for (RenderSettings, Balance), and what it reports (launch records, the
// frame's statistics, each MPI rank's report, the result). Declared here,
// below the renderer, so that the statistics, the pilot frames, the memory
// plan, the rank exchange, the bench and the command line need not include
// frame/renderer.h.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "scene/image.h"
#include "scene/ray_sample.h"
#include "core/stage_clock.h"
#include "opsila_shared.h"

namespace opsila {

class Progress;
class Ranks;

// How the scene is split over the PEs (--balance): equal shares of facets;
// shares of the frame's rays, sampled on the host first (scene/ray_sample.h);
// or shares of the work that pilot frames measured on the device
// (dist/pilot.h). Never the image.
enum class Balance { facets, work, measured };
const char* balance_name(Balance b);

struct RenderSettings {
  // The processes of the run (mpi/ranks.h): null is one process.
  Ranks* ranks = nullptr;
  int num_pes = 16;
  // n: bank slots per PE on average; P * n descriptors are in flight in each
  // SPMD phase, shared out by demand. 0 = choose from the device.
  int bank_capacity = 0;
  // At most this many work-groups serve one PE's bank per round (0 = as
  // many as its count needs). 1 is the paper's one PE, one processor.
  int work_groups_per_pe = 0;
  // Pixels per item-buffer launch (bounded work per launch). 0: as many as
  // the SPMD launch's slots (P x n, the work bound it keeps), at least 2^16;
  // a GPU's many slots then take a few launches where 2^16 took dozens.
  int item_buffer_tile = 0;
  int routing = OPSILA_ROUTING_BOXES;  // destination choice: cluster boxes, or the paper's spheres
  Progress* progress = nullptr;    // told at round boundaries when set (core/progress.h)
  // measured: the prepare step runs the pilot frames first (prepare/prepare_banks.h).
  Balance balance = Balance::facets;
  // --balance work: the frame's rays, sampled (scene/ray_sample.h); the
  // partition shares expected work as well as facets among the PEs. Without
  // it, the prepare step traces them with `sampler` (prepare/prepare_banks.h).
  const RaySample* ray_sample = nullptr;
  RaySampler sampler;
  // The pilot frames' program, which counts each cluster's tests (dist/pilot.h).
  bool measure_cost = false;
  // Count the work (tests, forwards, PE x PE traffic: RenderStats::counters
  // and traffic) as --stats and the bench read it. false: a program that
  // leaves it out (OPSILA_COUNT_WORK=0); the image, the ray counts and the
  // spawned and finished descriptors are the same.
  bool count_work = true;
  // Prepare both programs, so that Renderer::count_work can switch between
  // them from frame to frame (the bench: timed frames as a plain render
  // runs them, then one counted frame for the work figures).
  bool switch_counting = false;
  // Prepare the stage-clock program too (kernels/lib/stage_cycles.cl), so
  // that Renderer::count_stage_cycles can run a frame that times the SPMD phase's
  // stages (the bench's breakdown; ClRuntime::stage_cycles_unavailable says
  // where it cannot run).
  bool stage_cycles = false;
  // Fill RenderResult::item_buffer with each pixel's centre-ray (object,
  // facet), as --item-buffer writes it. false (a render without
  // --item-buffer, the bench's frames): the item buffer keeps only the hits
  // the frame needs and the output stays empty; the image is the same.
  bool item_buffer_output = true;
  // --balance measured: render the first pilot frame once more before the
  // pilots' clock starts, so that their time (PreparedBanks::pilot_seconds)
  // is the frames' and not the driver's (PoCL compiles a kernel for its
  // work-group size at its first launch). The bench sets it, as its timed
  // frames follow a warm-up frame.
  bool pilot_warm_up = false;
  // The image's read-back: false maps the pixel sums where the device shares
  // host memory (a CPU device) and reads them into pinned host memory
  // elsewhere (a discrete GPU); true takes the second way on any device, so
  // that the tests hold it to the same image on a CPU.
  bool pinned_readback = false;
  // The SPMD launch builds the next round's primary descriptors in
  // work-groups of its own, one launch a round fewer (a GPU's launches cost
  // more than that work); false builds them with a launch of their own, as
  // the tests compare. The same descriptors either way.
  bool primary_ahead = true;
  // Time every launch (RenderStats::launches), as --stats, the bench and
  // several ranks' reports read them. false (a plain render): on a device
  // that does not share host memory (a GPU), only the long launches keep an
  // OpenCL event (Launcher::set_sparse), the others go without; elsewhere
  // every launch is timed still, as a CPU driver's first frame needs its
  // launches' times to leave its kernels' compile out. The same image either
  // way; OPSILA_LAUNCH_EVENTS decides instead when set.
  bool launch_records = true;
};

// One kernel launch, named, with its OpenCL-profiled time.
struct LaunchRecord {
  std::string name;   // e.g. "item_buffer", "spmd_phase", "scatter_move"
  int round = -1;     // SPMD/scatter round, -1 for set-up kernels, kFoldedRound (below)
  double seconds = 0; // CL_PROFILING_COMMAND_END - START
  // When the host enqueued it and when it started, on the device's clock, in
  // seconds after the frame's first enqueue (CL_PROFILING_COMMAND_QUEUED and
  // _START): the gaps between kernels read from them. -1 in a folded record.
  double queued = -1, started = -1;
  std::uint64_t launches = 1;  // more than one: a folded record (Launcher)
  // Past Launcher's record cap, a kernel's later launches are folded into one
  // record of this round: their count and total seconds, so that an endless
  // render's records stay bounded and the per-kernel totals stay exact.
  static constexpr int kFoldedRound = -2;
};

// A rank's part of a scene read in shares (dist/collective_partition.h):
// inactive when every rank read the whole scene.
struct ShareFigures {
  bool active = false;            // the scene was read in shares
  std::uint64_t facets_read = 0;  // triangles of this rank's share of the scene
  std::uint64_t facets_held = 0;  // triangles of its group's banks
  std::uint64_t texture_bytes = 0;  // texels it decoded: the maps its facets use
  std::uint64_t pilot_facets_held = 0;  // --balance measured: the most facets held while the pilots ran
  double read_seconds = 0, partition_seconds = 0, exchange_seconds = 0, bank_seconds = 0;
};

// What one rank did, for --stats and the bench (rank 0 gathers them).
struct RankReport {
  int rank = 0, pe_begin = 0, pe_end = 0;
  std::string host, device;
  std::uint64_t device_bytes = 0;     // planned device memory (scene slice, image, descriptors)
  std::uint64_t scene_bytes = 0;      // of which the scene: own banks + global tables
  std::uint64_t host_peak_bytes = 0;  // peak resident set of the process
  double render_seconds = 0;
  double mpi_seconds = 0;        // inside MPI calls (relay, exchange, reductions)
  double exchange_seconds = 0;   // descriptor exchange: read-back, MPI, write-back (host wall time)
  double exposed_seconds = 0;    // part of it the SPMD phase did not cover
  std::vector<std::pair<std::string, double>> kernel_seconds;  // profiled, by kernel name
  std::vector<std::vector<std::uint64_t>> sent;      // [round][destination rank] descriptors
  std::vector<std::vector<std::uint64_t>> received;  // [round][source rank] descriptors
  ShareFigures share;
};

struct RenderStats {
  // counters[level][pe][OPSILA_STAT_*]
  std::vector<std::vector<std::vector<std::uint64_t>>> counters;
  std::uint64_t descriptors_spawned = 0;   // descriptors created: primary hits, children, shadow rays (not forwards)
  std::uint64_t descriptors_finished = 0;  // shaded hits + misses + occluded + lit
  std::uint64_t forwards = 0;        // extra descriptors for cross-bank nearest hit / shadows
  std::uint64_t overflow_deferrals = 0;  // descriptors that waited a round for a bank slot
  std::uint64_t waiting_peak = 0;        // most descriptors waiting after one exchange (this device)
  int throttled_rounds = 0;              // exchanges that took only rays ending their tree (this device)
  int rounds = 0;                    // SPMD + scatter rounds
  double render_seconds = 0;         // host wall time of the phases
  double readback_seconds = 0;       // of it, the image's read-back and decode (host wall time)
  // The kernels' compilation, kept out of render_seconds: in a machine's
  // first frame, the runtime's program builds so far and the device's long
  // waits before launches (compile_waits, device/launcher.h).
  double kernel_compile_seconds = 0;
  std::vector<LaunchRecord> launches;
  std::vector<std::uint64_t> bank_bytes;  // scene bytes per bank
  std::vector<std::uint64_t> texture_bytes;  // texture copies per bank (part of bank_bytes)
  std::uint64_t texture_replicated_bytes = 0;  // one copy of every texture used
  std::uint64_t global_bytes = 0;         // replicated per PE: spheres, PE boxes, materials, lights
  std::uint64_t replicated_bytes = 0;     // what a replicated scene would cost on each PE
  std::uint64_t device_bytes = 0;         // this device's planned memory (the frame's buffer table)
  // traffic[level][src_pe * P + dst_pe]: descriptors sent (scatter)
  std::vector<std::vector<std::uint64_t>> traffic;
  int bank_capacity = 0;
  int num_pes = 0;
  int num_clusters = 0;
  int routing = OPSILA_ROUTING_BOXES;
  Balance balance = Balance::facets;  // how the partition shared the scene (--balance)
  int pilot_frames = 0;               // --balance measured: pilot frames run while preparing
  double pilot_seconds = 0;           // their time (part of the prepare step, not of the frame)
  double pilot_warm_up_seconds = 0;   // RenderSettings::pilot_warm_up: the untimed frame before them
  PrepareTimes prepare;               // the preparation's stages (core/stage_clock.h)
  std::size_t work_group_size = 0;
  bool quantised_nodes = false;   // the bank walks read BankQNode (ClRuntime::quantised_nodes)
  std::vector<RankReport> ranks;  // several MPI ranks: one report each (rank 0's result only)
};

// The image, its rays (every primary ray, N per pixel, is cast by the item
// buffer; primary hits are the primary descriptors built from it) and how
// the machine ran.
struct RenderResult : ImageResult {
  RenderStats stats;
};

}  // namespace opsila
