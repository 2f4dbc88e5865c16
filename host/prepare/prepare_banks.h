// The prepare step's first part: the banks a render's settings ask for.
// With --balance measured the pilot frames (dist/pilot.h) run here,
// before the frame's renderer exists; the renderer then takes the banks.
#pragma once

#include "partition/banks.h"
#include "device/cl_runtime.h"
#include "scene/render_types.h"
#include "scene/image.h"

namespace opsila {

// The banks of this rank's PE group (every PE's with one rank), partitioned
// as settings.balance says: facets; work, with settings.ray_sample or the
// sample settings.sampler traces here (balance_sample, by the ranks
// together for a scene read in shares); or measured, from pilot frames run
// on `runtime` first. Throws InputError for
// a machine the kernels cannot run (check_machine_request).
PreparedBanks prepare_banks(const Scene& scene, const RenderSettings& settings, ClRuntime& runtime);
// The same, consuming: a scene read in shares gives up its facets (triangles
// and vertex attributes) to the partition once they are sent
// (docs/DISTRIBUTED.md), so a rank never holds them twice; a whole scene
// gives them up once the banks hold copies (Facets::released), or keeps
// them for a caller that still reads them (the bench's baselines).
enum class Facets { released, kept };
PreparedBanks prepare_banks_consuming(Scene& scene, const RenderSettings& settings, ClRuntime& runtime,
                                      Facets after = Facets::released);

// One frame with banks and a Renderer prepared for it; the scene is kept.
RenderResult render(const Scene& scene, const RenderSettings& settings, ClRuntime& runtime);
// The same, consuming a scene read in shares (prepare_banks_consuming): the
// command line's path.
RenderResult render_consuming(Scene& scene, const RenderSettings& settings, ClRuntime& runtime);

}  // namespace opsila
