#include "formats/assimp/glb_container.h"

#include "core/errors.h"

namespace opsila {

std::uint32_t glb_le32(const std::string& b, std::size_t at) {
  std::uint32_t v = 0;
  for (int k = 3; k >= 0; --k) v = v << 8 | static_cast<unsigned char>(b[at + k]);
  return v;
}

GltfParts split_glb(const std::string& b, const std::string& name) {
  const std::uint64_t size = b.size();
  if (size < 20) throw InputError(name + ": GLB file shorter than its header (truncated file)");
  const std::uint32_t version = glb_le32(b, 4), length = glb_le32(b, 8);
  // The importer reads the first chunk's header whatever the length says,
  // and allocates what that chunk claims (found by fuzz_model).
  if (length < 20)
    throw InputError(name + ": GLB header says " + std::to_string(length) +
                     " bytes, fewer than its header and first chunk's (20)");
  if (length > size)
    throw InputError(name + ": GLB header says " + std::to_string(length) + " bytes; the file holds " +
                     std::to_string(size) + " (truncated file)");
  GltfParts parts;
  parts.glb_version = int(version);
  if (version == 1) {  // 20-byte header, then the JSON content, then the binary body
    const std::uint64_t content = glb_le32(b, 12);
    if (content > std::uint64_t(length) - 20)
      throw InputError(name + ": GLB content length " + std::to_string(content) + " runs past the file's " +
                       std::to_string(length) + " bytes");
    parts.json = b.substr(20, content);
    parts.bin_bytes = length - 20 - content;
    return parts;
  }
  if (version != 2) throw InputError(name + ": GLB version " + std::to_string(version) + " (1 or 2 are read)");
  std::uint64_t at = 12;
  for (int chunk = 0; at < length; ++chunk) {
    if (std::uint64_t(length) - at < 8) throw InputError(name + ": GLB chunk " + std::to_string(chunk) + ": header cut off");
    const std::uint64_t bytes = glb_le32(b, at), type = glb_le32(b, at + 4);
    if (bytes > std::uint64_t(length) - at - 8)
      throw InputError(name + ": GLB chunk " + std::to_string(chunk) + " claims " + std::to_string(bytes) +
                       " bytes; " + std::to_string(std::uint64_t(length) - at - 8) + " follow it in the file");
    if (chunk == 0 && type != 0x4E4F534Au) throw InputError(name + ": GLB's first chunk is not JSON");
    if (chunk == 0) parts.json = b.substr(at + 8, bytes);
    if (chunk == 1 && type == 0x004E4942u) parts.bin_bytes = bytes;
    // The importer reads chunk 1's and ignores the rest.
    if (chunk > 1 && type == 0x004E4942u)
      throw InputError(name + ": GLB chunk " + std::to_string(chunk) + ": a BIN chunk past chunk 1 (a GLB holds at "
                       "most one, as its second chunk)");
    at += 8 + bytes;
  }
  return parts;
}

}  // namespace opsila
