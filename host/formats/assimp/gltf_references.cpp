// glTF 2 references from one collection into another (a node's mesh, a
// texture's image), each an index of an entry, named by its key: the
// importer said only `Array index 1 is out of bounds (1) for "meshes"`,
// `Member "mesh" was not of type "uint"` or `Missing section "samplers"`.
// The buffers, views, accessors, a node's children and a primitive's
// material are gltf_checks.cpp's.
#include <string>

#include <nlohmann/json.hpp>

#include "core/errors.h"
#include "formats/assimp/model_checks.h"
#include "formats/common/json_text.h"

namespace opsila {

namespace {

using Json = nlohmann::json;

class References {
 public:
  References(const Json& root, const std::string& path) : root_(root), path_(path) {}

  // `value`, at key `where`, the index of an entry of `to`.
  void index(const Json& value, const std::string& where, const char* to) const {
    const auto list = root_.find(to);
    const std::size_t n = list != root_.end() && list->is_array() ? list->size() : 0;
    if (value.is_number_unsigned() && value.get<std::uint64_t>() < n) return;
    throw InputError(path_ + ": " + where + ": '" + quoted_prefix(value.dump()) + "' is not the index of one of its " +
                     std::to_string(n) + " '" + to + "' entries");
  }
  // obj[key], where present: an index into `to` (or, with `many`, a list
  // of them).
  void member(const Json& obj, const char* key, const std::string& where, const char* to, bool many = false) const {
    if (!obj.is_object()) return;
    const auto it = obj.find(key);
    if (it == obj.end()) return;
    const std::string at = where + "." + key;
    if (!many) return index(*it, at, to);
    if (!it->is_array()) throw InputError(path_ + ": " + at + ": not a list of indices of '" + to + "'");
    for (std::size_t k = 0; k < it->size(); ++k) index((*it)[k], at + "[" + std::to_string(k) + "]", to);
  }
  // Each entry of the top-level collection `from`, with its key.
  template <class Visit>
  void each(const char* from, Visit&& visit) const {
    const auto list = root_.find(from);
    if (list == root_.end() || !list->is_array()) return;
    for (std::size_t k = 0; k < list->size(); ++k) visit((*list)[k], std::string(from) + "[" + std::to_string(k) + "]");
  }

 private:
  const Json& root_;
  const std::string& path_;
};

// A material's texture slots (textureInfo objects), each naming a texture.
void material_textures(const References& r, const Json& m, const std::string& at) {
  if (!m.is_object()) return;
  for (const char* slot : {"normalTexture", "occlusionTexture", "emissiveTexture"})
    if (m.contains(slot)) r.member(m[slot], "index", at + "." + slot, "textures");
  const auto pbr = m.find("pbrMetallicRoughness");
  if (pbr == m.end() || !pbr->is_object()) return;
  for (const char* slot : {"baseColorTexture", "metallicRoughnessTexture"})
    if (pbr->contains(slot)) r.member((*pbr)[slot], "index", at + ".pbrMetallicRoughness." + slot, "textures");
}

}  // namespace

void check_gltf_references(const Json& root, const std::string& path) {
  const References r(root, path);
  r.each("scenes", [&](const Json& s, const std::string& at) { r.member(s, "nodes", at, "nodes", true); });
  r.each("nodes", [&](const Json& n, const std::string& at) {
    r.member(n, "mesh", at, "meshes");
    r.member(n, "camera", at, "cameras");
    r.member(n, "skin", at, "skins");
  });
  r.each("materials", [&](const Json& m, const std::string& at) { material_textures(r, m, at); });
  r.each("textures", [&](const Json& t, const std::string& at) {
    r.member(t, "source", at, "images");
    r.member(t, "sampler", at, "samplers");
  });
}

}  // namespace opsila
