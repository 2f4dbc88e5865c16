// Texture images (CONTRACT "Texture maps"): 8-bit PNG, JPEG, TGA or BMP decoded
// with stb_image, and the path rules real model files need.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "scene/scene.h"

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
// scene.input_files (no output may overwrite it). MapImages::later reads
// no image (list_map_for_later).
int add_texture_file(Scene& scene, const std::string& path, const std::string& where, MapImages images);

// Texture maps of a scene read in shares (docs/DISTRIBUTED.md): with
// MapImages::later, add_texture_file lists the map (path only,
// pixels_later) and a MapRequest where its warning would go, and returns
// its index. The ranks then check each image once between them
// (check_texture_map), and settle_texture_maps gives every rank the scene
// one process reads: the same warnings in the same places, the same maps
// ignored, the same texture table; only the texels wait for the ranks
// whose facets use them (decode_used_maps).
int list_map_for_later(Scene& scene, const std::string& path, const std::string& where);

// The index of the scene's map that is `path`'s file (by name, or by device
// and inode: a link or another path to it), or -1; `t` gets the file's
// device and inode for a map added next.
int map_of_file(const Scene& scene, const std::string& path, Texture& t);

// What checking one image found: its size, or why it is ignored.
struct MapCheck {
  bool ok = false;
  int width = 0, height = 0;
  std::string problem;
  std::vector<std::uint32_t> texels;  // kept only when asked
};
// The images scene.map_requests name, each once, in order.
std::vector<std::string> maps_to_check(const Scene& scene);
// Decodes the image to check it, keeping its texels only if asked.
MapCheck check_texture_map(const std::string& path, bool keep_texels = false);
// The requests become the warnings one process gives (or go); maps whose
// image failed are ignored; the table keeps the others, sizes filled in
// (and texels, where a check kept them).
// `checks[k]` is maps_to_check(scene)[k]'s.
void settle_texture_maps(Scene& scene, std::vector<MapCheck>& checks);
// A read that failed: its requests, checked here, as warnings.
void settle_map_warnings(Scene& scene);

// Decodes the maps that `scene`'s facets with texture coordinates use and
// that are not decoded yet; returns the bytes of texels it holds. Throws
// InputError naming the file if an image checked while reading no longer
// decodes.
std::uint64_t decode_used_maps(Scene& scene);

}  // namespace opsila
