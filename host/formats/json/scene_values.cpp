// The values of a JSON scene document (scene_values.h). nlohmann::json
// checks the syntax; a second, light pass over the (then known to be valid)
// text records the line of every key path (JsonLines), so that semantic
// errors can name file, line and key.
#include "formats/json/scene_values.h"

#include <algorithm>
#include <cmath>

#include "core/errors.h"
#include "scene/scene.h"

namespace opsila {
namespace scene_json {

namespace {

// A library message without line breaks and of bounded length.
std::string quoted_line(std::string text) {
  std::replace(text.begin(), text.end(), '\n', ' ');
  if (text.size() > 200) text = text.substr(0, 200) + "...";
  return text;
}

[[noreturn]] void syntax_error(const std::string& text, const std::string& name, std::size_t byte,
                               const std::string& what, const std::string& token) {
  const std::size_t p = std::min(byte > 0 ? byte - 1 : 0, text.size());
  int line = 1;
  std::size_t line_start = 0;
  for (std::size_t k = 0; k < p; ++k) {
    if (text[k] == '\n') {
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
  throw InputError(name + ":" + std::to_string(line) + ":" +
                   std::to_string(p - line_start + 1) + ": " + quoted_line(detail));
}

// nlohmann's DOM builder, with every syntax or range error turned into
// syntax_error's message.
struct DomBuilder : nlohmann::detail::json_sax_dom_parser<Json> {
  DomBuilder(Json& root, const std::string& text, const std::string& name)
      : nlohmann::detail::json_sax_dom_parser<Json>(root, false), text_(text), name_(name) {}
  bool parse_error(std::size_t byte, const std::string& token, const nlohmann::detail::exception& e) {
    syntax_error(text_, name_, byte, e.what(), token);
  }
  const std::string& text_;
  const std::string& name_;
};

}  // namespace

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

Json parse_scene_text(const std::string& text, const std::string& name) {
  check_json_shape(text, name, kMaxNesting, kMaxKeys);
  Json root;
  DomBuilder builder(root, text, name);
  if (!Json::sax_parse(text, &builder)) syntax_error(text, name, text.size(), "syntax error", "");
  return root;
}

SceneValues::SceneValues(const std::string& text, const std::string& name, std::vector<std::string>& warnings)
    : name_(name), warnings_(warnings), lines_(std::make_unique<JsonLines>(text, name, warnings)) {}

std::string SceneValues::where(const std::string& path) const {
  const int line = lines_->line_of(path);
  return name_ + ":" + std::to_string(line) + ": " + (path.empty() ? "" : shown_path(path) + ": ");
}

std::string SceneValues::place(const std::string& path) const {
  std::string w = where(path);
  w.resize(w.size() - 2);  // its ": "
  return w;
}

[[noreturn]] void SceneValues::fail(const std::string& path, const std::string& what) const {
  throw InputError(where(path) + what);
}

void SceneValues::warn(const std::string& path, const std::string& what) {
  warnings_.push_back(where(path) + what);
}

const Json* SceneValues::find(const Json& obj, const char* key) {
  auto it = obj.find(key);
  return it == obj.end() ? nullptr : &*it;
}

const Json& SceneValues::require(const Json& obj, const std::string& path, const char* key) const {
  const Json* v = find(obj, key);
  if (!v) fail(path, std::string("missing key '") + key + "'");
  return *v;
}

void SceneValues::expect_object(const Json& v, const std::string& path) const {
  if (!v.is_object()) fail(path, std::string("expected an object, not ") + kind(v));
}

void SceneValues::expect_array(const Json& v, const std::string& path) const {
  if (!v.is_array()) fail(path, std::string("expected an array, not ") + kind(v));
}

void SceneValues::check_keys(const Json& obj, const std::string& path,
                             std::initializer_list<const char*> allowed) {
  for (auto it = obj.begin(); it != obj.end(); ++it) {
    if (it.key() == "comment") continue;
    bool known = false;
    for (const char* a : allowed) known = known || it.key() == a;
    if (!known)
      warn(join_key(path, it.key()), "unknown key '" + quoted_prefix(it.key()) + "' (ignored)");
  }
}

double SceneValues::number(const Json& v, const std::string& path) const {
  if (!v.is_number()) fail(path, std::string("expected a number, not ") + kind(v));
  const double d = v.get<double>();
  if (!std::isfinite(d) || !std::isfinite(static_cast<float>(d)))
    fail(path, "number " + num_text(d) + " is out of range");
  return d;
}

float SceneValues::real(const Json& v, const std::string& path) const {
  return static_cast<float>(number(v, path));
}

float SceneValues::positive(const Json& v, const std::string& path) const {
  const float x = real(v, path);
  if (!(x > 0)) fail(path, "must be positive, not " + num_text(x));
  return x;
}

int SceneValues::integer(const Json& v, const std::string& path, long long lo, long long hi) const {
  const double d = number(v, path);
  if (std::floor(d) != d) fail(path, "expected an integer, not " + num_text(d));
  if (d < double(lo) || d > double(hi))
    fail(path, "must be in " + std::to_string(lo) + ".." + std::to_string(hi) + ", not " +
                   num_text(d));
  return static_cast<int>(d);
}

Vec3 SceneValues::vec3(const Json& v, const std::string& path) const {
  if (!v.is_array() || v.size() != 3)
    fail(path, std::string("expected [x, y, z], not ") +
                   (v.is_array() ? "an array of " + std::to_string(v.size())
                                 : std::string(kind(v))));
  return {real(v[0], join_index(path, 0)), real(v[1], join_index(path, 1)),
          real(v[2], join_index(path, 2))};
}

Vec3 SceneValues::colour(const Json& v, const std::string& path) const {
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

void SceneValues::size2(const Json& v, const std::string& path, float& a, float& b) const {
  if (v.is_number()) {
    a = b = positive(v, path);
  } else if (v.is_array() && v.size() == 2) {
    a = positive(v[0], join_index(path, 0));
    b = positive(v[1], join_index(path, 1));
  } else {
    fail(path, std::string("expected a positive number or [x, z], not ") + kind(v));
  }
}

void SceneValues::count2(const Json& v, const std::string& path, int hi, int& a, int& b) const {
  if (v.is_number()) {
    a = b = integer(v, path, 1, hi);
  } else if (v.is_array() && v.size() == 2) {
    a = integer(v[0], join_index(path, 0), 1, hi);
    b = integer(v[1], join_index(path, 1), 1, hi);
  } else {
    fail(path, std::string("expected an integer or [nx, nz], not ") + kind(v));
  }
}

std::string SceneValues::string(const Json& v, const std::string& path) const {
  if (!v.is_string()) fail(path, std::string("expected a string, not ") + kind(v));
  return v.get_ref<const std::string&>();
}

// A name cut at its NUL would name something else ("t.obj\u0000x" read
// t.obj; a material or a key likewise): no string or key may hold one.
void SceneValues::refuse_nul(const Json& v, const std::string& path) const {
  const auto has_nul = [](const std::string& s) { return s.find('\0') != std::string::npos; };
  if (v.is_string() && has_nul(v.get_ref<const std::string&>()))
    fail(path, "a string may not hold \\u0000 (a NUL)");
  if (v.is_array())
    for (std::size_t i = 0; i < v.size(); ++i) refuse_nul(v[i], join_index(path, i));
  if (!v.is_object()) return;
  for (auto it = v.begin(); it != v.end(); ++it) {
    if (has_nul(it.key())) fail(path, "a key may not hold \\u0000 (a NUL)");
    refuse_nul(it.value(), join_key(path, it.key()));
  }
}

}  // namespace scene_json
}  // namespace opsila
