#include "prepare/view.h"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <set>

#include "core/util.h"
#include "mpi/ranks.h"
#include "opsila_shared.h"
#include "prepare/map_checks.h"
#include "reference/reference.h"
#include "scene/camera.h"

namespace opsila {

namespace {

// The camera's basis exists (check_camera). A framed eye stands farther
// the narrower the view: where the scene's own framing fails only for its
// narrow field of view (framed at 90 degrees it would pass), that is named.
void check_view_camera(const Scene& scene, const ViewOptions& o, const std::string& file, bool framed) {
  // Each part named where it came from: a flag, the file's key, or the
  // framing (a scene without a camera) and the default up.
  const std::string camera = !scene.camera_where.empty() ? scene.camera_where
                             : framed                    ? file + ": the camera framing the scene (it has none)"
                                                         : file + ": camera";
  const bool view_flags = o.eye || o.look_at;
  const std::string eye_source = view_flags ? "--eye/--look-at" : camera;
  const std::string up_source = o.up                             ? "--up"
                                : !scene.camera_up_where.empty() ? scene.camera_up_where
                                                                 : camera + ": its default up";
  const std::string parallel = !o.up && view_flags ? "--eye/--look-at: the camera up" : up_source;
  try {
    check_camera(scene.camera, eye_source, up_source, parallel);
  } catch (const InputError&) {
    if (!framed || o.eye || o.look_at || o.up) throw;
    Vec3 lo, hi;
    scene.bounds(lo, hi);
    check_camera(frame_bounds(lo, hi, 90.0f, static_cast<float>(scene.width) / scene.height), eye_source, up_source,
                 parallel);
    char fov[32];
    std::snprintf(fov, sizeof fov, "%g", double(scene.camera.fov_deg));
    throw InputError((o.fov ? "--fov " : file + ": field of view ") + std::string(fov) +
                     ": too narrow to frame a scene without a camera (its eye would stand at " +
                     format_vec(scene.camera.eye) + ", beyond float's reach); give a wider field of view or a camera");
  }
}

}  // namespace

RenderSettings render_settings(const ViewOptions& o) {
  RenderSettings settings;
  settings.num_pes = o.pes.value_or(settings.num_pes);
  settings.bank_capacity = o.bank_capacity;
  settings.work_groups_per_pe = o.work_groups_per_pe;
  if (o.routing) settings.routing = *o.routing;
  settings.balance = o.balance.value_or(kDefaultBalance);
  settings.sampler = [](const Scene& scene, const SampleJoin* join) {
    return ReferenceTracer(scene).sample_rays(kBalanceSampleRays, join);
  };
  return settings;
}

void apply_view_options(Scene& scene, const ViewOptions& o) {
  if (o.width) scene.width = *o.width;
  if (o.height) scene.height = *o.height;
  if (o.depth) scene.max_depth = *o.depth;
  if (o.spp) scene.spp = *o.spp;
  if (o.ambient) scene.ambient = *o.ambient;
  if (o.background) scene.background = *o.background;
  if (o.fov) scene.camera.fov_deg = *o.fov;
  if (o.smooth) scene.smooth = true;

  const std::string& file = o.scene_path.empty() ? std::string("scene") : o.scene_path;
  // Checks the scene file's own values too, so the renderer never sees bad ones.
  if (scene.width <= 0 || scene.height <= 0 || scene.width > kMaxImageSide || scene.height > kMaxImageSide ||
      static_cast<long long>(scene.width) * scene.height > kMaxImagePixels)
    throw InputError((o.width ? "--size: " : file + ": image: ") + std::to_string(scene.width) + "x" +
                     std::to_string(scene.height) + " is outside 1.." + std::to_string(kMaxImageSide) +
                     " per side and 2^26 pixels");
  if (scene.max_depth < 1 || scene.max_depth > OPSILA_MAX_DEPTH)
    throw InputError(file + ": depth " + std::to_string(scene.max_depth) + " is outside 1.." + std::to_string(OPSILA_MAX_DEPTH));
  if (const std::string problem = spp_problem(scene.spp); !problem.empty())
    throw InputError(file + ": spp " + std::to_string(scene.spp) + ": " + problem);
  if (!(scene.camera.fov_deg > 0 && scene.camera.fov_deg < 180))
    throw InputError(file + ": field of view " + std::to_string(scene.camera.fov_deg) +
                     " is not strictly between 0 and 180 degrees");

  // A scene without a camera frames its bounding box; flags given still win.
  const bool framed = !scene.has_camera && scene.has_facets();
  if (framed) {
    Vec3 lo, hi;
    scene.bounds(lo, hi);
    const float fov = scene.camera.fov_deg;
    scene.camera = frame_bounds(lo, hi, fov, static_cast<float>(scene.width) / scene.height);
    scene.camera.fov_deg = fov;
  }
  if (o.eye) scene.camera.eye = *o.eye;
  if (o.look_at) scene.camera.look_at = *o.look_at;
  if (o.up) scene.camera.up = *o.up;

  check_view_camera(scene, o, file, framed);

  if (!o.lights.empty()) {
    scene.lights = o.lights;
    scene.has_lights = true;
  } else if (!scene.has_lights && scene.lights.empty()) {
    // CONTRACT: with no light given anywhere, one white light sits at the eye.
    LightDesc light;
    light.position = scene.camera.eye;
    light.intensity = Vec3{1, 1, 1};
    scene.lights.push_back(light);
  }
}


void check_scene_file(const std::string& path) {
  struct stat st;
  if (::stat(path.c_str(), &st) != 0) throw InputError(path + ": cannot open scene (" + std::strerror(errno) + ")");
  if (S_ISDIR(st.st_mode)) throw InputError(path + ": is a folder, not a scene file");
  if (!S_ISREG(st.st_mode)) throw InputError(path + ": not a regular file");
  if (::access(path.c_str(), R_OK) != 0)
    throw InputError(path + ": cannot read scene (" + std::strerror(errno) + ")");
}

// Each distinct warning once; a flood of them (a hostile file) is cut short.
void print_warnings(const std::vector<std::string>& warnings, bool quiet) {
  if (quiet) return;
  constexpr std::size_t kMaxShown = 100;
  std::set<std::string> seen;
  for (const std::string& w : warnings)
    if (seen.size() < kMaxShown && seen.insert(w).second)
      std::fprintf(stderr, "opsila: warning: %s\n", shown_text(w).c_str());
  if (warnings.size() > seen.size() && seen.size() == kMaxShown)
    std::fprintf(stderr, "opsila: warning: ... and more (only the first %zu are shown)\n", kMaxShown);
}

Scene load_scene_or_explain(const std::string& path, bool quiet, Ranks& ranks, const SceneShare& share,
                            const TriangleLimit& limit) {
  Scene scene;
  // Read in shares: texture images are checked once over the ranks, then
  // decoded only where used (settle_maps, docs/DISTRIBUTED.md).
  const bool shares = share.ranks > 1;
  SceneShare request = share;
  if (shares) request.map_images = MapImages::later;
  try {
    scene = load_scene(path, request, limit);
  } catch (InputError& e) {
    print_warnings(e.warnings, quiet);  // a misspelt key explains many errors
    throw;
  }
  if (shares) settle_maps(scene, ranks);
  print_warnings(scene.warnings, quiet);
  return scene;
}

}  // namespace opsila
