// Bytes of small glTF and GLB files for the model import tests.
#pragma once

#include <cstdint>
#include <cstring>
#include <string>

namespace opsila::test {

inline std::string le32(std::uint32_t v) {
  std::string s(4, '\0');
  for (int k = 0; k < 4; ++k) s[k] = char(v >> (8 * k) & 0xff);
  return s;
}

inline std::string f32(float x) {
  std::uint32_t v;
  static_assert(sizeof v == sizeof x);
  std::memcpy(&v, &x, sizeof v);
  return le32(v);
}

// One triangle's positions, 36 bytes.
inline std::string triangle_bytes() {
  std::string b;
  for (float x : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) b += f32(x);
  return b;
}

// A glTF 2 whose one triangle sits at the end of a chain of `depth` + 1
// nodes; the buffer is `uri` (external or data:), the view and accessor as given.
inline std::string gltf(const std::string& uri, const std::string& view = R"("byteOffset": 0, "byteLength": 36)",
                 const std::string& accessor_count = "3", int depth = 0) {
  std::string nodes;
  for (int i = 0; i < depth; ++i) nodes += "{\"children\": [" + std::to_string(i + 1) + "]},";
  nodes += "{\"mesh\": 0}";
  return R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [)" + nodes +
         R"(], "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
  "buffers": [{"uri": ")" + uri + R"(", "byteLength": 36}],
  "bufferViews": [{"buffer": 0, )" + view + R"(}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": )" + accessor_count +
         R"(, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}]})";
}

// A GLB 2 of `json` (its chunk claiming `json_claim` bytes) and `bin`.
inline std::string glb(const std::string& json, std::uint32_t json_claim, const std::string& bin = "") {
  std::string chunks = le32(json_claim) + "JSON" + json;
  if (!bin.empty()) chunks += le32(std::uint32_t(bin.size())) + std::string("BIN\0", 4) + bin;
  return "glTF" + le32(2) + le32(std::uint32_t(12 + chunks.size())) + chunks;
}

}  // namespace opsila::test
