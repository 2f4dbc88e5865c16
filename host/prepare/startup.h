// The start-up that `opsila render` and `opsila bench` share, between the
// outputs they declare and the machine they run: each rank's device line,
// and the scene read, checked against the outputs, with the view flags
// applied.
#pragma once

#include <functional>
#include <string>

#include "prepare/view.h"
#include "formats/image/output_files.h"
#include "scene/scene.h"
#include "mpi/ranks.h"

namespace opsila {

// "DEVICE", or under mpirun "rank R of N (HOST), PEs A..B: DEVICE" for this
// rank's group of num_pes PEs.
std::string device_text(Ranks& ranks, int num_pes, const std::string& description);

// Under mpirun each rank reads only its share of the scene and the ranks
// partition it together, with any --balance: the pilots of measured and the
// ray sample of work included (docs/DISTRIBUTED.md). One process: the
// scene is whole.
SceneShare scene_share_for(Ranks& ranks);

// Reads the scene (this rank's share when `share` asks), with the
// preparation's progress unless quiet, refuses it as an output, applies the
// view flags, and passes a note on a large frame to `note` (not when quiet).
Scene load_view_scene(const std::string& path, const ViewOptions& view, bool quiet, OutputFiles& outputs,
                      const std::function<void(const std::string&)>& note, const SceneShare& share = SceneShare{});

}  // namespace opsila
