// stb_image is compiled here, once, with only the decoders CONTRACT names.
#include "formats/image/texture_file.h"

#include <algorithm>
#include <cstdlib>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <system_error>

#include <sys/stat.h>

#define STBI_ONLY_PNG
#define STBI_ONLY_JPEG
#define STBI_ONLY_TGA
#define STBI_ONLY_BMP
#define STBI_NO_STDIO
#define STBI_MAX_DIMENSIONS 16384
// Failure reasons as sentences ("Corrupt PNG"), not stb's short codes.
#define STBI_FAILURE_USERMSG
#define STB_IMAGE_IMPLEMENTATION
#include <stb/stb_image.h>

#include "core/input_file.h"

namespace opsila {

namespace fs = std::filesystem;

namespace {

std::uint32_t le(const unsigned char* data, std::size_t at, int bytes) {
  std::uint32_t v = 0;
  for (int k = bytes - 1; k >= 0; --k) v = v << 8 | data[at + std::size_t(k)];
  return v;
}

// Where an uncompressed BMP, or a TGA, is shorter than its header says:
// stb decodes the missing pixels as zeros, so a file of a few bytes would
// become a black image of the size it claims. "" when it is long enough (or
// not one of these; stb then judges it). A TGA's run-length packets hold at
// most 128 pixels each, in at least one byte more than a pixel.
std::string short_bmp_or_tga(const unsigned char* data, std::size_t size, long long w, long long h) {
  const unsigned long long pixels = static_cast<unsigned long long>(w) * static_cast<unsigned long long>(h);
  unsigned long long need = 0;
  const char* format = "";
  if (size >= 34 && data[0] == 'B' && data[1] == 'M') {
    const bool os2 = le(data, 14, 4) == 12;  // the old 12-byte header: no compression field
    const std::uint32_t compression = os2 ? 0 : le(data, 30, 4), bits = le(data, os2 ? 24 : 28, 2);
    if (compression != 0 && compression != 3) return "";
    format = "BMP";
    need = le(data, 10, 4) + (static_cast<unsigned long long>(w) * bits + 31) / 32 * 4 * static_cast<unsigned long long>(h);
  } else if (size >= 18 && (data[2] & 7) != 0 && (data[2] & ~0xBu) == 0 && (data[1] == 0 || data[1] == 1)) {
    const unsigned long long pixel_bytes = (data[16] + 7u) / 8u;
    const unsigned long long palette = data[1] ? le(data, 5, 2) * ((data[7] + 7u) / 8u) : 0;
    format = "TGA";
    need = 18 + data[0] + palette + ((data[2] & 8) ? (pixels + 127) / 128 * (1 + pixel_bytes) : pixels * pixel_bytes);
  }
  if (need <= size) return "";
  return std::string("truncated ") + format + ": " + std::to_string(w) + "x" + std::to_string(h) + " needs at least " +
         std::to_string(need) + " bytes, the file has " + std::to_string(size);
}

}  // namespace

bool decode_texture_memory(const unsigned char* data, std::size_t size, const std::string& name,
                           Texture& out, std::string& problem) {
  if (size == 0 || size > static_cast<std::size_t>(std::numeric_limits<int>::max())) {
    problem = size == 0 ? "empty image file" : "image file too large";
    return false;
  }
  const int len = static_cast<int>(size);
  int w = 0, h = 0, channels = 0;
  // A PNG's size is in its first chunk (IHDR, big-endian width and height):
  // stb refuses one past its limit, then tries the other formats, and its
  // last reason ("unknown type") would hide why.
  static const unsigned char kPngSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  const bool png = size >= 8 && std::equal(kPngSignature, kPngSignature + 8, data);
  if (png && size >= 24) {
    const auto be32 = [&](std::size_t at) {
      return std::uint32_t(data[at]) << 24 | std::uint32_t(data[at + 1]) << 16 | std::uint32_t(data[at + 2]) << 8 |
             std::uint32_t(data[at + 3]);
    };
    const std::uint32_t pw = be32(16), ph = be32(20);
    if (pw > std::uint32_t(kMaxTextureSide) || ph > std::uint32_t(kMaxTextureSide)) {
      problem = "image too large (" + std::to_string(pw) + "x" + std::to_string(ph) + ")";
      return false;
    }
  }
  if (!stbi_info_from_memory(data, len, &w, &h, &channels)) {
    const char* why = stbi_failure_reason();
    problem = std::string("not a readable PNG, JPEG, TGA or BMP image") + (why ? std::string(" (") + why + ")" : "");
    return false;
  }
  // A top-down BMP may state a negative height: the size is told as it is meant.
  const long long aw = std::llabs(w), ah = std::llabs(h);
  if (aw == 0 || ah == 0) {
    problem = "image has no pixels (" + std::to_string(w) + "x" + std::to_string(h) + ")";
    return false;
  }
  if (aw > kMaxTextureSide || ah > kMaxTextureSide ||
      static_cast<std::size_t>(aw) * static_cast<std::size_t>(ah) > kMaxTextureTexels) {
    problem = "image too large (" + std::to_string(aw) + "x" + std::to_string(ah) + ")";
    return false;
  }
  if (std::string why = short_bmp_or_tga(data, size, aw, ah); !why.empty()) {
    problem = "cannot decode the image (" + why + ")";
    return false;
  }
  if (stbi_is_16_bit_from_memory(data, len)) {
    problem = "16-bit images are not supported (8 bits per channel)";
    return false;
  }
  unsigned char* pixels = stbi_load_from_memory(data, len, &w, &h, &channels, 3);
  if (!pixels) {
    const char* why = stbi_failure_reason();
    problem = std::string("cannot decode the image") + (why ? std::string(" (") + why + ")" : "");
    // stb names the chunk it could not read, not the truncation.
    static const char kIend[4] = {'I', 'E', 'N', 'D'};
    if (png && std::search(data, data + size, kIend, kIend + 4) == data + size)
      problem = "cannot decode the image (truncated PNG: it ends before its IEND chunk)";
    return false;
  }
  out.path = name;
  out.width = w;
  out.height = h;
  out.texels.resize(static_cast<std::size_t>(w) * h);
  for (std::size_t i = 0; i < out.texels.size(); ++i)
    out.texels[i] = std::uint32_t(pixels[3 * i]) | std::uint32_t(pixels[3 * i + 1]) << 8 |
                    std::uint32_t(pixels[3 * i + 2]) << 16;
  stbi_image_free(pixels);
  return true;
}

bool decode_texture_file(const std::string& path, Texture& out, std::string& problem) {
  std::string bytes;
  try {
    bytes = read_input_file(path);
  } catch (const InputError& e) {
    problem = e.what();
    const std::string prefix = path + ": ";
    if (problem.compare(0, prefix.size(), prefix) == 0) problem = problem.substr(prefix.size());
    return false;
  }
  return decode_texture_memory(reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size(), path, out,
                               problem);
}

std::string resolve_texture_path(const std::string& written, const std::string& base_dir) {
  std::string name = written;
  for (char& c : name)
    if (c == '\\') c = '/';
  while (name.compare(0, 2, "./") == 0) name.erase(0, 2);
  // Blender's "//x.png" is x.png beside the .blend file, not /x.png.
  if (name.compare(0, 2, "//") == 0) name.erase(0, name.find_first_not_of('/'));
  const fs::path p(name);
  const fs::path base = base_dir.empty() ? fs::path(".") : fs::path(base_dir);
  const fs::path full = (p.is_absolute() ? p : base / p).lexically_normal();
  std::error_code ec;
  if (fs::is_regular_file(full, ec)) return full.string();
  // "C:/textures/wood.jpg" or a folder that did not travel with the model.
  const fs::path beside = (base / p.filename()).lexically_normal();
  if (!p.filename().empty() && fs::is_regular_file(beside, ec)) return beside.string();
  return full.string();
}

int map_of_file(const Scene& scene, const std::string& path, Texture& t) {
  struct stat st {};
  if (stat(path.c_str(), &st) == 0) t.file_device = std::uint64_t(st.st_dev), t.file_inode = std::uint64_t(st.st_ino);
  for (std::size_t i = 0; i < scene.textures.size(); ++i) {
    const Texture& known = scene.textures[i];
    if (known.path == path || known.same_file(t.file_device, t.file_inode)) return static_cast<int>(i);
  }
  return -1;
}

int add_texture_file(Scene& scene, const std::string& path, const std::string& where, MapImages images) {
  if (images == MapImages::later) return list_map_for_later(scene, path, where);
  Texture t;
  if (const int known = map_of_file(scene, path, t); known >= 0) return known;
  // An input, whether or not it decodes: no output may overwrite it.
  scene.input_files.push_back(path);
  std::string problem;
  if (!decode_texture_file(path, t, problem)) {
    scene.warnings.push_back(where + "texture map '" + path + "' ignored: " + problem);
    return -1;
  }
  scene.textures.push_back(std::move(t));
  return static_cast<int>(scene.textures.size()) - 1;
}

}  // namespace opsila
