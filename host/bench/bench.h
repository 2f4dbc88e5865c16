// `opsila bench`: the paper's measurements (scatter speed-up against vector
// length, PE occupancy) and more (phase times, exchange share, memory per
// bank), with baselines on the same rays: a replicated-scene megakernel on
// the same device, the sequential host reference, and Embree when built in.
// See docs/BENCHMARKS.md for the JSON schema and how to reproduce.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <utility>
#include <string>
#include <vector>

#include "device/cl_runtime.h"
#include "device/descriptors.h"
#include "mpi/ranks.h"
#include "scene/image.h"
#include "core/util.h"
#include "scene/scene.h"

namespace opsila {

// Entry point of `opsila bench ARGS...` (ARGS = everything after "bench").
// Returns the exit code; throws InputError / ClError like the other commands.
int run_bench(const std::vector<std::string>& args, Ranks& ranks);

// One point of the scatter curve (the paper's figure 6): the scatter kernels
// (count + scan + plan + move, OpenCL-profiled) against host_scatter on the
// same input, and the device's copy bandwidth for the same bytes.
struct ScatterPoint {
  std::size_t length = 0;  // source entries (the vector length)
  std::size_t moved = 0;   // valid entries (placed + waiting)
  std::size_t waiting = 0; // entries that found no bank slot (next queue)
  int pes = 0, n = 0;      // PEs and bank slots per PE (P * n slots in all)
  int repeats = 0;
  double host_seconds = 0;         // median of host_scatter
  double kernel_seconds = 0;       // median of the sum of the scatter kernels
  double count_seconds = 0, plan_seconds = 0, move_seconds = 0;  // of that median run (the plan: scan and plan)
  double copy_kernel_seconds = 0;  // median of copy_float4 over moved * kBytes bytes
  double copy_buffer_seconds = 0;  // median of clEnqueueCopyBuffer, same bytes
  // The paper's primitive alone, Vd(I'(i)) = Vs(i) with I' given: on its six
  // vectors, and on one 64-byte record (kernels/baselines/copy.cl).
  double six_vectors_seconds = 0, one_record_seconds = 0;
  bool verified = false;           // bank counts and queue length equal host_scatter's
  // min / median / max of the timed runs of each figure above.
  Spread host_spread, kernel_spread, copy_kernel_spread, copy_buffer_spread, six_vectors_spread, one_record_spread;
  // Bytes moved by one scatter: descriptor bytes read + written.
  double bytes() const { return 2.0 * double(DescriptorSet::kBytes) * double(moved); }
  double speedup() const { return kernel_seconds > 0 ? host_seconds / kernel_seconds : 0; }
  double gbytes_per_s() const { return kernel_seconds > 0 ? bytes() / kernel_seconds / 1e9 : 0; }
  double host_gbytes_per_s() const { return host_seconds > 0 ? bytes() / host_seconds / 1e9 : 0; }
  double copy_kernel_gbytes_per_s() const { return copy_kernel_seconds > 0 ? bytes() / copy_kernel_seconds / 1e9 : 0; }
  double copy_buffer_gbytes_per_s() const { return copy_buffer_seconds > 0 ? bytes() / copy_buffer_seconds / 1e9 : 0; }
  double six_vectors_gbytes_per_s() const { return six_vectors_seconds > 0 ? bytes() / six_vectors_seconds / 1e9 : 0; }
  double one_record_gbytes_per_s() const { return one_record_seconds > 0 ? bytes() / one_record_seconds / 1e9 : 0; }
};

// Measures one point: `warmup` untimed runs, then the median of `repeats`.
ScatterPoint measure_scatter(ClRuntime& runtime, std::size_t length, int pes, int warmup, int repeats,
                             double hole_rate = 0.0);

// Device memory one point needs: its largest buffer and all its buffers at
// once (the paper's primitive, whose destination holds the banks and the
// waiting pool, is the largest part).
struct ScatterFootprint {
  std::size_t largest = 0, total = 0;
};
ScatterFootprint scatter_footprint(std::size_t length, int pes);

// ------------------------------------------------------ baseline renderers

// A baseline's image and rays, with its timings.
struct BaselineImage : ImageResult {
  double seconds = 0;         // wall time of the frame (scene build excluded; the megakernel's uploads too)
  double kernel_seconds = 0;  // device time (megakernel only)
  double build_seconds = 0;   // acceleration structure / upload preparation
  std::uint64_t triangle_tests = 0, box_tests = 0;  // megakernel only: ray-facet and ray-box tests
};

// The replicated-scene megakernel (kernels/baselines/megakernel.cl): one work-item per
// pixel, one BVH over the whole scene, the same shading and fixed-point sums
// as the OPSILA renderer. `tile` bounds the pixels of one launch. Prepared
// once, as OPSILA's renderer is (its BVH, uploads and output buffers): a
// frame is its kernels and the read-back, and its output pages are not
// mapped afresh every frame.
class Megakernel {
 public:
  // item_buffer: the frames give the item buffer too (BaselineImage::item_buffer).
  Megakernel(const Scene& scene, ClRuntime& runtime, int tile = 1 << 16, bool item_buffer = true);
  ~Megakernel();
  BaselineImage frame();
  // The same frame into `out`, reusing its image storage (Renderer::render).
  void frame(BaselineImage& out);
  // Count the ray-facet and ray-box tests (the default) or not: the
  // program without the counters (KernelProgram::baselines_uncounted,
  // built here) for the bench's timed frames, as OPSILA's timed frames run
  // without theirs. The image and the ray counts are the same.
  void count_work(bool count);
  // One more frame, of the stage-cycle program (megakernel_stages, built
  // here; only where ClRuntime::stage_cycles_unavailable is empty): the
  // cycles of every stage (OPSILA_STAGES), summed over the pixels, then the
  // clock readings that entered each (OPSILA_STAGE_COUNTERS), and the
  // frame's kernel seconds (the clocks' own cost included).
  std::vector<std::uint64_t> stage_cycles(double& kernel_seconds);

