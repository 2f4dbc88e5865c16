// The values of a JSON scene document (scenes/FORMAT.md), read with every
// error one InputError naming the file, the line and the key path
// (objects[3].material.Kd): the part of the scene reader every section
// uses. Internal to formats/json.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdio>
#include <initializer_list>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/vec.h"
#include "formats/common/json_text.h"

namespace opsila {
namespace scene_json {

using Json = nlohmann::ordered_json;

constexpr int kMaxNesting = 64;
constexpr int kMaxKeys = 1024;  // in one object: FORMAT.md "Limits"

inline std::string num_text(double v) {
  char buf[32];
  // Whole numbers as written (2147483648, not 2.14748365e+09): a count or an
  // index read back in the message should be the user's number.
  if (std::floor(v) == v && std::fabs(v) < 1e15)
    std::snprintf(buf, sizeof buf, "%.0f", v);
  else
    std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

inline std::string join_key(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}

inline std::string join_index(const std::string& path, std::size_t i) {
  return path + "[" + std::to_string(i) + "]";
}

// What a value is, for "expected X, not Y".
const char* kind(const Json& v);

// The document of `text`: its nesting and keys within the limits, then
// parsed, every syntax or range error (number overflow included) one
// InputError naming FILE:LINE:COLUMN instead of the library's own text.
Json parse_scene_text(const std::string& text, const std::string& name);

class SceneValues {
 public:
  // The line of every key path of the (parsed) `text`; duplicate keys and
  // later warnings are appended to `warnings`.
  SceneValues(const std::string& text, const std::string& name, std::vector<std::string>& warnings);

  // "FILE:LINE: PATH: ", the start of a message about `path`.
  std::string where(const std::string& path) const;
  // where() without its closing ": " ("FILE:LINE: PATH"), for a message built later.
  std::string place(const std::string& path) const;
  [[noreturn]] void fail(const std::string& path, const std::string& what) const;
  void warn(const std::string& path, const std::string& what);

  static const Json* find(const Json& obj, const char* key);
  const Json& require(const Json& obj, const std::string& path, const char* key) const;
  void expect_object(const Json& v, const std::string& path) const;
  void expect_array(const Json& v, const std::string& path) const;
  // Unknown keys are warnings: typo protection without breaking old files.
  void check_keys(const Json& obj, const std::string& path, std::initializer_list<const char*> allowed);

  double number(const Json& v, const std::string& path) const;
  float real(const Json& v, const std::string& path) const;
  float positive(const Json& v, const std::string& path) const;
  int integer(const Json& v, const std::string& path, long long lo, long long hi) const;
  Vec3 vec3(const Json& v, const std::string& path) const;
  // A number (grey) or [r, g, b]; never negative.
  Vec3 colour(const Json& v, const std::string& path) const;
  // A positive number (both sizes alike) or [a, b].
  void size2(const Json& v, const std::string& path, float& a, float& b) const;
  // An integer in 1..hi (both alike) or [a, b].
  void count2(const Json& v, const std::string& path, int hi, int& a, int& b) const;
  std::string string(const Json& v, const std::string& path) const;
  // Refuses a \u0000 in any string or key under v (nesting is bounded).
  void refuse_nul(const Json& v, const std::string& path) const;

 private:
  const std::string& name_;
  std::vector<std::string>& warnings_;
  std::unique_ptr<JsonLines> lines_;
};

}  // namespace scene_json
}  // namespace opsila
