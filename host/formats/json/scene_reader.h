// The JSON scene reader shared by the files that read a scene document:
// scene_file.cpp (the document, its limits and value checks),
// scene_sections.cpp (image, camera, lights, materials, transforms) and
// scene_objects.cpp (objects, generators, included models). Internal to
// host/input.
#pragma once

#include "formats/json/scene_file.h"

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
#include "formats/common/json_text.h"
#include "formats/assimp/model_import.h"
#include "formats/assimp/model_window.h"
#include "formats/json/primitives.h"

namespace opsila {
namespace scene_json {

using Json = nlohmann::ordered_json;

constexpr int kMaxNesting = 64;
constexpr int kMaxKeys = 1024;  // in one object: FORMAT.md "Limits"
constexpr int kMaxGeneratorItems = 1000000;  // FORMAT.md "Limits"

inline std::string num_text(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

inline std::string join_key(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}

inline std::string join_index(const std::string& path, std::size_t i) {
  return path + "[" + std::to_string(i) + "]";
}

inline const char* kind(const Json& v) {
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
  // share.ranks > 1: read this rank's share (scene_share.cpp); max_triangles
  // is then one rank's limit, and the scene may have ranks times it.
  SceneReader(const std::string& text, const std::string& name, const std::string& base_dir,
              std::size_t max_triangles, const SceneShare& share = SceneShare{})
      : text_(text), name_(name), base_dir_(base_dir), entry_limit_(max_triangles),
        max_triangles_(max_triangles * std::size_t(std::max(share.ranks, 1))), share_(share) {}

  Scene run();

 private:
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

  // The document, its errors and value checks (scene_file.cpp).
  Scene read();
  Json parse() const;
  [[noreturn]] void syntax_error(std::size_t byte, const std::string& what,
                                 const std::string& token) const;
  static std::string quoted_line(std::string text);
  std::string where(const std::string& path) const;
  [[noreturn]] void fail(const std::string& path, const std::string& what) const;
  void warn(const std::string& path, const std::string& what);
  static const Json* find(const Json& obj, const char* key);
  const Json& require(const Json& obj, const std::string& path, const char* key) const;
  void expect_object(const Json& v, const std::string& path) const;
  void expect_array(const Json& v, const std::string& path) const;
  void check_keys(const Json& obj, const std::string& path,
                  std::initializer_list<const char*> allowed);
  double number(const Json& v, const std::string& path) const;
  float real(const Json& v, const std::string& path) const;
  float positive(const Json& v, const std::string& path) const;
  int integer(const Json& v, const std::string& path, long long lo, long long hi) const;
  Vec3 vec3(const Json& v, const std::string& path) const;
  Vec3 colour(const Json& v, const std::string& path) const;
  void size2(const Json& v, const std::string& path, float& a, float& b) const;
  void count2(const Json& v, const std::string& path, int hi, int& a, int& b) const;
  std::string string(const Json& v, const std::string& path) const;

  // Sections (scene_sections.cpp).
  void image(const Json& v, const std::string& path);
  void camera(const Json& v, const std::string& path);
  void lights(const Json& v, const std::string& path);
  void materials(const Json& v, const std::string& path);
  MaterialDesc material(const Json& v, const std::string& path, const std::string& name);
  int material_ref(const Json* v, const std::string& path);
  std::vector<int> material_list(const Json& v, const std::string& path);
  Transform transform(const Json& v, const std::string& path);

  // Objects (scene_objects.cpp).
  // windowed: an entry no rank holds whole (a terrain made in windows, a
  // generator's items dealt as they are made), so not limited to one rank's
  // triangles on several ranks.
  void budget(std::size_t triangles, std::size_t facets, std::size_t objects,
              const std::string& path, bool windowed = false);
  void budget(std::size_t triangles, const std::string& path);
  std::string ranks_hint(std::size_t triangles, bool windowed) const;
  void objects(const Json& v, const std::string& path);
  void object(const Json& v, const std::string& path);
  std::size_t settle(std::size_t first, const std::string& path);  // returns the triangles dropped
  void flush_entry();
  void warn_dropped(const std::string& path, std::size_t dropped);
  void box_extent(const Json& v, const std::string& path, Vec3& lo, Vec3& hi) const;
  std::function<void(std::vector<Triangle>&)> solid(const Json& v, const std::string& path, const std::string& type);
  std::function<void(std::vector<Triangle>&)> plane(const Json& v, const std::string& path, bool checker);
  long long generator_items(const Json& v, const std::string& path, bool grid, int counts[3]);
  double material_weights(const Json& v, const std::string& path, std::size_t materials,
                          std::vector<double>& cumulative);
  std::function<void(std::vector<Triangle>&)> terrain(const Json& v, const std::string& path);
  std::function<void(std::vector<Triangle>&)> generator(const Json& v, const std::string& path,
                                                        bool grid);
  void build_items(std::vector<Triangle>& tris, bool grid, long long items, const int counts[3],
                   const Vec3& lo, const Vec3& hi, float jitter,
                   const std::vector<bool>& shape_is_box, float rmin, float rmax, int sub,
                   const std::vector<int>& mats, const std::vector<double>& cumulative,
                   double total, std::uint64_t seed);
  std::function<void(std::vector<Triangle>&)> include_obj(const Json& v, const std::string& path,
                                                          bool any_format);
  // Shares (scene_share.cpp).
  void deal(std::size_t first, std::size_t first_attribute);
  void window(std::size_t all, int object, std::size_t& begin, std::size_t& end);
  void count_window(std::size_t first);
  void file_window(Scene& sub, const std::string& file, std::uint64_t fans, const std::string& fkey);
  void model_again(Scene& sub, const std::string& file, std::size_t triangles, const std::string& fkey);
  void grow_bounds(const Triangle& t);
  void settle_share();

  const std::string& text_;
  const std::string& name_;
  std::string base_dir_;
  std::size_t entry_limit_;    // one entry of "objects" (one rank's limit)
  std::size_t max_triangles_;  // the whole scene
  SceneShare share_;           // rank and ranks; the whole scene's figures as they are built
  std::vector<int> owner_;     // object id -> the rank it is dealt to (-1: not yet seen)
  // The entry of "objects" being built: what is not yet placed, settled and
  // dealt starts at `first`; `dealt` of its triangles were dealt before.
  struct Entry {
    std::optional<Transform> placed;
    std::string path;
    std::size_t first = 0, first_attribute = 0, dropped = 0;
    std::size_t planned_begin = 0, planned_end = 0;  // its part of the plan
    std::size_t expected = 0;  // its exact triangle count when known before it is built (generators)
    std::size_t dealt = 0;
    bool windowed = false;  // each rank made only its window (window())
  } entry_;
  bool bounded_ = false;  // share_.lo/hi hold a triangle
  std::vector<std::string> window_paths_;  // the windowed entries, as share_.window_dropped
  static constexpr long long kFlushItems = 4096;  // generator items between flushes, at most
  static constexpr std::size_t kFlushTriangles = std::size_t(1) << 18;  // and about this many triangles
  std::unique_ptr<JsonLines> lines_;
  Scene scene_;
  std::vector<std::function<void()>> builds_;  // one per object, in order
  std::size_t planned_triangles_ = 0, planned_facets_ = 0, planned_objects_ = 0;
  std::unordered_map<std::string, int> named_;
  std::vector<std::string> named_order_;
  int next_object_ = 0;
  int next_facet_ = 0;
};

}  // namespace scene_json
}  // namespace opsila
