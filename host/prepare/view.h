// The request's view: what to render, with which camera, lights and
// machine, as values (app/args.cpp parses them from the view flags), and how
// they are applied to a scene read from its file.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "formats/json/scene_file.h"
#include "mpi/ranks.h"
#include "scene/ray_sample.h"
#include "scene/render_types.h"
#include "scene/scene.h"

namespace opsila {

// The view group, shared by render and bench. Unset optionals leave the
// scene file's value alone.
struct ViewOptions {
  std::string scene_path;
  std::string device_spec;  // --device
  std::optional<int> width, height, depth, pes, spp;
  std::optional<Vec3> eye, look_at, up, ambient, background;
  std::optional<float> fov;
  std::vector<LightDesc> lights;  // --light, in order; replace the scene's lights
  int bank_capacity = 0;          // 0 = automatic
  int work_groups_per_pe = 0;     // 0 = as many as each bank's descriptors need
  std::optional<int> routing;     // --routing: OPSILA_ROUTING_*
  std::optional<Balance> balance;  // --balance (default kDefaultBalance)
  bool smooth = false;            // --smooth: CONTRACT's smooth shading (else the scene's "smooth")
  std::uint64_t host_memory = 0;  // --host-memory in bytes (0: what the host has available)
};

// --balance when the flag is absent: render keeps equal banks (no pilot
// frames to pay for before the frame); the bench measures the scheme with
// its PEs balanced by measured work (docs/BENCHMARKS.md).
constexpr Balance kDefaultBalance = Balance::facets;
constexpr Balance kBenchBalance = Balance::measured;

// Applies the flags to a loaded scene (flags win), frames a scene that has no
// camera, adds the default light at the eye when there is no light at all,
// then checks the final camera, size and depth. Throws InputError.
void apply_view_options(Scene& scene, const ViewOptions& options);

// The machine the view flags ask for (--pes, --bank-capacity,
// --work-groups-per-pe, --routing, --balance; the ray sample of --balance
// work is traced when the banks are prepared, by the reference tracer it
// hands down as settings.sampler).
RenderSettings render_settings(const ViewOptions& options);

// Checks that PATH is a readable regular file before any work is done.
void check_scene_file(const std::string& path);
// Prints each distinct warning once ("opsila: warning: ..."), at most 100.
void print_warnings(const std::vector<std::string>& warnings, bool quiet);
// load_scene, with its warnings printed, also those found before an error.
Scene load_scene_or_explain(const std::string& path, bool quiet, Ranks& ranks, const SceneShare& share,
                            const TriangleLimit& limit);

}  // namespace opsila
