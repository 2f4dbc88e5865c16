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
#include "formats/image/image_checks.h"

namespace opsila {

namespace fs = std::filesystem;

namespace {

// Texel i of stb's 8-bit RGB pixels, packed as Texture holds it.
std::uint32_t texel_at(const unsigned char* rgb, std::size_t i) {
  return std::uint32_t(rgb[3 * i]) | std::uint32_t(rgb[3 * i + 1]) << 8 | std::uint32_t(rgb[3 * i + 2]) << 16;
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
  const bool png = is_png(data, size);
  if (std::string why = png_crc_problem(data, size); !why.empty()) {
    problem = why;
    return false;
  }
  if (std::string why = png_side_problem(data, size, kMaxTextureSide); !why.empty()) {
    problem = why;
    return false;
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
  std::string why = short_bmp_or_tga(data, size, aw, ah);
  if (why.empty()) why = jpeg_problem(data, size, aw, ah);
  PaddedPalette palette;
  if (why.empty() && png) why = pad_png_palette(data, size, palette);
  if (!why.empty() || palette.bytes.size() > static_cast<std::size_t>(std::numeric_limits<int>::max())) {
    problem = "cannot decode the image (" + (why.empty() ? std::string("image file too large") : why) + ")";
    return false;
  }
  if (stbi_is_16_bit_from_memory(data, len)) {
    problem = "16-bit images are not supported (8 bits per channel)";
    return false;
  }
  const bool padded = !palette.bytes.empty();
  unsigned char* pixels =
      padded ? stbi_load_from_memory(reinterpret_cast<const unsigned char*>(palette.bytes.data()),
                                     static_cast<int>(palette.bytes.size()), &w, &h, &channels, 3)
             : stbi_load_from_memory(data, len, &w, &h, &channels, 3);
  if (!pixels) {
    const char* why = stbi_failure_reason();
    problem = std::string("cannot decode the image") + (why ? std::string(" (") + why + ")" : "");
    // stb names the chunk it could not read, not the truncation.
    static const char kIend[4] = {'I', 'E', 'N', 'D'};
    if (png && std::search(data, data + size, kIend, kIend + 4) == data + size)
      problem = "cannot decode the image (truncated PNG: it ends before its IEND chunk)";
    return false;
  }
  const std::size_t texels = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
  std::size_t past = padded ? 0 : texels;
  while (past < texels && texel_at(pixels, past) != palette.sentinel) ++past;
  if (past < texels) {
    stbi_image_free(pixels);
    problem = "cannot decode the image (a pixel indexes past the PNG palette of " + std::to_string(palette.entries) + ")";
    return false;
  }
  out.path = name;
  out.width = w;
  out.height = h;
  out.texels.resize(texels);
  for (std::size_t i = 0; i < texels; ++i) out.texels[i] = texel_at(pixels, i);
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
