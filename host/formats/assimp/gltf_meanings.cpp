// What a glTF states that the importer would ignore or misread, checked
// before it reads the file (model_checks.h, check_gltf_meanings): found by
// hostile files that rendered something else than they say, exit 0.
#include <cmath>
#include <cstdio>
#include <string>

#include <nlohmann/json.hpp>

#include "core/errors.h"
#include "formats/assimp/model_checks.h"
#include "formats/common/json_text.h"

namespace opsila {

namespace {

using Json = nlohmann::json;

// The extensions a file may require: those the importer reads (Debian's
// assimp 5.2), and shading ones (KHR_materials_*, WebGL techniques), which
// the contract's material mapping replaces anyway. A loader must refuse
// any other (glTF 2.0, 3.12): instancing, quantised meshes and the like
// would be lost or misread.
const char* const kReadExtensions[] = {"KHR_draco_mesh_compression", "KHR_texture_transform", "KHR_lights_punctual",
                                       "KHR_technique_webgl", "KHR_techniques_webgl"};

bool read_extension(const Json& e) {
  if (!e.is_string()) return false;
  const std::string& name = e.get_ref<const std::string&>();
  for (const char* known : kReadExtensions)
    if (name == known) return true;
  return name.rfind("KHR_materials_", 0) == 0;
}

std::string number_text(double v) {
  char s[32];
  std::snprintf(s, sizeof s, "%g", v);
  return s;
}

[[noreturn]] void refuse(const std::string& path, const std::string& where, const std::string& what) {
  throw InputError(path + ": " + where + ": " + what);
}

void check_version(const Json& root, const std::string& path, bool& two) {
  // Without one, or with a number, the importer's glTF 1 reader may still
  // take it (early glTF 1 files): its own words then.
  const auto asset = root.find("asset");
  if (asset == root.end() || !asset->is_object() || !asset->contains("version")) return;
  if (!(*asset)["version"].is_string()) return;  // early glTF 1 files wrote a number
  const std::string v = (*asset)["version"].get<std::string>();
  if (v.rfind("1.", 0) != 0 && v.rfind("2.", 0) != 0)
    refuse(path, "asset.version", "'" + quoted_prefix(v) + "' (glTF 1.x and 2.x are read)");
  two = v[0] == '2';
}

void check_required(const Json& root, const std::string& path) {
  const auto required = root.find("extensionsRequired");
  if (required == root.end() || !required->is_array()) return;
  for (std::size_t k = 0; k < required->size(); ++k) {
    const Json& e = (*required)[k];
    if (!read_extension(e))
      refuse(path, "extensionsRequired[" + std::to_string(k) + "]",
             "'" + quoted_prefix(e.is_string() ? e.get<std::string>() : e.dump()) +
                 "' is required, and the model importer does not read it (what it changes would be lost)");
  }
}

// `n` finite numbers in [lo, hi] at j[key], where present.
void check_numbers(const Json& j, const char* key, std::size_t n, double lo, double hi, const std::string& path,
                   const std::string& where) {
  if (!j.is_object() || !j.contains(key)) return;
  const Json& v = j[key];
  bool sound = v.is_array() && v.size() == n;
  for (std::size_t k = 0; sound && k < n; ++k)
    sound = v[k].is_number() && std::isfinite(v[k].get<double>()) && v[k].get<double>() >= lo && v[k].get<double>() <= hi;
  if (!sound)
    refuse(path, where + "." + key,
           "expected " + std::to_string(n) + " numbers" +
               (std::isfinite(lo) ? " from " + number_text(lo) + " to " + number_text(hi) : std::string()) +
               ", not " + quoted_prefix(v.dump()));
}

// Every KHR_texture_transform below `j` (a material's texture infos): its
// offset and scale two numbers, its rotation one (the importer indexed
// short arrays out of bounds).
void check_transforms(const Json& j, const std::string& path, const std::string& where) {
  if (j.is_array())
    for (std::size_t k = 0; k < j.size(); ++k) check_transforms(j[k], path, where + "[" + std::to_string(k) + "]");
  if (!j.is_object()) return;
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string at = where + "." + it.key();
    if (it.key() != "KHR_texture_transform") {
      check_transforms(it.value(), path, at);
      continue;
    }
    const double inf = INFINITY;
    check_numbers(it.value(), "offset", 2, -inf, inf, path, at);
    check_numbers(it.value(), "scale", 2, -inf, inf, path, at);
    if (it.value().is_object() && it.value().contains("rotation") &&
        !(it.value()["rotation"].is_number() && std::isfinite(it.value()["rotation"].get<double>())))
      refuse(path, at + ".rotation", "expected a number, not " + quoted_prefix(it.value()["rotation"].dump()));
  }
}

// A primitive's POSITION and NORMAL: float VEC3 accessors, the only kind
// the importer reads as such (a VEC2 position had its z read as 0, a
// quantised one, KHR_mesh_quantization, its bytes as floats).
void check_attributes(const Json& root, const std::string& path) {
  const auto meshes = root.find("meshes"), accessors = root.find("accessors");
  if (meshes == root.end() || !meshes->is_array() || accessors == root.end() || !accessors->is_array()) return;
  for (std::size_t m = 0; m < meshes->size(); ++m) {
    const Json& prims = (*meshes)[m].is_object() ? (*meshes)[m].value("primitives", Json()) : Json();
    for (std::size_t p = 0; prims.is_array() && p < prims.size(); ++p)
      for (const char* name : {"POSITION", "NORMAL"}) {
        const Json& attrs = prims[p].is_object() ? prims[p].value("attributes", Json()) : Json();
        if (!attrs.is_object() || !attrs.contains(name) || !attrs[name].is_number_unsigned()) continue;
        const std::size_t a = attrs[name].get<std::size_t>();
        if (a >= accessors->size() || !(*accessors)[a].is_object()) continue;  // judged with the accessors
        const Json& acc = (*accessors)[a];
        if (acc.value("type", Json()) == "VEC3" && acc.value("componentType", Json()) == 5126) continue;
        refuse(path,
               "meshes[" + std::to_string(m) + "].primitives[" + std::to_string(p) + "].attributes." + name,
               "accessor " + std::to_string(a) + " is " + acc.value("type", Json()).dump() + " of componentType " +
                   acc.value("componentType", Json()).dump() +
                   "; the model importer reads positions and normals as float VEC3 (5126) only (quantised meshes, "
                   "KHR_mesh_quantization, are not read)");
      }
  }
}

// The scene to show: the importer said only "No scene" of an index past
// the list, or of a file without scenes.
void check_scene_index(const Json& root, const std::string& path) {
  const auto scenes = root.find("scenes");
  const std::size_t n = scenes != root.end() && scenes->is_array() ? scenes->size() : 0;
  if (n == 0) refuse(path, "scenes", "none: nothing places a mesh (a glTF shows the nodes of a scene)");
  const auto scene = root.find("scene");
  if (scene == root.end()) return;
  if (!scene->is_number_integer() || scene->get<long long>() < 0 || std::size_t(scene->get<long long>()) >= n)
    refuse(path, "scene", "'" + quoted_prefix(scene->dump()) + "' is not the index of one of its " +
                              std::to_string(n) + " scene(s)");
}

}  // namespace

void check_gltf_meanings(const Json& root, const std::string& path) {
  bool two = false;
  check_version(root, path, two);
  if (!two) return;  // glTF 1 keys its collections by id: the importer's own checks
  check_required(root, path);
  check_scene_index(root, path);
  check_attributes(root, path);
  const auto materials = root.find("materials");
  for (std::size_t k = 0; materials != root.end() && materials->is_array() && k < materials->size(); ++k) {
    const Json& m = (*materials)[k];
    const std::string at = "materials[" + std::to_string(k) + "]";
    if (m.is_object() && m.contains("pbrMetallicRoughness"))
      check_numbers(m["pbrMetallicRoughness"], "baseColorFactor", 4, 0, 1, path, at + ".pbrMetallicRoughness");
    check_transforms(m, path, at);
  }
  check_gltf_references(root, path);
}

}  // namespace opsila
