// The JSON scene format (scenes/FORMAT.md). nlohmann::json checks the syntax;
// a second, light pass over the (then known to be valid) text records the
// line of every key path (JsonLines), so that semantic errors can name file,
// line and key. Objects are read in two passes: every object is checked and
// its triangles counted first, and only when the whole scene fits the limits
// is any geometry built.
#include "formats/json/scene_file.h"

#include "formats/json/scene_reader.h"
#include "formats/assimp/model_window.h"
#include "formats/image/texture_file.h"
#include "core/env_hooks.h"
#include "core/input_file.h"
#include "core/stage_clock.h"

#include <chrono>
#include <functional>
#include <cstdlib>

namespace opsila {

namespace fs = std::filesystem;

namespace scene_json {

Scene SceneReader::run() {
  try {
    return read();
  } catch (InputError& e) {
    // Warnings found before the error still reach the user (a misspelt
    // key explains a later "no facets"), those of maps listed for later
    // with them (their images checked here: the ranks end without
    // checking them together).
    settle_map_warnings(scene_);
    e.warnings.insert(e.warnings.begin(), scene_.warnings.begin(), scene_.warnings.end());
    throw;
  }
}

Scene SceneReader::read() {
  check_json_shape(text_, name_, kMaxNesting, kMaxKeys);
  const Json root = parse();
  lines_ = std::make_unique<JsonLines>(text_, name_, scene_.warnings);
  if (!root.is_object()) fail("", std::string("the scene must be a JSON object, not ") + kind(root));
  check_keys(root, "", {"description", "camera", "image", "depth", "spp", "ambient", "background",
                        "lights", "materials", "objects", "smooth"});
  if (const Json* d = find(root, "description"); d && !d->is_string())
    fail("description", std::string("expected a string, not ") + kind(*d));

  scene_.materials.push_back(MaterialDesc::default_material());
  if (const Json* m = find(root, "materials")) materials(*m, "materials");
  if (const Json* im = find(root, "image")) image(*im, "image");
  if (const Json* d = find(root, "depth"))
    scene_.max_depth = integer(*d, "depth", 1, OPSILA_MAX_DEPTH);
  if (const Json* n = find(root, "spp")) {
    scene_.spp = integer(*n, "spp", 1, kMaxSpp);
    if (const std::string problem = spp_problem(scene_.spp); !problem.empty()) fail("spp", problem);
  }
  if (const Json* sm = find(root, "smooth")) {
    if (!sm->is_boolean()) fail("smooth", std::string("expected true or false, not ") + kind(*sm));
    scene_.smooth = sm->get<bool>();
  }
  if (const Json* a = find(root, "ambient")) scene_.ambient = colour(*a, "ambient");
  if (const Json* b = find(root, "background")) scene_.background = colour(*b, "background");
  if (const Json* l = find(root, "lights")) lights(*l, "lights");
  if (const Json* o = find(root, "objects")) objects(*o, "objects");
  // Every object is checked and the total counted: only now is geometry built.
  if (share_.ranks == 1) reserve_more(scene_.triangles, planned_triangles_);  // a share grows as it is dealt
  for (const auto& build : builds_) build();

  scene_.num_objects = next_object_;
  scene_.num_facets = next_facet_;
  if (share_.ranks > 1) settle_share();
  if (scene_.total_triangles() == 0) fail("objects", "no facets: the scene has no visible objects");
  Vec3 lo, hi;
  scene_.bounds(lo, hi);  // one scan of the facets for the check and the framing
  check_scene_extent(scene_.total_triangles(), lo, hi, name_);
  if (const Json* c = find(root, "camera"))
    camera(*c, "camera");  // the whole camera: nothing of the framing is kept
  else
    scene_.camera = frame_bounds(lo, hi, 45.0f, float(scene_.width) / float(scene_.height));
  return std::move(scene_);
}

Json SceneReader::parse() const {
  Json root;
  DomBuilder builder(root, *this);
  if (!Json::sax_parse(text_, &builder)) syntax_error(text_.size(), "syntax error", "");
  return root;
}

[[noreturn]] void SceneReader::syntax_error(std::size_t byte, const std::string& what,
                                            const std::string& token) const {
  const std::size_t p = std::min(byte > 0 ? byte - 1 : 0, text_.size());
  int line = 1;
  std::size_t line_start = 0;
  for (std::size_t k = 0; k < p; ++k) {
    if (text_[k] == '\n') {
      ++line;
      line_start = k + 1;
    }
  }
  // The library's text is "[json.exception...] parse error at line L,
  // column C: DETAIL; last read: 'TOKEN'": keep DETAIL, quote a prefix of
  // TOKEN only.
  std::string detail = what;
  if (const std::size_t col = detail.find("column "); col != std::string::npos) {
    const std::size_t colon = detail.find(": ", col);
    if (colon != std::string::npos) detail = detail.substr(colon + 2);
  } else if (const std::size_t close = detail.find("] "); detail.rfind("[json.", 0) == 0 &&
                                                           close != std::string::npos) {
    detail = detail.substr(close + 2);
  }
  if (const std::size_t last = detail.find("; last read: "); last != std::string::npos)
    detail = detail.substr(0, last) + "; last read: '" + quoted_prefix(token) + "'";
  if (const std::size_t parsing = detail.find("number overflow parsing '");
      parsing != std::string::npos)
    detail = "number " + quoted_prefix(token) + " is out of range";
  throw InputError(name_ + ":" + std::to_string(line) + ":" +
                   std::to_string(p - line_start + 1) + ": " + quoted_line(detail));
}

// A library message without line breaks and of bounded length.
std::string SceneReader::quoted_line(std::string text) {
  std::replace(text.begin(), text.end(), '\n', ' ');
  if (text.size() > 200) text = text.substr(0, 200) + "...";
  return text;
}

std::string SceneReader::where(const std::string& path) const {
  const int line = lines_ ? lines_->line_of(path) : 1;
  return name_ + ":" + std::to_string(line) + ": " + (path.empty() ? "" : shown_path(path) + ": ");
}

[[noreturn]] void SceneReader::fail(const std::string& path, const std::string& what) const {
  throw InputError(where(path) + what);
}

void SceneReader::warn(const std::string& path, const std::string& what) {
  scene_.warnings.push_back(where(path) + what);
}

// ------------------------------------------------------------ access ----
const Json* SceneReader::find(const Json& obj, const char* key) {
  auto it = obj.find(key);
  return it == obj.end() ? nullptr : &*it;
}

const Json& SceneReader::require(const Json& obj, const std::string& path, const char* key) const {
  const Json* v = find(obj, key);
  if (!v) fail(path, std::string("missing key '") + key + "'");
  return *v;
}

void SceneReader::expect_object(const Json& v, const std::string& path) const {
  if (!v.is_object()) fail(path, std::string("expected an object, not ") + kind(v));
}

void SceneReader::expect_array(const Json& v, const std::string& path) const {
  if (!v.is_array()) fail(path, std::string("expected an array, not ") + kind(v));
}

// Unknown keys are warnings: typo protection without breaking old files.
void SceneReader::check_keys(const Json& obj, const std::string& path,
                             std::initializer_list<const char*> allowed) {
  for (auto it = obj.begin(); it != obj.end(); ++it) {
    if (it.key() == "comment") continue;
    bool known = false;
    for (const char* a : allowed) known = known || it.key() == a;
    if (!known)
      warn(join_key(path, it.key()), "unknown key '" + quoted_prefix(it.key()) + "' (ignored)");
  }
}

double SceneReader::number(const Json& v, const std::string& path) const {
  if (!v.is_number()) fail(path, std::string("expected a number, not ") + kind(v));
  const double d = v.get<double>();
  if (!std::isfinite(d) || !std::isfinite(static_cast<float>(d)))
    fail(path, "number " + num_text(d) + " is out of range");
  return d;
}

float SceneReader::real(const Json& v, const std::string& path) const {
  return static_cast<float>(number(v, path));
}

float SceneReader::positive(const Json& v, const std::string& path) const {
  const float x = real(v, path);
  if (!(x > 0)) fail(path, "must be positive, not " + num_text(x));
  return x;
}

int SceneReader::integer(const Json& v, const std::string& path, long long lo, long long hi) const {
  const double d = number(v, path);
  if (std::floor(d) != d) fail(path, "expected an integer, not " + num_text(d));
  if (d < double(lo) || d > double(hi))
    fail(path, "must be in " + std::to_string(lo) + ".." + std::to_string(hi) + ", not " +
                   num_text(d));
  return static_cast<int>(d);
}

Vec3 SceneReader::vec3(const Json& v, const std::string& path) const {
  if (!v.is_array() || v.size() != 3)
    fail(path, std::string("expected [x, y, z], not ") +
                   (v.is_array() ? "an array of " + std::to_string(v.size())
                                 : std::string(kind(v))));
  return {real(v[0], join_index(path, 0)), real(v[1], join_index(path, 1)),
          real(v[2], join_index(path, 2))};
}

// A number (grey) or [r, g, b]; never negative.
Vec3 SceneReader::colour(const Json& v, const std::string& path) const {
  Vec3 c;
  if (v.is_number()) {
    const float g = real(v, path);
    c = {g, g, g};
  } else if (v.is_array() && v.size() == 3) {
    c = vec3(v, path);
  } else {
    fail(path, std::string("expected a number or [r, g, b], not ") + kind(v));
  }
  for (float x : c)
    if (const std::string why = material_value_problem(path, x); !why.empty())
      fail(path, "colour components " + why);
  return c;
}

// A positive number (both sizes alike) or [a, b].
void SceneReader::size2(const Json& v, const std::string& path, float& a, float& b) const {
  if (v.is_number()) {
    a = b = positive(v, path);
  } else if (v.is_array() && v.size() == 2) {
    a = positive(v[0], join_index(path, 0));
    b = positive(v[1], join_index(path, 1));
  } else {
    fail(path, std::string("expected a positive number or [x, z], not ") + kind(v));
  }
}

void SceneReader::count2(const Json& v, const std::string& path, int hi, int& a, int& b) const {
  if (v.is_number()) {
    a = b = integer(v, path, 1, hi);
  } else if (v.is_array() && v.size() == 2) {
    a = integer(v[0], join_index(path, 0), 1, hi);
    b = integer(v[1], join_index(path, 1), 1, hi);
  } else {
    fail(path, std::string("expected an integer or [nx, nz], not ") + kind(v));
  }
}

std::string SceneReader::string(const Json& v, const std::string& path) const {
  if (!v.is_string()) fail(path, std::string("expected a string, not ") + kind(v));
  return v.get<std::string>();
}

}  // namespace scene_json

using scene_json::Json;
using scene_json::SceneReader;

Scene load_scene_from_string(const std::string& text, const std::string& name,
                             const std::string& base_dir, std::size_t max_triangles,
                             const SceneShare& share) {
  try {
    if (text.size() > kMaxSceneFileBytes)
      throw InputError(name + ": scene file too large (" + std::to_string(text.size()) +
                       " bytes; the limit is " + std::to_string(kMaxSceneFileBytes) + ")");
    int line = 1;
    check_json_bytes(text.data(), text.size(), 0, line, name);
    return SceneReader(text, name, base_dir, max_triangles, share).run();
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

std::size_t rank_triangle_limit() {
  const std::string expected = "a number of triangles, 1.." + std::to_string(kMaxTriangles);
  return env_hook_number(EnvHook::rank_triangle_limit, 1, kMaxTriangles, expected.c_str()).value_or(kMaxTriangles);
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

}  // namespace

Scene load_scene(const std::string& path, const SceneShare& share) {
  const auto start = std::chrono::steady_clock::now();
  const std::string ext = lower(fs::path(path).extension().string());
  if (windowed(path, ext, share)) {
    const std::size_t limit = rank_triangle_limit() * std::size_t(share.ranks);
    Scene scene = load_window_share(
        path, [&](const ModelWindow& w, std::uint64_t& fans) {
          return ext == ".obj" ? load_obj_window(path, limit, w, fans) : load_model_window(path, limit, w, fans);
        },
        share);
    scene.share.read_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return scene;
  }
  if (ext == ".obj") return load_obj(path);
  // Parsing, and the shapes and generators it builds (a read is its own stage).
  StageClock clock(PrepareStage::parse);
  if (ext != ".json" && is_imported_model(path)) {
    Scene scene = load_model(path, share.map_images);
    scene.input_files.insert(scene.input_files.begin(), path);
    return scene;
  }
  int line = 1;
  const std::string text = read_input_file(
      path, kMaxSceneFileBytes, [&](const char* data, std::size_t n, std::size_t offset) {
        check_json_bytes(data, n, offset, line, path);
      });
  std::string dir = fs::path(path).parent_path().string();
  if (dir.empty()) dir = ".";
  Scene scene = load_scene_from_string(text, path, dir, rank_triangle_limit(), share);
  scene.input_files.insert(scene.input_files.begin(), path);
  scene.share.read_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return scene;
}

}  // namespace opsila
