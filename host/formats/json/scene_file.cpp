// The JSON scene format (scenes/FORMAT.md), read by parts: the document and
// its values (scene_values.h), the sections (scene_sections.h) and the
// objects (scene_objects.h: shapes, generators, included models, and a
// rank's share of them). Objects are read in two passes: every object is
// checked and its triangles counted first, and only when the whole scene
// fits the limits is any geometry built.
#include "formats/json/scene_file.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <functional>

#include "core/env_hooks.h"
#include "core/input_file.h"
#include "core/stage_clock.h"
#include "core/util.h"
#include "formats/assimp/model_import.h"
#include "formats/assimp/model_window.h"
#include "formats/common/json_text.h"
#include "formats/image/texture_file.h"
#include "formats/json/scene_objects.h"
#include "formats/json/scene_sections.h"
#include "formats/json/scene_values.h"
#include "opsila_shared.h"

namespace opsila {

namespace fs = std::filesystem;

namespace scene_json {

namespace {

// The document, section after section; the objects are all checked and
// counted before any is built.
void read_document(Scene& scene, const std::string& text, const std::string& name, const std::string& base_dir,
                   const TriangleLimit& limit, const SceneShare& share) {
  const Json root = parse_scene_text(text, name);
  SceneValues values(text, name, scene.warnings);
  values.refuse_nul(root, "");
  if (!root.is_object()) values.fail("", std::string("the scene must be a JSON object, not ") + kind(root));
  values.check_keys(root, "", {"description", "camera", "image", "depth", "spp", "ambient", "background",
                               "lights", "materials", "objects", "smooth"});
  const auto find = [&](const char* key) { return SceneValues::find(root, key); };
  if (const Json* d = find("description"); d && !d->is_string())
    values.fail("description", std::string("expected a string, not ") + kind(*d));

  SceneSections sections(values, scene);
  scene.materials.push_back(MaterialDesc::default_material());
  if (const Json* m = find("materials")) sections.materials(*m, "materials");
  if (const Json* im = find("image")) sections.image(*im, "image");
  if (const Json* d = find("depth")) scene.max_depth = values.integer(*d, "depth", 1, OPSILA_MAX_DEPTH);
  if (const Json* n = find("spp")) {
    scene.spp = values.integer(*n, "spp", 1, kMaxSpp);
    if (const std::string problem = spp_problem(scene.spp); !problem.empty()) values.fail("spp", problem);
  }
  if (const Json* sm = find("smooth")) {
    if (!sm->is_boolean()) values.fail("smooth", std::string("expected true or false, not ") + kind(*sm));
    scene.smooth = sm->get<bool>();
  }
  if (const Json* a = find("ambient")) scene.ambient = values.colour(*a, "ambient");
  if (const Json* b = find("background")) scene.background = values.colour(*b, "background");
  if (const Json* l = find("lights")) sections.lights(*l, "lights");
  ObjectReader objects(values, sections, scene, base_dir, limit, share);
  if (const Json* o = find("objects")) objects.read(*o, "objects");
  // Every object is checked and the total counted: only now is geometry built.
  objects.build();

  if (!scene.has_facets()) values.fail("objects", "no facets: the scene has no visible objects");
  Vec3 lo, hi;
  scene.bounds(lo, hi);  // one scan of the facets for the check and the framing
  check_scene_extent(scene.total_triangles() + scene.instances.size(), lo, hi, name);  // an instance has facets
  if (const Json* c = find("camera"))
    sections.camera(*c, "camera");  // the whole camera: nothing of the framing is kept
  else
    scene.camera = frame_bounds(lo, hi, 45.0f, float(scene.width) / float(scene.height));
}

// share.ranks > 1: this rank's share (scene_share.h); the limit is then
// one rank's, and the scene may have ranks times it.
Scene read_scene(const std::string& text, const std::string& name, const std::string& base_dir,
                 const TriangleLimit& limit, const SceneShare& share) {
  Scene scene;
  try {
    read_document(scene, text, name, base_dir, limit, share);
  } catch (InputError& e) {
    // Warnings found before the error still reach the user (a misspelt
    // key explains a later "no facets"), those of maps listed for later
    // with them (their images checked here: the ranks end without
    // checking them together).
    settle_map_warnings(scene);
    e.warnings.insert(e.warnings.begin(), scene.warnings.begin(), scene.warnings.end());
    throw;
  }
  return scene;
}

}  // namespace

}  // namespace scene_json

using scene_json::Json;

Scene load_scene_from_string(const std::string& text, const std::string& name,
                             const std::string& base_dir, const TriangleLimit& limit,
                             const SceneShare& share) {
  try {
    if (text.size() > kMaxSceneFileBytes)
      throw InputError(name + ": scene file too large (" + std::to_string(text.size()) +
                       " bytes; the limit is " + std::to_string(kMaxSceneFileBytes) + ")");
    int line = 1;
    check_json_bytes(text.data(), text.size(), 0, line, name);
    return scene_json::read_scene(lone_cr_as_lf(text), name, base_dir, limit, share);
  } catch (const Json::exception&) {
    // Never the library's text: the reader checks every value's type first,
    // so this is a reader bug, reported without a misleading detail.
    throw InputError(name + ":1: could not read the scene (unexpected value)");
  } catch (const std::bad_alloc&) {
    throw InputError(name + ": out of memory while loading the scene");
  } catch (const std::length_error&) {
    throw InputError(name + ": scene too large to load");
  }
}

TriangleLimit rank_triangle_limit(const TriangleLimit& limit) {
  const std::string expected = "a number of triangles, 1.." + std::to_string(kMaxTriangles);
  if (const auto n = env_hook_number(EnvHook::rank_triangle_limit, 1, kMaxTriangles, expected.c_str()))
    return limit.capped_for_tests(std::size_t(*n));
  return limit;
}

// A bare OBJ or PLY read by several ranks: streamed once for its counts,
// then again keeping this rank's window of its triangles (obj_stream.cpp,
// ply_window.cpp). Every rank sees every polygon, so the figures need no
// joining; `combine` still runs, the ranks' agreement that each has read
// its share.
namespace {

using WindowRead = std::function<Scene(const ModelWindow&, std::uint64_t& fans)>;

Scene load_window_share(const std::string& path, const WindowRead& read, const SceneShare& share) {
  const FileReadStamp stamp(path);
  ModelWindow w;
  w.rank = share.rank, w.ranks = share.ranks;
  w.load_maps = false;
  std::uint64_t fans = 0;
  const std::size_t all = read(w, fans).share.total_triangles;
  w.plan_all = w.plan_total = all;
  w.fans = fans;
  w.load_maps = true;
  w.map_images = share.map_images;
  Scene scene = read(w, fans);
  SceneShare figures = share;
  figures.total_triangles = scene.share.total_triangles;
  figures.lo = scene.share.lo;
  figures.hi = scene.share.hi;
  figures.spread = std::move(scene.share.spread);
  figures.reads.emplace_back(path, stamp.after(fans, all, std::uint64_t(scene.num_facets)));
  if (figures.combine) figures.combine(figures);
  scene.share = std::move(figures);
  return scene;
}

// The file as a stream in windows, when several ranks read it and the
// stream reads it as one process does (an OBJ, or a PLY or binary STL that
// model_stream_refusal accepts).
bool windowed(const std::string& path, const std::string& ext, const SceneShare& share) {
  return share.ranks > 1 && (ext == ".obj" || (is_streamed_model(path) && model_stream_refusal(path).empty()));
}

// The limit of a file that several ranks read as a stream in windows: all
// of theirs, under the ids ceiling.
std::size_t windowed_limit(const TriangleLimit& rank, const SceneShare& share) {
  return std::min(rank.triangles * std::size_t(share.ranks), kMaxTriangles);
}

// A file named neither .json nor a model format the importer reads is read
// as a scene, which is a JSON object: one that does not start as one (a
// VRML or JT model, say) is named as what it is not, not by the JSON
// reader's complaint about its first byte.
void check_scene_start(std::string_view head, const std::string& path, const std::string& ext) {
  std::size_t at = head.compare(0, 3, "\xEF\xBB\xBF") == 0 ? 3 : 0;
  while (at < head.size() && std::isspace(static_cast<unsigned char>(head[at]))) ++at;
  if (at < head.size() && head[at] == '{') return;
  throw InputError(path + ": not a JSON scene (it does not start with '{'), and " +
                   (ext.empty() ? std::string("without an extension it is no model") : "'" + ext + "' is no model format") +
                   " the importer reads (see scenes/FORMAT.md)");
}

Scene read_scene_file(const std::string& path, const SceneShare& share, const TriangleLimit& rank) {
  const auto start = std::chrono::steady_clock::now();
  const std::string ext = lower(fs::path(path).extension().string());
  if (windowed(path, ext, share)) {
    const std::size_t limit = windowed_limit(rank, share);
    Scene scene = load_window_share(
        path, [&](const ModelWindow& w, std::uint64_t& fans) {
          return ext == ".obj" ? load_obj_window(path, limit, w, fans) : load_model_window(path, limit, w, fans);
        },
        share);
    scene.share.read_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return scene;
  }
  if (ext == ".obj") return load_obj(path, rank.triangles);
  // Parsing, and the shapes and generators it builds (a read is its own stage).
  StageClock clock(PrepareStage::parse);
  if (ext != ".json" && is_imported_model(path)) {
    Scene scene = load_model(path, share.map_images, rank.triangles);
    scene.input_files.insert(scene.input_files.begin(), path);
    return scene;
  }
  int line = 1;
  const std::string text = read_input_file(
      path, kMaxSceneFileBytes, [&](const char* data, std::size_t n, std::size_t offset) {
        if (offset == 0 && ext != ".json") check_scene_start(std::string_view(data, n), path, ext);
        check_json_bytes(data, n, offset, line, path);
      });
  std::string dir = fs::path(path).parent_path().string();
  if (dir.empty()) dir = ".";
  Scene scene = load_scene_from_string(text, path, dir, rank, share);
  scene.input_files.insert(scene.input_files.begin(), path);
  scene.share.read_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return scene;
}

}  // namespace

Scene load_scene(const std::string& path, const SceneShare& share, const TriangleLimit& limit) {
  const TriangleLimit rank = rank_triangle_limit(limit);
  try {
    return read_scene_file(path, share, rank);
  } catch (TooManyTriangles& e) {
    // A reader that counts as it streams knows only that it passed its
    // limit; what the limit comes from is said here, once.
    const bool several = windowed(path, lower(fs::path(path).extension().string()), share);
    InputError refusal(e.what() + rank.why_not(several ? windowed_limit(rank, share) : rank.triangles,
                                               several ? share.ranks : 1, true));
    refusal.warnings = std::move(e.warnings);
    throw refusal;
  }
}

}  // namespace opsila
