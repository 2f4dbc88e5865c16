// Texture images (SPEC "Texture maps"): 8-bit PNG, JPEG, TGA or BMP decoded
// with stb_image, and the path rules real model files need.
#pragma once

#include <cstddef>
#include <string>

#include "core/scene.h"

namespace opsila {

// Largest texture accepted (per side, and in texels): beyond it the map is
// ignored with a warning rather than exhausting memory.
constexpr int kMaxTextureSide = 16384;
constexpr std::size_t kMaxTextureTexels = std::size_t(1) << 26;

// Decodes an image file into `out` (path, size, packed sRGB texels). On
// failure returns false and says why in `problem` ("cannot open", "not a
// PNG/JPEG/TGA/BMP image", "too large", ...).
bool decode_texture_file(const std::string& path, Texture& out, std::string& problem);
// The same from bytes in memory (an image embedded in a model file).
bool decode_texture_memory(const unsigned char* data, std::size_t size, const std::string& name,
                           Texture& out, std::string& problem);

// Where a map statement's file is: backslashes become slashes, leading "./"
// go, and the name is taken relative to `base_dir`. If that file does not
// exist but one with the same base name sits in base_dir (a Windows path
// such as C:\models\wood.jpg), that one is used.
std::string resolve_texture_path(const std::string& written, const std::string& base_dir);

// Texture maps a scene already holds are shared: loads `path` once and
// returns its index in scene.textures, or -1 (with one warning naming
// `where`) when the image cannot be read. Either way the file is one of
// scene.input_files (no output may overwrite it).
int add_texture_file(Scene& scene, const std::string& path, const std::string& where);

}  // namespace opsila