 private:
  struct State;
  std::unique_ptr<State> s_;
};

// One frame of a megakernel prepared for it.
BaselineImage render_megakernel(const Scene& scene, ClRuntime& runtime, int tile = 1 << 16);

// Traversal alone: the rays of one megakernel frame (every primary,
// secondary and shadow ray it counts, in its order), traced again through
// the megakernel's BVH by batch kernels that do nothing else
// (kernels/baselines/traversal.cl): no camera, shading, accumulation or
// output. Kernel times, OpenCL-profiled: `warmup` untimed runs, then the
// run of median total of `repeats`. Not present (with the reason) when the
// device cannot hold the rays.
struct TraversalAlone {
  bool present = false;
  std::string skipped;
  std::size_t nearest_rays = 0, any_rays = 0;  // primary and secondary rays; shadow rays
  std::vector<double> seconds_all, nearest_seconds_all, any_seconds_all;
  double seconds = 0, nearest_seconds = 0, any_seconds = 0;  // of the median run
  std::size_t rays() const { return nearest_rays + any_rays; }
  // --rays-out: asked for before the batch is made; then the file's bytes
  // (bench/ray_file.h), the rays with the traversal's answers.
  bool keep_rays = false;
  std::string rays_file;
};
TraversalAlone measure_traversal_alone(const Scene& scene, ClRuntime& runtime, int warmup, int repeats,
                                       int tile = 1 << 16);

// The traversal alone a run at a time, for a bench that interleaves its
// renderers' runs: the construction logs the megakernel's rays and uploads
// them (into `record`'s counts, or its reason when the device cannot hold
// them); run() traces them once and returns the two kernels' device
// seconds (nearest hit, any hit).
class TraversalBatch {
 public:
  TraversalBatch(const Scene& scene, ClRuntime& runtime, TraversalAlone& record, int tile = 1 << 16);
  ~TraversalBatch();
  std::pair<double, double> run();
  // When record.keep_rays: traces the rays once more, reads the answers and
  // puts the rays file in record.rays_file.
  void write_rays_file(TraversalAlone& record);

 private:
  struct State;
  std::unique_ptr<State> s_;
};
// A timed run's seconds into `t`; finish_traversal then keeps the median run's.
void record_traversal_run(TraversalAlone& t, std::pair<double, double> seconds);
void finish_traversal(TraversalAlone& t);

// True when the binary was built with Embree (CMake found it).
bool embree_available();
std::string embree_version();
// The same rays and the same shading as the OPSILA renderer (textures,
// smooth normals, samples per pixel: the host reference's tracer), with the
// hits found by Embree's rtcIntersect1 / rtcOccluded1, on `threads` host
// threads. Throws std::runtime_error when Embree is not built in.
BaselineImage render_embree(const Scene& scene, int threads);

}  // namespace opsila
