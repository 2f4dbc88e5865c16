// Texture maps of a scene read in shares (docs/DISTRIBUTED.md): listed
// while reading, each image checked once over the ranks, and decoded only
// by the ranks whose facets use it.
#include <map>
#include <stdexcept>

#include "formats/image/texture_file.h"

namespace opsila {

namespace {

// The requests become the warnings one process gives, each in its place
// (its image was ignored), or go (its image is fine).
void resolve_requests(Scene& scene, const std::map<std::string, MapCheck*>& by_path) {
  std::vector<std::string> warnings;
  std::size_t next = 0;  // the next request
  const auto requests_before = [&](std::size_t k) {
    for (; next < scene.map_requests.size() && scene.map_requests[next].warning <= k; ++next) {
      const MapRequest& r = scene.map_requests[next];
      const MapCheck& c = *by_path.at(r.path);
      if (!c.ok) warnings.push_back(r.where + "texture map '" + r.path + "' ignored: " + c.problem);
    }
  };
  for (std::size_t k = 0; k < scene.warnings.size(); ++k) {
    requests_before(k);
    warnings.push_back(std::move(scene.warnings[k]));
  }
  requests_before(scene.warnings.size());
  scene.warnings = std::move(warnings);
  scene.map_requests.clear();
}

std::map<std::string, MapCheck*> checks_by_path(const Scene& scene, std::vector<MapCheck>& checks) {
  const std::vector<std::string> paths = maps_to_check(scene);
  if (paths.size() != checks.size()) throw std::logic_error("settle_texture_maps: one check per image");
  std::map<std::string, MapCheck*> by_path;
  for (std::size_t k = 0; k < paths.size(); ++k) by_path[paths[k]] = &checks[k];
  return by_path;
}

}  // namespace

// The map is listed once, a request stands wherever one process could warn
// about it.
int list_map_for_later(Scene& scene, const std::string& path, const std::string& where) {
  scene.map_requests.push_back(MapRequest{path, where, scene.warnings.size()});
  Texture t;
  if (const int known = map_of_file(scene, path, t); known >= 0) return known;
  scene.input_files.push_back(path);
  t.path = path;
  t.pixels_later = true;
  scene.textures.push_back(std::move(t));
  return static_cast<int>(scene.textures.size()) - 1;
}

std::vector<std::string> maps_to_check(const Scene& scene) {
  std::vector<std::string> paths;
  std::map<std::string, bool> seen;
  for (const MapRequest& r : scene.map_requests)
    if (!seen[r.path]) {
      seen[r.path] = true;
      paths.push_back(r.path);
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
  const std::map<std::string, MapCheck*> by_path = checks_by_path(scene, checks);
  resolve_requests(scene, by_path);
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

void settle_map_warnings(Scene& scene) {
  std::vector<MapCheck> checks;
  for (const std::string& path : maps_to_check(scene)) checks.push_back(check_texture_map(path));
  resolve_requests(scene, checks_by_path(scene, checks));
}

std::uint64_t decode_used_maps(Scene& scene) {
  std::vector<char> used(scene.textures.size(), 0);
  const auto mark = [&](const Triangle& t) {  // the facets bank_attributes gives texture coordinates
    if (t.attributes < 0 || !scene.attributes[std::size_t(t.attributes)].has_uv) return;
    const MaterialDesc& m = scene.materials[std::size_t(t.material)];
    for (int map : {m.map_kd, m.map_ka})
      if (map >= 0) used[std::size_t(map)] = 1;
  };
  for (const Triangle& t : scene.triangles) mark(t);
  // Every rank holds every model an instance places (the banks hold copies).
  for (const Prototype& p : scene.prototypes)
    for (const Triangle& t : p.triangles) mark(t);
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
