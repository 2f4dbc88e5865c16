// The JSON scene format (scenes/FORMAT.md). nlohmann::json checks the syntax;
// a second, light pass over the (then known to be valid) text records the
// line of every key path (JsonLines), so that semantic errors can name file,
// line and key. Objects are read in two passes: every object is checked and
// its triangles counted first, and only when the whole scene fits the limits
// is any geometry built.
#include "input/scene_file.h"

#include <algorithm>
#include <cctype>
#include <climits>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <initializer_list>
#include <functional>
#include <memory>
#include <new>
#include <optional>
#include <stdexcept>
#include <string_view>
#include <unordered_map>
#include <unordered_set>

#include <nlohmann/json.hpp>

#include "opsila_shared.h"
#include "core/util.h"
#include "input/json_text.h"
#include "input/model_import.h"
#include "input/primitives.h"

namespace opsila {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

namespace {

constexpr int kMaxNesting = 64;
constexpr int kMaxKeys = 1024;  // in one object: FORMAT.md "Limits"
constexpr int kMaxGeneratorItems = 1000000;  // FORMAT.md "Limits"

std::string num_text(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

std::string join_key(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}

std::string join_index(const std::string& path, std::size_t i) {
  return path + "[" + std::to_string(i) + "]";
}

const char* kind(const Json& v) {
  switch (v.type()) {
    case Json::value_t::null: return "null";
    case Json::value_t::object: return "an object";
    case Json::value_t::array: return "an array";
    case Json::value_t::string: return "a string";
    case Json::value_t::boolean: return "true/false";
    case Json::value_t::discarded: return "nothing";
    default: return "a number";
  }
}

class SceneReader {
 public:
  SceneReader(const std::string& text, const std::string& name, const std::string& base_dir,
              std::size_t max_triangles)
      : text_(text), name_(name), base_dir_(base_dir), max_triangles_(max_triangles) {}

  Scene run() {
    try {
      return read();
    } catch (InputError& e) {
      // Warnings found before the error still reach the user (a misspelt
      // key explains a later "no facets").
      e.warnings.insert(e.warnings.begin(), scene_.warnings.begin(), scene_.warnings.end());
      throw;
    }
  }

 private:
  Scene read() {
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
    reserve_more(scene_.triangles, planned_triangles_);
    for (const auto& build : builds_) build();

    scene_.num_objects = next_object_;
    scene_.num_facets = next_facet_;
    if (scene_.triangles.empty()) fail("objects", "no facets: the scene has no visible objects");
    check_scene_extent(scene_, name_);
    Vec3 lo, hi;
    scene_.bounds(lo, hi);
    scene_.camera =
        frame_bounds(lo, hi, 45.0f, float(scene_.width) / float(scene_.height));
    if (const Json* c = find(root, "camera")) camera(*c, "camera");
    return std::move(scene_);
  }

  // ------------------------------------------------------------ errors ----
  // nlohmann's DOM builder, with every syntax or range error (number
  // overflow included) turned into FILE:LINE:COLUMN instead of the library's
  // own exception text.
  struct DomBuilder : nlohmann::detail::json_sax_dom_parser<Json> {
    DomBuilder(Json& root, const SceneReader& reader)
        : nlohmann::detail::json_sax_dom_parser<Json>(root, false), reader_(reader) {}
    bool parse_error(std::size_t byte, const std::string& token,
                     const nlohmann::detail::exception& e) {
      reader_.syntax_error(byte, e.what(), token);
    }
    const SceneReader& reader_;
  };

  Json parse() const {
    Json root;
    DomBuilder builder(root, *this);
    if (!Json::sax_parse(text_, &builder)) syntax_error(text_.size(), "syntax error", "");
    return root;
  }

  [[noreturn]] void syntax_error(std::size_t byte, const std::string& what,
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
  static std::string quoted_line(std::string text) {
    std::replace(text.begin(), text.end(), '\n', ' ');
    if (text.size() > 200) text = text.substr(0, 200) + "...";
    return text;
  }

  std::string where(const std::string& path) const {
    const int line = lines_ ? lines_->line_of(path) : 1;
    return name_ + ":" + std::to_string(line) + ": " + (path.empty() ? "" : shown_path(path) + ": ");
  }
  [[noreturn]] void fail(const std::string& path, const std::string& what) const {
    throw InputError(where(path) + what);
  }
  void warn(const std::string& path, const std::string& what) {
    scene_.warnings.push_back(where(path) + what);
  }

  // ------------------------------------------------------------ access ----
  static const Json* find(const Json& obj, const char* key) {
    auto it = obj.find(key);
    return it == obj.end() ? nullptr : &*it;
  }
  const Json& require(const Json& obj, const std::string& path, const char* key) const {
    const Json* v = find(obj, key);
    if (!v) fail(path, std::string("missing key '") + key + "'");
    return *v;
  }
  void expect_object(const Json& v, const std::string& path) const {
    if (!v.is_object()) fail(path, std::string("expected an object, not ") + kind(v));
  }
  void expect_array(const Json& v, const std::string& path) const {
    if (!v.is_array()) fail(path, std::string("expected an array, not ") + kind(v));
  }
  // Unknown keys are warnings: typo protection without breaking old files.
  void check_keys(const Json& obj, const std::string& path,
                  std::initializer_list<const char*> allowed) {
    for (auto it = obj.begin(); it != obj.end(); ++it) {
      if (it.key() == "comment") continue;
      bool known = false;
      for (const char* a : allowed) known = known || it.key() == a;
      if (!known)
        warn(join_key(path, it.key()), "unknown key '" + quoted_prefix(it.key()) + "' (ignored)");
    }
  }

  double number(const Json& v, const std::string& path) const {
    if (!v.is_number()) fail(path, std::string("expected a number, not ") + kind(v));
    const double d = v.get<double>();
    if (!std::isfinite(d) || !std::isfinite(static_cast<float>(d)))
      fail(path, "number " + num_text(d) + " is out of range");
    return d;
  }
  float real(const Json& v, const std::string& path) const {
    return static_cast<float>(number(v, path));
  }
  float positive(const Json& v, const std::string& path) const {
    const float x = real(v, path);
    if (!(x > 0)) fail(path, "must be positive, not " + num_text(x));
    return x;
  }
  int integer(const Json& v, const std::string& path, long long lo, long long hi) const {
    const double d = number(v, path);
    if (std::floor(d) != d) fail(path, "expected an integer, not " + num_text(d));
    if (d < double(lo) || d > double(hi))
      fail(path, "must be in " + std::to_string(lo) + ".." + std::to_string(hi) + ", not " +
                     num_text(d));
    return static_cast<int>(d);
  }
  Vec3 vec3(const Json& v, const std::string& path) const {
    if (!v.is_array() || v.size() != 3)
      fail(path, std::string("expected [x, y, z], not ") +
                     (v.is_array() ? "an array of " + std::to_string(v.size())
                                   : std::string(kind(v))));
    return {real(v[0], join_index(path, 0)), real(v[1], join_index(path, 1)),
            real(v[2], join_index(path, 2))};
  }
  // A number (grey) or [r, g, b]; never negative.
  Vec3 colour(const Json& v, const std::string& path) const {
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
  void size2(const Json& v, const std::string& path, float& a, float& b) const {
    if (v.is_number()) {
      a = b = positive(v, path);
    } else if (v.is_array() && v.size() == 2) {
      a = positive(v[0], join_index(path, 0));
      b = positive(v[1], join_index(path, 1));
    } else {
      fail(path, std::string("expected a positive number or [x, z], not ") + kind(v));
    }
  }
  void count2(const Json& v, const std::string& path, int hi, int& a, int& b) const {
    if (v.is_number()) {
      a = b = integer(v, path, 1, hi);
    } else if (v.is_array() && v.size() == 2) {
      a = integer(v[0], join_index(path, 0), 1, hi);
      b = integer(v[1], join_index(path, 1), 1, hi);
    } else {
      fail(path, std::string("expected an integer or [nx, nz], not ") + kind(v));
    }
  }
  std::string string(const Json& v, const std::string& path) const {
    if (!v.is_string()) fail(path, std::string("expected a string, not ") + kind(v));
    return v.get<std::string>();
  }

  // ----------------------------------------------------------- sections ---
  void image(const Json& v, const std::string& path) {
    expect_object(v, path);
    check_keys(v, path, {"width", "height", "size"});
    const int kMax = kMaxImageSide;
    if (const Json* s = find(v, "size")) {
      if (find(v, "width") || find(v, "height"))
        fail(join_key(path, "size"), "give either size or width/height, not both");
      if (!s->is_array() || s->size() != 2)
        fail(join_key(path, "size"), std::string("expected [width, height], not ") + kind(*s));
      scene_.width = integer((*s)[0], join_index(join_key(path, "size"), 0), 1, kMax);
      scene_.height = integer((*s)[1], join_index(join_key(path, "size"), 1), 1, kMax);
    } else {
      scene_.width = integer(require(v, path, "width"), join_key(path, "width"), 1, kMax);
      scene_.height = integer(require(v, path, "height"), join_key(path, "height"), 1, kMax);
    }
    if (static_cast<long long>(scene_.width) * scene_.height > kMaxImagePixels)
      fail(find(v, "size") ? join_key(path, "size") : path, std::to_string(scene_.width) + " x " + std::to_string(scene_.height) +
                     " pixels; at most " + std::to_string(kMaxImagePixels) + " (2^26) are allowed");
  }

  void camera(const Json& v, const std::string& path) {
    expect_object(v, path);
    check_keys(v, path, {"eye", "look_at", "up", "fov"});
    CameraDesc cam;
    cam.eye = vec3(require(v, path, "eye"), join_key(path, "eye"));
    cam.look_at = vec3(require(v, path, "look_at"), join_key(path, "look_at"));
    if (const Json* u = find(v, "up")) cam.up = vec3(*u, join_key(path, "up"));
    if (const Json* f = find(v, "fov")) {
      cam.fov_deg = real(*f, join_key(path, "fov"));
      if (!(cam.fov_deg > 0 && cam.fov_deg < 180))
        fail(join_key(path, "fov"), "must be between 0 and 180 degrees (exclusive), not " +
                                        num_text(cam.fov_deg));
    }
    double f[3], u[3];
    for (int a = 0; a < 3; ++a) {
      f[a] = double(cam.look_at[a]) - double(cam.eye[a]);
      u[a] = cam.up[a];
    }
    const double fl = std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
    const double ul = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    if (!(fl > 0)) fail(join_key(path, "look_at"), "is the same point as the eye");
    const double c[3] = {f[1] * u[2] - f[2] * u[1], f[2] * u[0] - f[0] * u[2],
                         f[0] * u[1] - f[1] * u[0]};
    const double cl = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    if (!(cl > 1e-6 * fl * ul) || !std::isfinite(cl))
      fail(join_key(path, "up"), "is zero or parallel to the viewing direction");
    scene_.camera = cam;
    scene_.has_camera = true;
  }

  void lights(const Json& v, const std::string& path) {
    expect_array(v, path);
    if (v.size() > OPSILA_MAX_LIGHTS)
      fail(path, std::to_string(v.size()) + " lights; at most " +
                     std::to_string(OPSILA_MAX_LIGHTS) + " are supported");
    for (std::size_t i = 0; i < v.size(); ++i) {
      const std::string p = join_index(path, i);
      expect_object(v[i], p);
      check_keys(v[i], p, {"position", "intensity"});
      LightDesc light;
      light.position = vec3(require(v[i], p, "position"), join_key(p, "position"));
      if (const Json* in = find(v[i], "intensity"))
        light.intensity = colour(*in, join_key(p, "intensity"));
      scene_.lights.push_back(light);
    }
    scene_.has_lights = true;
  }

  void materials(const Json& v, const std::string& path) {
    expect_object(v, path);
    for (auto it = v.begin(); it != v.end(); ++it) {
      const std::string p = join_key(path, it.key());
      if (it.key().empty()) fail(p, "a material needs a non-empty name");
      named_.emplace(it.key(), static_cast<int>(scene_.materials.size()));
      named_order_.push_back(it.key());
      scene_.materials.push_back(material(it.value(), p, it.key()));
    }
  }

  // SPEC terms, plus kr (-> Ks) and kt (-> Tf) with illum chosen to apply them.
  MaterialDesc material(const Json& v, const std::string& path, const std::string& name) {
    expect_object(v, path);
    check_keys(v, path, {"Ka", "Kd", "Ks", "Ns", "Ni", "Tf", "illum", "kr", "kt"});
    MaterialDesc m;  // SPEC defaults for keys left out
    m.name = name;
    const auto key = [&](const char* k) { return join_key(path, k); };
    if (const Json* x = find(v, "Ka")) m.ka = colour(*x, key("Ka"));
    if (const Json* x = find(v, "Kd")) m.kd = colour(*x, key("Kd"));
    if (const Json* x = find(v, "Ks")) m.ks = colour(*x, key("Ks"));
    if (const Json* x = find(v, "Tf")) m.tf = colour(*x, key("Tf"));
    if (const Json* x = find(v, "Ns")) {
      m.ns = real(*x, key("Ns"));
      if (const std::string why = material_value_problem("Ns", m.ns); !why.empty())
        fail(key("Ns"), why);
    }
    if (const Json* x = find(v, "Ni")) m.ni = positive(*x, key("Ni"));
    const Json* kr = find(v, "kr");
    const Json* kt = find(v, "kt");
    if (kr) {
      if (find(v, "Ks")) fail(key("kr"), "give either Ks or kr, not both (kr sets Ks)");
      m.ks = colour(*kr, key("kr"));
    }
    if (kt) {
      if (find(v, "Tf")) fail(key("kt"), "give either Tf or kt, not both (kt sets Tf)");
      m.tf = colour(*kt, key("kt"));
    }
    if (const Json* x = find(v, "illum")) {
      m.illum = integer(*x, key("illum"), 0, 10);
      if (kr && !illum_reflects(m.illum))
        fail(key("kr"), "has no effect with illum " + std::to_string(m.illum) +
                            " (reflection needs illum 3..7)");
      if (kt && !illum_transmits(m.illum))
        fail(key("kt"), "has no effect with illum " + std::to_string(m.illum) +
                            " (transmission needs illum 4, 6 or 7)");
    } else {
      m.illum = kt ? 6 : kr ? 3 : 0;
    }
    return m;
  }

  // A material name from "materials", or an inline material; none = default.
  int material_ref(const Json* v, const std::string& path) {
    if (!v) return 0;
    if (v->is_string()) {
      const std::string n = v->get<std::string>();
      auto it = named_.find(n);
      if (it == named_.end()) {
        // As in OBJ (FORMAT.md): a warning, and the default material.
        std::string known;
        for (const std::string& k : named_order_) {
          known += (known.empty() ? "" : ", ") + quoted_prefix(k);
          if (known.size() > 200) {
            known += ", ...";
            break;
          }
        }
        warn(path, "unknown material '" + quoted_prefix(n) + "'" +
                       (known.empty() ? " (the scene defines none)" : " (defined: " + known + ")") +
                       "; the default material is used");
        return 0;
      }
      return it->second;
    }
    if (v->is_object()) {
      scene_.materials.push_back(material(*v, path, path));
      return static_cast<int>(scene_.materials.size()) - 1;
    }
    fail(path, std::string("expected a material name or an inline material, not ") + kind(*v));
  }

  std::vector<int> material_list(const Json& v, const std::string& path) {
    expect_array(v, path);
    if (v.empty()) fail(path, "needs at least one material");
    std::vector<int> out;
    for (std::size_t i = 0; i < v.size(); ++i)
      out.push_back(material_ref(&v[i], join_index(path, i)));
    return out;
  }

  Transform transform(const Json& v, const std::string& path) {
    expect_object(v, path);
    check_keys(v, path, {"translate", "rotate", "scale"});
    Transform t;
    if (const Json* x = find(v, "translate")) t.translate = vec3(*x, join_key(path, "translate"));
    if (const Json* x = find(v, "rotate")) t.rotate_deg = vec3(*x, join_key(path, "rotate"));
    if (const Json* x = find(v, "scale")) {
      const std::string p = join_key(path, "scale");
      if (x->is_number()) {
        const float s = positive(*x, p);
        t.scale = {s, s, s};
      } else if (x->is_array() && x->size() == 3) {
        for (int a = 0; a < 3; ++a) t.scale[a] = positive((*x)[a], join_index(p, a));
      } else {
        fail(p, std::string("expected a positive number or [x, y, z], not ") + kind(*x));
      }
    }
    return t;
  }

  // ------------------------------------------------------------ objects ---
  // Counts an object's triangles (and facets, an upper bound for generated
  // shapes) against the scene's limits before anything is built.
  void budget(std::size_t triangles, std::size_t facets, std::size_t objects,
              const std::string& path) {
    if (triangles > max_triangles_ || planned_triangles_ > max_triangles_ - triangles)
      fail(path, "would make " + std::to_string(triangles) + " more triangles (" +
                     std::to_string(planned_triangles_) + " so far); a scene may have at most " +
                     std::to_string(max_triangles_) + " (scenes/FORMAT.md, Limits)");
    if (facets > std::size_t(INT_MAX) - planned_facets_)
      fail(path, "too many facets for 32-bit ids");
    if (objects > std::size_t(INT_MAX) - planned_objects_) fail(path, "too many objects");
    planned_triangles_ += triangles;
    planned_facets_ += facets;
    planned_objects_ += objects;
  }
  void budget(std::size_t triangles, const std::string& path) {
    budget(triangles, triangles, 1, path);
  }

  void objects(const Json& v, const std::string& path) {
    expect_array(v, path);
    for (std::size_t i = 0; i < v.size(); ++i) object(v[i], join_index(path, i));
  }

  // Checks one object and plans its construction; builds_ runs the plans in
  // order once the whole scene is known to fit.
  void object(const Json& v, const std::string& path) {
    expect_object(v, path);
    const std::string type = string(require(v, path, "type"), join_key(path, "type"));
    const auto key = [&](const char* k) { return join_key(path, k); };
    std::function<void(std::vector<Triangle>&)> make;

    if (type == "sphere") {
      check_keys(v, path, {"type", "name", "center", "radius", "subdivisions", "material",
                           "transform"});
      const Vec3 c = vec3(require(v, path, "center"), key("center"));
      const float r = positive(require(v, path, "radius"), key("radius"));
      int sub = 3;
      if (const Json* s = find(v, "subdivisions")) sub = integer(*s, key("subdivisions"), 0, 10);
      const int mat = material_ref(find(v, "material"), key("material"));
      budget(icosphere_triangles(sub), path);
      make = [this, c, r, sub, mat](std::vector<Triangle>& tris) {
        next_facet_ = add_icosphere(tris, c, r, sub, FacetTag{next_object_++, mat}, next_facet_);
      };
    } else if (type == "box") {
      check_keys(v, path, {"type", "name", "min", "max", "center", "size", "material",
                           "transform"});
      Vec3 lo, hi;
      box_extent(v, path, lo, hi);
      const int mat = material_ref(find(v, "material"), key("material"));
      budget(12, 6, 1, path);
      make = [this, lo, hi, mat](std::vector<Triangle>& tris) {
        next_facet_ = add_box(tris, lo, hi, FacetTag{next_object_++, mat}, next_facet_);
      };
    } else if (type == "plane" || type == "checkerboard") {
      const bool checker = type == "checkerboard";
      if (checker)
        check_keys(v, path, {"type", "name", "center", "size", "squares", "materials",
                             "transform"});
      else
        check_keys(v, path, {"type", "name", "center", "size", "material", "transform"});
      Vec3 c{0, 0, 0};
      if (const Json* x = find(v, "center")) c = vec3(*x, key("center"));
      float sx, sz;
      size2(require(v, path, "size"), key("size"), sx, sz);
      if (checker) {
        int nx = 8, nz = 8;
        if (const Json* s = find(v, "squares")) count2(*s, key("squares"), 100000, nx, nz);
        const std::vector<int> mats = material_list(require(v, path, "materials"), key("materials"));
        if (mats.size() != 2) fail(key("materials"), "expected exactly 2 materials");
        budget(std::size_t(2) * nx * nz, std::size_t(nx) * nz, 1, path);
        make = [this, c, sx, sz, nx, nz, mats](std::vector<Triangle>& tris) {
          next_facet_ = add_checkerboard(tris, c, sx, sz, nx, nz, next_object_++, mats[0], mats[1],
                                         next_facet_);
        };
      } else {
        const int mat = material_ref(find(v, "material"), key("material"));
        budget(2, 1, 1, path);
        make = [this, c, sx, sz, mat](std::vector<Triangle>& tris) {
          next_facet_ = add_plane(tris, c, sx, sz, FacetTag{next_object_++, mat}, next_facet_);
        };
      }
    } else if (type == "polygon") {
      check_keys(v, path, {"type", "name", "vertices", "material", "transform"});
      const Json& vs = require(v, path, "vertices");
      expect_array(vs, key("vertices"));
      if (vs.size() < 3) fail(key("vertices"), "a polygon needs at least 3 vertices");
      std::vector<Vec3> pts;
      for (std::size_t k = 0; k < vs.size(); ++k)
        pts.push_back(vec3(vs[k], join_index(key("vertices"), k)));
      const int mat = material_ref(find(v, "material"), key("material"));
      budget(pts.size() - 2, 1, 1, path);
      const std::string where_vertices = key("vertices");
      make = [this, pts, mat, where_vertices](std::vector<Triangle>& tris) {
        const std::size_t before = tris.size();
        next_facet_ = add_polygon(tris, pts, FacetTag{next_object_++, mat}, next_facet_);
        if (tris.size() == before) fail(where_vertices, "the polygon has zero area");
      };
    } else if (type == "terrain") {
      make = terrain(v, path);
    } else if (type == "scatter" || type == "grid") {
      make = generator(v, path, type == "grid");
    } else if (type == "obj" || type == "model") {
      make = include_obj(v, path, type == "model");
    } else {
      fail(key("type"), "unknown object type '" + quoted_prefix(type) +
                            "' (expected sphere, box, plane, checkerboard, polygon, terrain, "
                            "scatter, grid, obj or model)");
    }
    std::optional<Transform> placed;
    if (const Json* t = find(v, "transform")) placed = transform(*t, key("transform"));
    builds_.push_back([this, make, placed, path] {
      auto& tris = scene_.triangles;
      const std::size_t first = tris.size();
      const std::size_t first_attribute = scene_.attributes.size();
      make(tris);
      if (placed) {
        transform_triangles(tris, first, *placed);
        transform_normals(scene_.attributes, first_attribute, *placed);
      }
      settle(first, path);
    });
  }

  // After placement: zero-area triangles (possible after extreme scaling)
  // are dropped, facets whose normal overflows float are refused.
  void settle(std::size_t first, const std::string& path) {
    auto& tris = scene_.triangles;
    std::size_t keep = first, dropped = 0;
    for (std::size_t k = first; k < tris.size(); ++k) {
      const Triangle& t = tris[k];
      const float e1[3] = {t.v1[0] - t.v0[0], t.v1[1] - t.v0[1], t.v1[2] - t.v0[2]};
      const float e2[3] = {t.v2[0] - t.v0[0], t.v2[1] - t.v0[1], t.v2[2] - t.v0[2]};
      const float c[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                          e1[0] * e2[1] - e1[1] * e2[0]};
      if (!std::isfinite(c[0]) || !std::isfinite(c[1]) || !std::isfinite(c[2]))
        fail(path, "object too large: facet " + std::to_string(t.facet_id) +
                       " overflows float arithmetic");
      if (c[0] == 0 && c[1] == 0 && c[2] == 0) {
        ++dropped;
        continue;
      }
      tris[keep++] = t;
    }
    tris.resize(keep);
    if (dropped > 0)
      warn(path, std::to_string(dropped) +
                     " zero-area triangle(s) left out (too small for float); facet ids kept");
  }

  void box_extent(const Json& v, const std::string& path, Vec3& lo, Vec3& hi) const {
    const auto key = [&](const char* k) { return join_key(path, k); };
    const Json* mn = find(v, "min");
    const Json* mx = find(v, "max");
    const Json* ce = find(v, "center");
    const Json* sz = find(v, "size");
    if ((mn || mx) && (ce || sz)) fail(path, "give either min/max or center/size, not both");
    if (mn || mx) {
      lo = vec3(require(v, path, "min"), key("min"));
      hi = vec3(require(v, path, "max"), key("max"));
      for (int a = 0; a < 3; ++a)
        if (!(hi[a] > lo[a])) fail(key("max"), "must be greater than min on every axis");
      return;
    }
    if (!ce || !sz) fail(path, "a box needs min and max, or center and size");
    const Vec3 c = vec3(*ce, key("center"));
    Vec3 s;
    if (sz->is_number()) {
      const float x = positive(*sz, key("size"));
      s = {x, x, x};
    } else if (sz->is_array() && sz->size() == 3) {
      for (int a = 0; a < 3; ++a) s[a] = positive((*sz)[a], join_index(key("size"), a));
    } else {
      fail(key("size"), std::string("expected a positive number or [x, y, z], not ") + kind(*sz));
    }
    for (int a = 0; a < 3; ++a) {
      lo[a] = static_cast<float>(double(c[a]) - 0.5 * s[a]);
      hi[a] = static_cast<float>(double(c[a]) + 0.5 * s[a]);
      if (!(hi[a] > lo[a]) || !std::isfinite(lo[a]) || !std::isfinite(hi[a]))
        fail(key("size"), "too small or too large for the box's position");
    }
  }

  std::function<void(std::vector<Triangle>&)> terrain(const Json& v, const std::string& path) {
    check_keys(v, path, {"type", "name", "center", "size", "quads", "height", "features",
                         "octaves", "seed", "material", "materials", "transform"});
    const auto key = [&](const char* k) { return join_key(path, k); };
    TerrainDesc d;
    if (const Json* x = find(v, "center")) d.center = vec3(*x, key("center"));
    size2(require(v, path, "size"), key("size"), d.size_x, d.size_z);
    count2(require(v, path, "quads"), key("quads"), 100000, d.quads_x, d.quads_z);
    if (const Json* x = find(v, "height")) d.height = real(*x, key("height"));
    if (const Json* x = find(v, "features")) {
      d.features = positive(*x, key("features"));
      if (d.features > 1e6f) fail(key("features"), "must be at most 1e6");
    }
    if (const Json* x = find(v, "octaves")) d.octaves = integer(*x, key("octaves"), 1, 16);
    if (const Json* x = find(v, "seed")) d.seed = std::uint64_t(integer(*x, key("seed"), 0, INT_MAX));
    int a = 0, b = 0;
    if (find(v, "material") && find(v, "materials"))
      fail(path, "give either material or materials, not both");
    if (const Json* m = find(v, "materials")) {
      const std::vector<int> mats = material_list(*m, key("materials"));
      if (mats.size() != 2) fail(key("materials"), "expected exactly 2 materials");
      a = mats[0];
      b = mats[1];
    } else {
      a = b = material_ref(find(v, "material"), key("material"));
    }
    budget(std::size_t(2) * d.quads_x * d.quads_z, path);
    return [this, d, a, b](std::vector<Triangle>& tris) {
      next_facet_ = add_terrain(tris, d, next_object_++, a, b, next_facet_);
    };
  }

  // Many spheres/boxes, each its own object, from a fixed-seed PCG32. Per item
  // seven numbers are drawn in a fixed order: shape, radius, x, y, z,
  // material, angle (see FORMAT.md), so a scene is the same everywhere.
  std::function<void(std::vector<Triangle>&)> generator(const Json& v, const std::string& path,
                                                        bool grid) {
    if (grid)
      check_keys(v, path, {"type", "name", "counts", "min", "max", "jitter", "shapes", "radius",
                           "subdivisions", "materials", "weights", "seed", "transform"});
    else
      check_keys(v, path, {"type", "name", "count", "min", "max", "shapes", "radius",
                           "subdivisions", "materials", "weights", "seed", "transform"});
    const auto key = [&](const char* k) { return join_key(path, k); };
    const Vec3 lo = vec3(require(v, path, "min"), key("min"));
    const Vec3 hi = vec3(require(v, path, "max"), key("max"));
    for (int a = 0; a < 3; ++a)
      if (!(hi[a] >= lo[a])) fail(key("max"), "must not be less than min on any axis");
    const int kMaxItems = kMaxGeneratorItems;
    int counts[3] = {1, 1, 1};
    long long items = 0;
    if (grid) {
      const Json& c = require(v, path, "counts");
      if (c.is_number()) {
        counts[0] = counts[1] = counts[2] = integer(c, key("counts"), 1, 1000);
      } else if (c.is_array() && c.size() == 3) {
        for (int a = 0; a < 3; ++a) counts[a] = integer(c[a], join_index(key("counts"), a), 1, 100000);
      } else {
        fail(key("counts"), std::string("expected an integer or [nx, ny, nz], not ") + kind(c));
      }
      items = 1LL * counts[0] * counts[1] * counts[2];
      if (items > kMaxItems) fail(key("counts"), "more than " + std::to_string(kMaxItems) + " items");
    } else {
      items = integer(require(v, path, "count"), key("count"), 1, kMaxItems);
    }
    float jitter = 0;
    if (const Json* j = find(v, "jitter")) {
      jitter = real(*j, key("jitter"));
      if (!(jitter >= 0 && jitter <= 1)) fail(key("jitter"), "must be in [0, 1]");
    }
    bool want_sphere = true, want_box = false;
    std::vector<bool> shape_is_box{false};
    if (const Json* s = find(v, "shapes")) {
      expect_array(*s, key("shapes"));
      if (s->empty()) fail(key("shapes"), "needs at least one shape");
      shape_is_box.clear();
      want_sphere = false;
      for (std::size_t k = 0; k < s->size(); ++k) {
        const std::string n = string((*s)[k], join_index(key("shapes"), k));
        if (n != "sphere" && n != "box")
          fail(join_index(key("shapes"), k), "unknown shape '" + n + "' (expected sphere or box)");
        shape_is_box.push_back(n == "box");
        want_sphere = want_sphere || n == "sphere";
        want_box = want_box || n == "box";
      }
    }
    float rmin = 0.5f, rmax = 0.5f;
    if (const Json* r = find(v, "radius")) {
      if (r->is_array() && r->size() == 2) {
        rmin = positive((*r)[0], join_index(key("radius"), 0));
        rmax = positive((*r)[1], join_index(key("radius"), 1));
        if (rmax < rmin) fail(key("radius"), "[min, max] with max < min");
      } else {
        rmin = rmax = positive(*r, key("radius"));
      }
    }
    int sub = 2;
    if (const Json* s = find(v, "subdivisions")) sub = integer(*s, key("subdivisions"), 0, 10);
    std::vector<int> mats{0};
    if (const Json* m = find(v, "materials")) mats = material_list(*m, key("materials"));
    std::vector<double> cumulative;
    double total = 0;
    if (const Json* w = find(v, "weights")) {
      expect_array(*w, key("weights"));
      if (w->size() != mats.size())
        fail(key("weights"), "needs one weight per material (" + std::to_string(mats.size()) + ")");
      for (std::size_t k = 0; k < w->size(); ++k) {
        const double x = number((*w)[k], join_index(key("weights"), k));
        if (x < 0) fail(join_index(key("weights"), k), "must not be negative");
        total += x;
        cumulative.push_back(total);
      }
      if (!(total > 0)) fail(key("weights"), "must not all be zero");
    } else {
      for (std::size_t k = 0; k < mats.size(); ++k) cumulative.push_back(total += 1.0);
    }
    std::uint64_t seed = 1;
    if (const Json* s = find(v, "seed")) seed = std::uint64_t(integer(*s, key("seed"), 0, INT_MAX));

    const std::size_t per_item =
        std::max(want_sphere ? icosphere_triangles(sub) : 0, want_box ? std::size_t(12) : 0);
    if (per_item > 0 && std::size_t(items) > max_triangles_ / per_item)
      fail(path, std::to_string(items) + " items would make more than " +
                     std::to_string(max_triangles_) + " triangles (scenes/FORMAT.md, Limits)");
    budget(std::size_t(items) * per_item, std::size_t(items) * per_item, std::size_t(items), path);
    return [=](std::vector<Triangle>& tris) {
      build_items(tris, grid, items, counts, lo, hi, jitter, shape_is_box, rmin, rmax, sub, mats,
                  cumulative, total, seed);
    };
  }

  void build_items(std::vector<Triangle>& tris, bool grid, long long items, const int counts[3],
                   const Vec3& lo, const Vec3& hi, float jitter,
                   const std::vector<bool>& shape_is_box, float rmin, float rmax, int sub,
                   const std::vector<int>& mats, const std::vector<double>& cumulative,
                   double total, std::uint64_t seed) {
    Pcg32 rng(seed);
    for (long long n = 0; n < items; ++n) {
      const double u_shape = rng.uniform(), u_radius = rng.uniform();
      const double ux = rng.uniform(), uy = rng.uniform(), uz = rng.uniform();
      const double u_mat = rng.uniform(), u_angle = rng.uniform();
      const bool box = shape_is_box[std::min<std::size_t>(
          std::size_t(u_shape * shape_is_box.size()), shape_is_box.size() - 1)];
      const double r = rmin + (double(rmax) - rmin) * u_radius;
      double centre[3];
      const double u[3] = {ux, uy, uz};
      if (grid) {
        const long long cell[3] = {n % counts[0], (n / counts[0]) % counts[1],
                                   n / (1LL * counts[0] * counts[1])};
        for (int a = 0; a < 3; ++a) {
          const double step = (double(hi[a]) - lo[a]) / counts[a];
          centre[a] = lo[a] + step * (cell[a] + 0.5) + jitter * 0.5 * step * (2.0 * u[a] - 1.0);
        }
      } else {
        for (int a = 0; a < 3; ++a) centre[a] = lo[a] + (double(hi[a]) - lo[a]) * u[a];
      }
      std::size_t m = 0;
      const double pick = u_mat * total;
      while (m + 1 < cumulative.size() && pick >= cumulative[m]) ++m;
      const FacetTag tag{next_object_++, mats[m]};
      const Vec3 c{static_cast<float>(centre[0]), static_cast<float>(centre[1]),
                   static_cast<float>(centre[2])};
      const float rf = static_cast<float>(r);
      if (box) {
        const std::size_t start = tris.size();
        next_facet_ = add_box(tris, {-rf, -rf, -rf}, {rf, rf, rf}, tag, next_facet_);
        Transform place;
        place.rotate_deg = {0, static_cast<float>(90.0 * u_angle), 0};
        place.translate = c;
        transform_triangles(tris, start, place);
      } else {
        next_facet_ = add_icosphere(tris, c, rf, sub, tag, next_facet_);
      }
    }
  }

  // An OBJ file ("obj"), or a model in any format ("model": OBJ by the strict
  // reader, the others through the importer). The file is read now (an OBJ's
  // triangles count against the scene's limit as they are read), its
  // triangles appended when the scene is built.
  std::function<void(std::vector<Triangle>&)> include_obj(const Json& v, const std::string& path,
                                                          bool any_format) {
    check_keys(v, path, {"type", "name", "file", "material", "transform"});
    const std::string fkey = join_key(path, "file");
    const std::string file = string(require(v, path, "file"), fkey);
    if (file.empty()) fail(fkey, "empty file name");
    if (base_dir_.empty())
      fail(fkey, "this scene is read from memory and may not name other files");
    const fs::path p(file);
    const std::string full =
        p.is_absolute() ? file : (fs::path(base_dir_) / p).lexically_normal().string();
    const int override_mat = find(v, "material")
                                 ? material_ref(find(v, "material"), join_key(path, "material"))
                                 : -1;
    auto sub = std::make_shared<Scene>();
    try {
      const bool obj = lower(fs::path(full).extension().string()) == ".obj";
      if (!obj && any_format && !is_imported_model(full))
        throw InputError(full + ": not a model format the importer reads (see scenes/FORMAT.md)");
      if (obj || !any_format) {
        *sub = load_obj(full, max_triangles_ - planned_triangles_);
      } else {
        *sub = load_model(full);
        sub->input_files.insert(sub->input_files.begin(), full);
      }
    } catch (const InputError& e) {
      scene_.warnings.insert(scene_.warnings.end(), e.warnings.begin(), e.warnings.end());
      fail(fkey, e.what());
    }
    budget(sub->triangles.size(), std::size_t(sub->num_facets), std::size_t(sub->num_objects),
           path);
    const int mat_offset = static_cast<int>(scene_.materials.size()) - 1;
    const int tex_offset = static_cast<int>(scene_.textures.size());
    if (override_mat < 0) {
      for (std::size_t k = 1; k < sub->materials.size(); ++k) {
        MaterialDesc m = sub->materials[k];
        if (m.map_kd >= 0) m.map_kd += tex_offset;
        if (m.map_ka >= 0) m.map_ka += tex_offset;
        scene_.materials.push_back(std::move(m));
      }
      for (Texture& t : sub->textures) scene_.textures.push_back(std::move(t));
    }
    for (std::string& w : sub->warnings) scene_.warnings.push_back(std::move(w));
    for (std::string& f : sub->input_files) scene_.input_files.push_back(std::move(f));
    return [this, sub, override_mat, mat_offset](std::vector<Triangle>& tris) {
      const int attr_offset = static_cast<int>(scene_.attributes.size());
      for (const VertexAttributes& a : sub->attributes) scene_.attributes.push_back(a);
      for (Triangle t : sub->triangles) {
        t.object_id += next_object_;
        t.facet_id += next_facet_;
        t.material = override_mat >= 0 ? override_mat
                                       : (t.material == 0 ? 0 : t.material + mat_offset);
        if (t.attributes >= 0) t.attributes += attr_offset;
        tris.push_back(t);
      }
      next_object_ += sub->num_objects;
      next_facet_ += sub->num_facets;
      sub->triangles = std::vector<Triangle>();
      sub->attributes = std::vector<VertexAttributes>();
    };
  }

  const std::string& text_;
  const std::string& name_;
  std::string base_dir_;
  std::size_t max_triangles_;
  std::unique_ptr<JsonLines> lines_;
  Scene scene_;
  std::vector<std::function<void()>> builds_;  // one per object, in order
  std::size_t planned_triangles_ = 0, planned_facets_ = 0, planned_objects_ = 0;
  std::unordered_map<std::string, int> named_;
  std::vector<std::string> named_order_;
  int next_object_ = 0;
  int next_facet_ = 0;
};

}  // namespace

Scene load_scene_from_string(const std::string& text, const std::string& name,
                             const std::string& base_dir, std::size_t max_triangles) {
  try {
    if (text.size() > kMaxSceneFileBytes)
      throw InputError(name + ": scene file too large (" + std::to_string(text.size()) +
                       " bytes; the limit is " + std::to_string(kMaxSceneFileBytes) + ")");
    int line = 1;
    check_json_bytes(text.data(), text.size(), 0, line, name);
    return SceneReader(text, name, base_dir, max_triangles).run();
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

Scene load_scene(const std::string& path) {
  const std::string ext = lower(fs::path(path).extension().string());
  if (ext == ".obj") return load_obj(path);
  if (ext != ".json" && is_imported_model(path)) {
    Scene scene = load_model(path);
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
  Scene scene = load_scene_from_string(text, path, dir);
  scene.input_files.insert(scene.input_files.begin(), path);
  return scene;
}

}  // namespace opsila
