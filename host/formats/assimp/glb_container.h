// The GLB container (binary glTF, versions 1 and 2): its header and chunks,
// read with every length checked against the bytes that are there, since
// the importer allocates a chunk as long as its header says.
#pragma once

#include <cstdint>
#include <string>

namespace opsila {

// The little-endian 32-bit word at byte `at` of `b` (at + 4 <= b.size()).
std::uint32_t glb_le32(const std::string& b, std::size_t at);

// The JSON text of a glTF and the length of its GLB binary chunk (0 for a
// text glTF, or a GLB without one).
struct GltfParts {
  std::string json;
  std::uint64_t bin_bytes = 0;
  int glb_version = 0;  // 0: a text glTF
};

// A GLB's parts. Throws InputError naming `name` where a length runs past
// the file, or the version or first chunk is not one glTF defines.
GltfParts split_glb(const std::string& bytes, const std::string& name);

}  // namespace opsila
