// The OPSILA renderer on OpenCL: item buffer (SIMD), then rounds of exchange
// (SIMD scatter) + SPMD phase until every descriptor has finished.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include "partition/banks.h"
#include "device/cl_runtime.h"
#include "scene/render_types.h"
#include "scene/image.h"
#include "scene/ray_sample.h"
#include "opsila_shared.h"
#include "scene/scene.h"

namespace opsila {

// The OPSILA machine, prepared once for one scene and one view, then run for
// as many frames as wanted (the bench's repeats reuse one Renderer).
//   prepare (the constructor): validation, partition into banks, bank size n
//     and the memory plan, work-group sizes, scene uploads, buffers;
//   render(): item buffer, then rounds of primary descriptors, exchange
//     (scatter) and SPMD phase until no descriptor is left, then the image.
// Throws InputError for impossible requests (sizes beyond the device) and
// ClError for driver faults, from either step.
class Renderer {
 public:
  // `banks`: this device's banks, prepared for settings.num_pes PEs
  // (prepare/prepare_banks.h, or bank_scene for a given policy).
  Renderer(const Scene& scene, PreparedBanks banks, const RenderSettings& settings, ClRuntime& runtime);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;
  RenderResult render();
  // The same frame into `out`, whose image storage is reused when it already
  // has this frame's size (the bench's repeated frames: no fresh pages to
  // map in every frame, as Embree's and the megakernel's images are not).
  // When it throws, `out` holds no frame: its contents are left unspecified.
  void render(RenderResult& out);
  // From the next frame on, count the work (tests, forwards, PE x PE
  // traffic) or only the rays (RenderSettings::count_work); the image and
  // the ray counts are the same. Needs RenderSettings::switch_counting, or
  // the way the machine was prepared (std::logic_error otherwise).
  void count_work(bool on);
  // From the next frame on, run the stage-clock program (on) or the one
  // count_work chose; the image and the ray counts are the same. Needs
  // RenderSettings::stage_cycles (std::logic_error otherwise). After a
  // clocked frame, stage_cycles() gives the SPMD phase's cycles per stage
  // (OPSILA_STAGES, kernels/opsila_shared.h), summed over its work-items,
  // then the clock readings that entered each (OPSILA_STAGE_COUNTERS).
  void count_stage_cycles(bool on);
  std::vector<std::uint64_t> stage_cycles();
  // After render() of a Renderer prepared with measure_cost: each cluster's
  // tests per level, [level * clusters + cluster], summed over the ranks
  // (dist/pilot.h spreads them over the facets); empty otherwise.
  std::vector<std::uint64_t> cluster_work();
  // The device memory the memory plan gave this machine (device/memory_plan.h),
  // in all and by buffer name (the frame's buffer table, summed by name).
  std::uint64_t planned_device_bytes() const;
  std::map<std::string, std::uint64_t> planned_buffers() const;
  // Of the scene's uploads, the bytes the device reads in host memory in
  // place (CL_MEM_USE_HOST_PTR), not copied.
  std::uint64_t in_place_bytes() const;

 private:
  struct Machine;
  std::unique_ptr<Machine> m_;
};

}  // namespace opsila
