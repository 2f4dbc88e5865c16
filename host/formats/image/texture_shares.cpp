// Texture maps of a scene read in shares (docs/DISTRIBUTED.md): listed
// while reading, each image checked once over the ranks, and decoded only
// by the ranks whose facets use it.
#include <map>
#include <stdexcept>

#include "formats/image/texture_file.h"

namespace opsila {

namespace {

bool maps_later = false;  // a MapsDecidedLater is alive (scenes are read on one thread)

// A placeholder warning: a mark, then where the map was named, a NUL and the
// image's path (neither holds a NUL).
constexpr char kMark = '\x01';
bool is_placeholder(const std::string& w) { return !w.empty() && w[0] == kMark; }
std::string placeholder_path(const std::string& w) { return w.substr(w.find('\0') + 1); }
std::string placeholder_where(const std::string& w) { return w.substr(1, w.find('\0') - 1); }

// Each placeholder becomes the warning one process gives (its image was
// ignored) or goes (its image is fine).
void resolve_placeholders(std::vector<std::string>& warnings, const std::map<std::string, MapCheck*>& by_path) {
  std::vector<std::string> kept;
  for (std::string& w : warnings) {
    if (!is_placeholder(w)) {
      kept.push_back(std::move(w));
      continue;
    }
    const std::string path = placeholder_path(w);
    const MapCheck& c = *by_path.at(path);
    if (!c.ok) kept.push_back(placeholder_where(w) + "texture map '" + path + "' ignored: " + c.problem);
  }
  warnings = std::move(kept);
}

std::map<std::string, MapCheck*> checks_by_path(const std::vector<std::string>& warnings,
                                                std::vector<MapCheck>& checks) {
  const std::vector<std::string> paths = maps_to_check(warnings);
  if (paths.size() != checks.size()) throw std::logic_error("settle_texture_maps: one check per image");
  std::map<std::string, MapCheck*> by_path;
  for (std::size_t k = 0; k < paths.size(); ++k) by_path[paths[k]] = &checks[k];
  return by_path;
}

}  // namespace

MapsDecidedLater::MapsDecidedLater(bool active) { maps_later = active; }
MapsDecidedLater::~MapsDecidedLater() { maps_later = false; }

// add_texture_file's part while maps are decided later: the map is listed
// once, a placeholder stands wherever one process could warn about it.
bool list_map_for_later(Scene& scene, const std::string& path, const std::string& where, int& index) {
  if (!maps_later) return false;
  scene.warnings.push_back(std::string(1, kMark) + where + '\0' + path);
  for (std::size_t i = 0; i < scene.textures.size(); ++i)
    if (scene.textures[i].path == path) return index = static_cast<int>(i), true;
  scene.input_files.push_back(path);
  Texture t;
  t.path = path;
  t.pixels_later = true;
  scene.textures.push_back(std::move(t));
  index = static_cast<int>(scene.textures.size()) - 1;
  return true;
}

std::vector<std::string> maps_to_check(const std::vector<std::string>& warnings) {
  std::vector<std::string> paths;
  std::map<std::string, bool> seen;
  for (const std::string& w : warnings)
    if (is_placeholder(w) && !seen[placeholder_path(w)]) {
      seen[placeholder_path(w)] = true;
      paths.push_back(placeholder_path(w));
    }
  return paths;
}

MapCheck check_texture_map(const std::string& path, bool keep_texels) {
  MapCheck c;
  Texture t;
  c.ok = decode_texture_file(path, t, c.problem);
  c.width = t.width, c.height = t.height;
  if (keep_texels) c.texels = std::move(t.texels);
  return c;
}

void settle_texture_maps(Scene& scene, std::vector<MapCheck>& checks) {
  const std::map<std::string, MapCheck*> by_path = checks_by_path(scene.warnings, checks);
  resolve_placeholders(scene.warnings, by_path);
  // The table one process builds: an image that failed is not in it.
  std::vector<int> index(scene.textures.size(), -1);
  std::vector<Texture> table;
  std::map<std::string, int> uses;  // entries of a path (two included files may name one image)
  for (const Texture& t : scene.textures) uses[t.path] += t.pixels_later;
  for (std::size_t i = 0; i < scene.textures.size(); ++i) {
    Texture& t = scene.textures[i];
    if (t.pixels_later) {
      MapCheck& c = *by_path.at(t.path);
      if (!c.ok) continue;
      t.width = c.width, t.height = c.height;
      if (!c.texels.empty()) {  // kept by the check: the last entry of its path takes them
        t.texels = --uses[t.path] == 0 ? std::move(c.texels) : c.texels;
        t.pixels_later = false;
      }
    }
    index[i] = static_cast<int>(table.size());
    table.push_back(std::move(t));
  }
  scene.textures = std::move(table);
  for (MaterialDesc& m : scene.materials)
    for (int* map : {&m.map_kd, &m.map_ka})
      if (*map >= 0) *map = index[std::size_t(*map)];
}

void settle_map_warnings(std::vector<std::string>& warnings) {
  std::vector<MapCheck> checks;
  for (const std::string& path : maps_to_check(warnings)) checks.push_back(check_texture_map(path));
  resolve_placeholders(warnings, checks_by_path(warnings, checks));
}

std::uint64_t decode_used_maps(Scene& scene) {
  std::vector<char> used(scene.textures.size(), 0);
  for (const Triangle& t : scene.triangles) {  // the facets bank_attributes gives texture coordinates
    if (t.attributes < 0 || !scene.attributes[std::size_t(t.attributes)].has_uv) continue;
    const MaterialDesc& m = scene.materials[std::size_t(t.material)];
    for (int map : {m.map_kd, m.map_ka})
      if (map >= 0) used[std::size_t(map)] = 1;
  }
  std::uint64_t bytes = 0;
  for (std::size_t k = 0; k < scene.textures.size(); ++k) {
    Texture& t = scene.textures[k];
    if (used[k] && t.pixels_later && t.texels.empty()) {
      Texture image;
      std::string problem;
      if (!decode_texture_file(t.path, image, problem) || image.width != t.width || image.height != t.height)
        throw InputError(t.path + ": texture map changed while the scene was read" +
                         (problem.empty() ? std::string() : " (" + problem + ")"));
      t.texels = std::move(image.texels);
    }
    bytes += t.texels.size() * sizeof(std::uint32_t);
  }
  return bytes;
}

}  // namespace opsila
