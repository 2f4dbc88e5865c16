#include "formats/assimp/gltf_still.h"

#include <cstdint>

#include "formats/assimp/glb_container.h"

namespace opsila {

namespace {

std::string le32(std::size_t v) {
  std::string s(4, '\0');
  for (int k = 0; k < 4; ++k) s[std::size_t(k)] = char(v >> (8 * k) & 0xff);
  return s;
}

bool has_motion(const nlohmann::json& root) {
  if (root.contains("skins") || root.contains("animations")) return true;
  const auto nodes = root.find("nodes");
  if (nodes == root.end() || !nodes->is_structured()) return false;
  for (const nlohmann::json& n : *nodes)
    if (n.is_object() && n.contains("skin")) return true;
  return false;
}

}  // namespace

std::optional<std::string> gltf_without_motion(const nlohmann::json& root, const std::string& bytes,
                                               bool rewritten) {
  if (!rewritten && !has_motion(root)) return std::nullopt;
  nlohmann::json still = root;
  still.erase("skins");
  still.erase("animations");
  const auto nodes = still.find("nodes");
  if (nodes != still.end() && nodes->is_structured())
    for (nlohmann::json& n : *nodes)
      if (n.is_object()) n.erase("skin");
  std::string text = still.dump();
  if (bytes.compare(0, 4, "glTF") != 0) return text;
  // GLB: the binary data after the JSON starts 4-byte aligned, so the JSON
  // is padded with spaces (both versions).
  text.resize((text.size() + 3) / 4 * 4, ' ');
  const std::size_t length = glb_le32(bytes, 8);
  if (glb_le32(bytes, 4) == 1) {  // 20-byte header: magic, version, length, content length, format
    const std::size_t content = glb_le32(bytes, 12);
    std::string out = bytes.substr(0, 8) + le32(20 + text.size() + (length - 20 - content)) + le32(text.size()) +
                      bytes.substr(16, 4) + text + bytes.substr(20 + content, length - 20 - content);
    return out;
  }
  const std::size_t json = glb_le32(bytes, 12);  // the first chunk's length; its type is JSON
  return bytes.substr(0, 8) + le32(20 + text.size() + (length - 20 - json)) + le32(text.size()) +
         bytes.substr(16, 4) + text + bytes.substr(20 + json, length - 20 - json);
}

}  // namespace opsila
