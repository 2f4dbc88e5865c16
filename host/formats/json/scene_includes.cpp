// The "obj" and "model" entries of a JSON scene (scene_includes.h).
#include "formats/json/scene_includes.h"

#include <filesystem>

#include "core/input_file.h"
#include "core/last_words.h"
#include "core/util.h"
#include "formats/assimp/model_import.h"
#include "formats/assimp/model_window.h"
#include "formats/obj/obj_loader.h"

namespace opsila {

namespace fs = std::filesystem;

namespace scene_json {

ModelIncludes::Make ModelIncludes::plan(const Json& v, const std::string& path, bool any_format) {
  v_.check_keys(v, path, {"type", "name", "file", "material", "transform"});
  Reading r;
  r.fkey = join_key(path, "file");
  const std::string file = v_.string(v_.require(v, path, "file"), r.fkey);
  if (file.empty()) v_.fail(r.fkey, "empty file name");
  if (base_dir_.empty()) v_.fail(r.fkey, "this scene is read from memory and may not name other files");
  const fs::path p(file);
  r.full = p.is_absolute() ? file : (fs::path(base_dir_) / p).lexically_normal().string();
  const Json* material = SceneValues::find(v, "material");
  const int override_mat = material ? sections_.material_ref(material, join_key(path, "material")) : -1;
  auto sub = std::make_shared<Scene>();
  r.obj = lower(fs::path(r.full).extension().string()) == ".obj";
  r.streamed = dealer_.active() && any_format && is_streamed_model(r.full) && model_stream_refusal(r.full).empty();
  r.windowed = dealer_.active() && (r.obj || !any_format || r.streamed);
  std::uint64_t fans = 0;
  read(*sub, r, any_format, fans);
  budget_.add(r.windowed ? sub->share.total_triangles : sub->triangles.size(), std::size_t(sub->num_facets),
              std::size_t(sub->num_objects), path, r.windowed);
  const int mat_offset = static_cast<int>(scene_.materials.size()) - 1;
  if (override_mat < 0) {
    // The model's own materials (its first, the default, is the scene's).
    check_material_count(scene_.materials.size() + sub->materials.size() - 1, v_.where(r.fkey));
    join_materials(*sub);
  }
  append_warnings(scene_, *sub);
  for (std::string& f : sub->input_files) scene_.input_files.push_back(std::move(f));
  // A share does not hold an imported model from now until it is built:
  // it is read again then, and deal() keeps this rank's objects of it.
  const bool reread = dealer_.active() && !r.windowed;
  const std::size_t model_triangles = sub->triangles.size();
  if (reread) sub->triangles = std::vector<Triangle>(), sub->attributes = std::vector<VertexAttributes>();
  return [this, sub, override_mat, mat_offset, r, reread, model_triangles, fans](std::vector<Triangle>& tris) {
    if (r.windowed) file_window(*sub, r.full, fans, r.fkey);
    if (reread) model_again(*sub, r.full, model_triangles, r.fkey);
    int& next_object = building_.next_object;
    for (int o : sub->share.spread) dealer_.add_spread(next_object + o);
    const int attr_offset = static_cast<int>(scene_.attributes.size());
    for (const VertexAttributes& a : sub->attributes) scene_.attributes.push_back(a);
    for (Triangle t : sub->triangles) {
      t.object_id += next_object;
      t.facet_id += building_.next_facet;
      t.material = override_mat >= 0 ? override_mat : (t.material == 0 ? 0 : t.material + mat_offset);
      if (t.attributes >= 0) t.attributes += attr_offset;
      tris.push_back(t);
    }
    next_object += sub->num_objects;
    building_.next_facet += sub->num_facets;
    sub->triangles = std::vector<Triangle>();
    sub->attributes = std::vector<VertexAttributes>();
  };
}

// The file read now: an OBJ's triangles count against the scene's limit
// as they are read; a stream's first read (several ranks) keeps no polygon,
// only the counts, materials and warnings.
void ModelIncludes::read(Scene& sub, const Reading& r, bool any_format, std::uint64_t& fans) {
  const MapImages images = dealer_.share().map_images;
  const LastWordsPlace place(v_.where(r.fkey));  // for a fault inside the importer
  try {
    if (!r.obj && any_format && !is_imported_model(r.full))
      throw InputError(r.full + ": not a model format the importer reads (see scenes/FORMAT.md)");
    if (r.windowed) {
      ModelWindow counting;  // keeps no polygon
      counting.rank = dealer_.share().rank, counting.ranks = dealer_.share().ranks, counting.map_images = images;
      sub = r.streamed ? load_model_window(r.full, budget_.left(), counting, fans)
                       : load_obj_window(r.full, budget_.left(), counting, fans);
    } else if (r.obj || !any_format) {
      sub = load_obj(r.full, std::min(budget_.entry_limit(), budget_.left()));
    } else {
      sub = load_model(r.full, images);
      sub.input_files.insert(sub.input_files.begin(), r.full);
    }
  } catch (const InputError& e) {
    scene_.warnings.insert(scene_.warnings.end(), e.warnings.begin(), e.warnings.end());
    v_.fail(r.fkey, e.what() + budget_.beyond(e));
  }
}

// The model's own materials and maps after the scene's (its material 0,
// the default, is the scene's). A map an earlier include holds (the same
// file, by any name) is not joined again: twelve includes of a model
// with a map of 8192 x 8192 held twelve copies of its 256 MiB of texels.
void ModelIncludes::join_materials(Scene& sub) {
  std::vector<int> at(sub.textures.size());
  for (std::size_t k = 0; k < sub.textures.size(); ++k) {
    Texture& t = sub.textures[k];
    const std::string file = t.file_inode ? std::to_string(t.file_device) + ":" + std::to_string(t.file_inode) : t.path;
    const std::string key = file + (t.pixels_later ? "\n(later)" : "");
    const auto [it, added] = texture_at_.emplace(key, static_cast<int>(scene_.textures.size()));
    if (added) scene_.textures.push_back(std::move(t));
    at[k] = it->second;
  }
  std::vector<Texture>().swap(sub.textures);  // the model's triangles wait in `sub` until built: not its maps
  for (std::size_t k = 1; k < sub.materials.size(); ++k) {
    MaterialDesc m = sub.materials[k];
    if (m.map_kd >= 0) m.map_kd = at[std::size_t(m.map_kd)];
    if (m.map_ka >= 0) m.map_ka = at[std::size_t(m.map_ka)];
    scene_.materials.push_back(std::move(m));
  }
}

// An OBJ entry (or a PLY or STL model its stream reads) read as a stream
// again, keeping this rank's window (ShareDealer::file_window). The file's
// objects that fall in several slices are spread.
void ModelIncludes::file_window(Scene& sub, const std::string& file, std::uint64_t fans, const std::string& fkey) {
  const ModelWindow w = dealer_.file_window(building_.entry.share, budget_.planned(), fans);
  try {
    const FileReadStamp stamp(file);
    std::uint64_t again = 0;
    Scene part = is_streamed_model(file) ? load_model_window(file, budget_.most(), w, again)
                                         : load_obj_window(file, budget_.most(), w, again);
    if (again != fans) throw InputError(file + ": the file changed while it was read (its polygons)");
    dealer_.add_read(file, stamp.after(again, part.share.total_triangles, std::uint64_t(part.num_facets)));
    sub.triangles = std::move(part.triangles);
    sub.attributes = std::move(part.attributes);
    sub.share.spread = std::move(part.share.spread);
  } catch (const InputError& e) {  // the file changed since it was first read
    v_.fail(fkey, e.what() + budget_.beyond(e));
  }
}

// An imported model of a share, read again when its entry is built (the
// plan kept only its counts, materials and maps): its triangles and
// attributes, which must be those the plan counted.
void ModelIncludes::model_again(Scene& sub, const std::string& file, std::size_t triangles, const std::string& fkey) {
  Scene again;
  const LastWordsPlace place(v_.where(fkey));
  try {
    again = load_model(file, dealer_.share().map_images);
  } catch (const InputError& e) {
    v_.fail(fkey, e.what());
  }
  if (again.triangles.size() != triangles)
    v_.fail(fkey, file + ": the file changed while the scene was read (" + std::to_string(triangles) +
                      " triangles, then " + std::to_string(again.triangles.size()) + ")");
  sub.triangles = std::move(again.triangles);
  sub.attributes = std::move(again.attributes);
}

}  // namespace scene_json
}  // namespace opsila
