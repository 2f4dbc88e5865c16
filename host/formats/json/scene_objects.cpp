// The objects of the JSON scene format (scenes/FORMAT.md): each is checked
// and its triangles counted first (budget), and built only when the whole
// scene fits the limits.
#include "formats/json/scene_reader.h"

#include <cmath>

namespace opsila {

namespace fs = std::filesystem;

namespace scene_json {

// ------------------------------------------------------------ objects ---
// Counts an object's triangles (and facets, an upper bound for generated
// shapes) against the scene's limits before anything is built.
void SceneReader::budget(std::size_t triangles, std::size_t facets, std::size_t objects,
                         const std::string& path, bool windowed) {
  const std::string on_ranks = share_.ranks > 1 ? " on " + std::to_string(share_.ranks) + " ranks (" +
                                                     std::to_string(entry_limit_) + " per rank)"
                                               : std::string();
  if (triangles > max_triangles_ || planned_triangles_ > max_triangles_ - triangles)
    fail(path, "would make " + std::to_string(triangles) + " more triangles (" +
                   std::to_string(planned_triangles_) + " so far); a scene may have at most " +
                   std::to_string(max_triangles_) + on_ranks + " (scenes/FORMAT.md, Limits)" +
                   ranks_hint(triangles, windowed));
  if (triangles > entry_limit_ && !(windowed && share_.ranks > 1))  // every rank builds an entry whole
    fail(path, "would make " + std::to_string(triangles) + " triangles; one entry of objects may have at most " +
                   std::to_string(entry_limit_) + (windowed ? "" : " on any number of ranks") +
                   " (scenes/FORMAT.md, Limits)");
  if (facets > std::size_t(INT_MAX) - planned_facets_)
    fail(path, "too many facets for 32-bit ids");
  if (objects > std::size_t(INT_MAX) - planned_objects_) fail(path, "too many objects");
  planned_triangles_ += triangles;
  planned_facets_ += facets;
  planned_objects_ += objects;
}

// How many MPI ranks would take the triangles counted so far, when this
// entry can be spread over them; "" when no number of ranks would (at most
// one per PE, 1024) or the build has no MPI.
std::string SceneReader::ranks_hint(std::size_t triangles, bool windowed) const {
#ifdef OPSILA_HAVE_MPI
  const double ranks = std::ceil((double(planned_triangles_) + double(triangles)) / double(entry_limit_));
  if ((triangles > entry_limit_ && !windowed) || ranks > 1024) return "";
  const std::string r = std::to_string(static_cast<int>(ranks));
  return ": with the objects so far it needs at least " + r + " MPI ranks (mpirun -n " + r + " opsila render ...)";
#else
  (void)triangles, (void)windowed;
  return "";
#endif
}

void SceneReader::budget(std::size_t triangles, const std::string& path) {
  budget(triangles, triangles, 1, path);
}

void SceneReader::objects(const Json& v, const std::string& path) {
  expect_array(v, path);
  for (std::size_t i = 0; i < v.size(); ++i) object(v[i], join_index(path, i));
}

// Checks one object and plans its construction; builds_ runs the plans in
// order once the whole scene is known to fit.
void SceneReader::object(const Json& v, const std::string& path) {
  expect_object(v, path);
  const std::size_t planned_before = planned_triangles_;  // where this entry's triangles start in the plan
  const std::string type = string(require(v, path, "type"), join_key(path, "type"));
  const auto key = [&](const char* k) { return join_key(path, k); };
  std::function<void(std::vector<Triangle>&)> make;

  if (type == "sphere" || type == "box" || type == "polygon") {
    make = solid(v, path, type);
  } else if (type == "plane" || type == "checkerboard") {
    make = plane(v, path, type == "checkerboard");
  } else if (type == "terrain") {
    make = terrain(v, path);
  } else if (type == "scatter" || type == "grid") {
    make = generator(v, path, type == "grid");
  } else if (type == "obj" || type == "model") {
    make = include_obj(v, path, type == "model");
  } else {
    fail(key("type"), "unknown object type '" + quoted_prefix(type) +
                          "' (expected sphere, box, plane, checkerboard, polygon, terrain, "
                          "scatter, grid, obj or model)");
  }
  std::optional<Transform> placed;
  if (const Json* t = find(v, "transform")) placed = transform(*t, key("transform"));
  const std::size_t planned_after = planned_triangles_;
  builds_.push_back([this, make, placed, path, planned_before, planned_after] {
    entry_ = Entry{};
    entry_.placed = placed;
    entry_.path = path;
    entry_.first = scene_.triangles.size();
    entry_.first_attribute = scene_.attributes.size();
    entry_.planned_begin = planned_before;
    entry_.planned_end = planned_after;
    make(scene_.triangles);
    flush_entry();
    if (entry_.windowed && share_.ranks > 1) {  // this rank's window only: warned about once summed (settle_share)
      share_.window_dropped.push_back(entry_.dropped);
      window_paths_.push_back(path);
    } else {
      warn_dropped(path, entry_.dropped);
    }
  });
}

// A sphere, a box or a polygon entry: one object of one material.
std::function<void(std::vector<Triangle>&)> SceneReader::solid(const Json& v, const std::string& path,
                                                               const std::string& type) {
  const auto key = [&](const char* k) { return join_key(path, k); };
  std::function<void(std::vector<Triangle>&)> make;
  if (type == "sphere") {
    check_keys(v, path, {"type", "name", "center", "radius", "subdivisions", "material",
                         "transform"});
    const Vec3 c = vec3(require(v, path, "center"), key("center"));
    const float r = positive(require(v, path, "radius"), key("radius"));
    int sub = 3;
    if (const Json* s = find(v, "subdivisions")) sub = integer(*s, key("subdivisions"), 0, 10);
    const int mat = material_ref(find(v, "material"), key("material"));
    budget(icosphere_triangles(sub), path);
    make = [this, c, r, sub, mat](std::vector<Triangle>& tris) {
      next_facet_ = add_icosphere(tris, c, r, sub, FacetTag{next_object_++, mat}, next_facet_);
    };
  } else if (type == "box") {
    check_keys(v, path, {"type", "name", "min", "max", "center", "size", "material",
                         "transform"});
    Vec3 lo, hi;
    box_extent(v, path, lo, hi);
    const int mat = material_ref(find(v, "material"), key("material"));
    budget(12, 6, 1, path);
    make = [this, lo, hi, mat](std::vector<Triangle>& tris) {
      next_facet_ = add_box(tris, lo, hi, FacetTag{next_object_++, mat}, next_facet_);
    };
  } else {  // polygon
    check_keys(v, path, {"type", "name", "vertices", "material", "transform"});
    const Json& vs = require(v, path, "vertices");
    expect_array(vs, key("vertices"));
    if (vs.size() < 3) fail(key("vertices"), "a polygon needs at least 3 vertices");
    std::vector<Vec3> pts;
    for (std::size_t k = 0; k < vs.size(); ++k)
      pts.push_back(vec3(vs[k], join_index(key("vertices"), k)));
    const int mat = material_ref(find(v, "material"), key("material"));
    budget(pts.size() - 2, 1, 1, path);
    const std::string where_vertices = key("vertices");
    make = [this, pts, mat, where_vertices](std::vector<Triangle>& tris) {
      const std::size_t before = tris.size();
      next_facet_ = add_polygon(tris, pts, FacetTag{next_object_++, mat}, next_facet_);
      if (tris.size() == before) fail(where_vertices, "the polygon has zero area");
    };
  }
  return make;
}

// A plane, or a checkerboard of two materials.
std::function<void(std::vector<Triangle>&)> SceneReader::plane(const Json& v, const std::string& path, bool checker) {
  const auto key = [&](const char* k) { return join_key(path, k); };
  if (checker)
    check_keys(v, path, {"type", "name", "center", "size", "squares", "materials",
                         "transform"});
  else
    check_keys(v, path, {"type", "name", "center", "size", "material", "transform"});
  Vec3 c{0, 0, 0};
  if (const Json* x = find(v, "center")) c = vec3(*x, key("center"));
  float sx, sz;
  size2(require(v, path, "size"), key("size"), sx, sz);
  if (checker) {
    int nx = 8, nz = 8;
    if (const Json* s = find(v, "squares")) count2(*s, key("squares"), 100000, nx, nz);
    const std::vector<int> mats = material_list(require(v, path, "materials"), key("materials"));
    if (mats.size() != 2) fail(key("materials"), "expected exactly 2 materials");
    budget(std::size_t(2) * nx * nz, std::size_t(nx) * nz, 1, path);
    return [this, c, sx, sz, nx, nz, mats](std::vector<Triangle>& tris) {
      next_facet_ = add_checkerboard(tris, c, sx, sz, nx, nz, next_object_++, mats[0], mats[1],
                                     next_facet_);
    };
  } else {
    const int mat = material_ref(find(v, "material"), key("material"));
    budget(2, 1, 1, path);
    return [this, c, sx, sz, mat](std::vector<Triangle>& tris) {
      next_facet_ = add_plane(tris, c, sx, sz, FacetTag{next_object_++, mat}, next_facet_);
    };
  }
}

void SceneReader::warn_dropped(const std::string& path, std::size_t dropped) {
  if (dropped > 0)
    warn(path, std::to_string(dropped) + " zero-area triangle(s) left out (too small for float); facet ids kept");
}

// What the entry has made since the last flush: placed, settled and, on
// several ranks, dealt (scene_share.cpp). A generator flushes every few
// thousand items, so a rank never holds a whole generator's triangles.
void SceneReader::flush_entry() {
  auto& tris = scene_.triangles;
  const std::size_t first = entry_.first, first_attribute = entry_.first_attribute;
  if (entry_.placed) {
    transform_triangles(tris, first, *entry_.placed);
    transform_normals(scene_.attributes, first_attribute, *entry_.placed);
  }
  entry_.dropped += settle(first, entry_.path);
  if (share_.ranks > 1 && entry_.windowed)
    count_window(first);
  else if (share_.ranks > 1)
    deal(first, first_attribute);
  entry_.first = tris.size();
  entry_.first_attribute = scene_.attributes.size();
}

// After placement: zero-area triangles (possible after extreme scaling)
// are dropped, facets whose normal overflows float are refused.
std::size_t SceneReader::settle(std::size_t first, const std::string& path) {
  auto& tris = scene_.triangles;
  std::size_t keep = first, dropped = 0;
  for (std::size_t k = first; k < tris.size(); ++k) {
    const Triangle& t = tris[k];
    const float e1[3] = {t.v1[0] - t.v0[0], t.v1[1] - t.v0[1], t.v1[2] - t.v0[2]};
    const float e2[3] = {t.v2[0] - t.v0[0], t.v2[1] - t.v0[1], t.v2[2] - t.v0[2]};
    const float c[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                        e1[0] * e2[1] - e1[1] * e2[0]};
    if (!std::isfinite(c[0]) || !std::isfinite(c[1]) || !std::isfinite(c[2]))
      fail(path, "object too large: facet " + std::to_string(t.facet_id) +
                     " overflows float arithmetic");
    if (c[0] == 0 && c[1] == 0 && c[2] == 0) {
      ++dropped;
      continue;
    }
    tris[keep++] = t;
  }
  tris.resize(keep);
  return dropped;
}

void SceneReader::box_extent(const Json& v, const std::string& path, Vec3& lo, Vec3& hi) const {
  const auto key = [&](const char* k) { return join_key(path, k); };
  const Json* mn = find(v, "min");
  const Json* mx = find(v, "max");
  const Json* ce = find(v, "center");
  const Json* sz = find(v, "size");
  if ((mn || mx) && (ce || sz)) fail(path, "give either min/max or center/size, not both");
  if (mn || mx) {
    lo = vec3(require(v, path, "min"), key("min"));
    hi = vec3(require(v, path, "max"), key("max"));
    for (int a = 0; a < 3; ++a)
      if (!(hi[a] > lo[a])) fail(key("max"), "must be greater than min on every axis");
    return;
  }
  if (!ce || !sz) fail(path, "a box needs min and max, or center and size");
  const Vec3 c = vec3(*ce, key("center"));
  Vec3 s;
  if (sz->is_number()) {
    const float x = positive(*sz, key("size"));
    s = {x, x, x};
  } else if (sz->is_array() && sz->size() == 3) {
    for (int a = 0; a < 3; ++a) s[a] = positive((*sz)[a], join_index(key("size"), a));
  } else {
    fail(key("size"), std::string("expected a positive number or [x, y, z], not ") + kind(*sz));
  }
  for (int a = 0; a < 3; ++a) {
    lo[a] = static_cast<float>(double(c[a]) - 0.5 * s[a]);
    hi[a] = static_cast<float>(double(c[a]) + 0.5 * s[a]);
    if (!(hi[a] > lo[a]) || !std::isfinite(lo[a]) || !std::isfinite(hi[a]))
      fail(key("size"), "too small or too large for the box's position");
  }
}

std::function<void(std::vector<Triangle>&)> SceneReader::terrain(const Json& v, const std::string& path) {
  check_keys(v, path, {"type", "name", "center", "size", "quads", "height", "features",
                       "octaves", "seed", "material", "materials", "transform"});
  const auto key = [&](const char* k) { return join_key(path, k); };
  TerrainDesc d;
  if (const Json* x = find(v, "center")) d.center = vec3(*x, key("center"));
  size2(require(v, path, "size"), key("size"), d.size_x, d.size_z);
  count2(require(v, path, "quads"), key("quads"), 100000, d.quads_x, d.quads_z);
  if (const Json* x = find(v, "height")) d.height = real(*x, key("height"));
  if (const Json* x = find(v, "features")) {
    d.features = positive(*x, key("features"));
    if (d.features > 1e6f) fail(key("features"), "must be at most 1e6");
  }
  if (const Json* x = find(v, "octaves")) d.octaves = integer(*x, key("octaves"), 1, 16);
  if (const Json* x = find(v, "seed")) d.seed = std::uint64_t(integer(*x, key("seed"), 0, INT_MAX));
  int a = 0, b = 0;
  if (find(v, "material") && find(v, "materials"))
    fail(path, "give either material or materials, not both");
  if (const Json* m = find(v, "materials")) {
    const std::vector<int> mats = material_list(*m, key("materials"));
    if (mats.size() != 2) fail(key("materials"), "expected exactly 2 materials");
    a = mats[0];
    b = mats[1];
  } else {
    a = b = material_ref(find(v, "material"), key("material"));
  }
  const std::size_t all = terrain_triangles(d);
  budget(all, all, 1, path, true);
  return [this, d, a, b, all](std::vector<Triangle>& tris) {
    const int object = next_object_++;
    if (share_.ranks == 1) {
      next_facet_ = add_terrain(tris, d, object, a, b, next_facet_);
      return;
    }
    std::size_t begin = 0, end = 0;  // this rank's window (scene_share.cpp)
    window(all, object, begin, end);
    add_terrain_window(tris, d, object, a, b, next_facet_, begin, end);
    next_facet_ += static_cast<int>(all);
  };
}

// An OBJ file ("obj"), or a model in any format ("model": OBJ by the strict
// reader, the others through the importer). The file is read now (an OBJ's
// triangles count against the scene's limit as they are read), its
// triangles appended when the scene is built. A scene read in shares
// streams an OBJ (and a PLY or binary STL its stream reads as the importer does)
// instead: now for its counts, materials and warnings only, and again when
// it is built, keeping this rank's window (file_window()).
std::function<void(std::vector<Triangle>&)> SceneReader::include_obj(const Json& v, const std::string& path,
                                                                     bool any_format) {
  check_keys(v, path, {"type", "name", "file", "material", "transform"});
  const std::string fkey = join_key(path, "file");
  const std::string file = string(require(v, path, "file"), fkey);
  if (file.empty()) fail(fkey, "empty file name");
  if (base_dir_.empty())
    fail(fkey, "this scene is read from memory and may not name other files");
  const fs::path p(file);
  const std::string full =
      p.is_absolute() ? file : (fs::path(base_dir_) / p).lexically_normal().string();
  const int override_mat = find(v, "material")
                               ? material_ref(find(v, "material"), join_key(path, "material"))
                               : -1;
  auto sub = std::make_shared<Scene>();
  const std::string ext = lower(fs::path(full).extension().string());
  const bool obj = ext == ".obj";
  const bool streamed =
      share_.ranks > 1 && any_format && is_streamed_model(full) && model_stream_refusal(full).empty();
  const bool windowed = share_.ranks > 1 && (obj || !any_format || streamed);
  std::uint64_t fans = 0;
  try {
    if (!obj && any_format && !is_imported_model(full))
      throw InputError(full + ": not a model format the importer reads (see scenes/FORMAT.md)");
    if (windowed) {
      ModelWindow counting;  // keeps no polygon
      counting.rank = share_.rank, counting.ranks = share_.ranks, counting.map_images = share_.map_images;
      *sub = streamed ? load_model_window(full, max_triangles_ - planned_triangles_, counting, fans)
                      : load_obj_window(full, max_triangles_ - planned_triangles_, counting, fans);
    } else if (obj || !any_format) {
      *sub = load_obj(full, std::min(entry_limit_, max_triangles_ - planned_triangles_));
    } else {
      *sub = load_model(full, share_.map_images);
      sub->input_files.insert(sub->input_files.begin(), full);
    }
  } catch (const InputError& e) {
    scene_.warnings.insert(scene_.warnings.end(), e.warnings.begin(), e.warnings.end());
    fail(fkey, e.what());
  }
  budget(windowed ? sub->share.total_triangles : sub->triangles.size(), std::size_t(sub->num_facets),
         std::size_t(sub->num_objects), path, windowed);
  const int mat_offset = static_cast<int>(scene_.materials.size()) - 1;
  const int tex_offset = static_cast<int>(scene_.textures.size());
  if (override_mat < 0) {
    for (std::size_t k = 1; k < sub->materials.size(); ++k) {
      MaterialDesc m = sub->materials[k];
      if (m.map_kd >= 0) m.map_kd += tex_offset;
      if (m.map_ka >= 0) m.map_ka += tex_offset;
      scene_.materials.push_back(std::move(m));
    }
    for (Texture& t : sub->textures) scene_.textures.push_back(std::move(t));
  }
  append_warnings(scene_, *sub);
  for (std::string& f : sub->input_files) scene_.input_files.push_back(std::move(f));
  // A share does not hold an imported model from now until it is built:
  // it is read again then, and deal() keeps this rank's objects of it.
  const bool reread = share_.ranks > 1 && !windowed;
  const std::size_t model_triangles = sub->triangles.size();
  if (reread) sub->triangles = std::vector<Triangle>(), sub->attributes = std::vector<VertexAttributes>();
  return [this, sub, override_mat, mat_offset, windowed, reread, model_triangles, full, fans,
          fkey](std::vector<Triangle>& tris) {
    if (windowed) file_window(*sub, full, fans, fkey);
    if (reread) model_again(*sub, full, model_triangles, fkey);
    for (int o : sub->share.spread) share_.spread.push_back(next_object_ + o);
    const int attr_offset = static_cast<int>(scene_.attributes.size());
    for (const VertexAttributes& a : sub->attributes) scene_.attributes.push_back(a);
    for (Triangle t : sub->triangles) {
      t.object_id += next_object_;
      t.facet_id += next_facet_;
      t.material = override_mat >= 0 ? override_mat
                                     : (t.material == 0 ? 0 : t.material + mat_offset);
      if (t.attributes >= 0) t.attributes += attr_offset;
      tris.push_back(t);
    }
    next_object_ += sub->num_objects;
    next_facet_ += sub->num_facets;
    sub->triangles = std::vector<Triangle>();
    sub->attributes = std::vector<VertexAttributes>();
  };
}

}  // namespace scene_json
}  // namespace opsila
