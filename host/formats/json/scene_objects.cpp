// The objects of the JSON scene format (scene_objects.h): each is checked
// and its triangles counted first (TriangleBudget), and built only when the
// whole scene fits the limits.
#include "formats/json/scene_objects.h"

#include <climits>
#include <cmath>

#include "formats/json/scene_generators.h"
#include "opsila_shared.h"

namespace opsila {
namespace scene_json {

void ObjectReader::read(const Json& v, const std::string& path) {
  v_.expect_array(v, path);
  for (std::size_t i = 0; i < v.size(); ++i) object(v[i], join_index(path, i));
}

void ObjectReader::build() {
  if (!dealer_.active()) reserve_more(scene_.triangles, budget_.planned());  // a share grows as it is dealt
  for (const auto& build : builds_) build();
  scene_.num_objects = building_.next_object;
  scene_.num_facets = building_.next_facet;
  if (!dealer_.active()) return;
  dealer_.add_instances(scene_);
  dealer_.finish(scene_, [this](const std::string& path, std::size_t dropped) { warn_dropped(path, dropped); });
}

// Checks one object and plans its construction; builds_ runs the plans in
// order once the whole scene is known to fit.
void ObjectReader::object(const Json& v, const std::string& path) {
  v_.expect_object(v, path);
  const std::size_t planned_before = budget_.planned();  // where this entry's triangles start in the plan
  const std::string type = v_.string(v_.require(v, path, "type"), join_key(path, "type"));
  if (const Json* name = v_.find(v, "name")) v_.string(*name, join_key(path, "name"));  // a label, but a string
  if (type == "instances") {
    builds_.push_back(instances(v, path));
    return;
  }
  const Make make = type == "scatter" || type == "grid" ? generator(v, path, type == "grid") : shape(v, path, type);
  const std::optional<Transform> placed = placement(v, path);
  const std::size_t planned_after = budget_.planned();
  builds_.push_back([this, make, placed, path, planned_before, planned_after] {
    Entry& entry = building_.entry;
    entry = Entry{};
    entry.placed = placed;
    entry.path = path;
    entry.first = scene_.triangles.size();
    entry.first_attribute = scene_.attributes.size();
    entry.share.planned_begin = planned_before;
    entry.share.planned_end = planned_after;
    make(scene_.triangles);
    flush_entry();
    if (entry.share.windowed && dealer_.active())  // this rank's window only: warned about once summed
      dealer_.add_window_dropped(path, entry.dropped);
    else
      warn_dropped(path, entry.dropped);
  });
}

// An entry that makes the facets of one object or of one model's objects:
// any type but the generators and instances.
ObjectReader::Make ObjectReader::shape(const Json& v, const std::string& path, const std::string& type) {
  if (type == "sphere" || type == "box" || type == "polygon") return solid(v, path, type);
  if (type == "plane" || type == "checkerboard") return plane(v, path, type == "checkerboard");
  if (type == "terrain") return terrain(v, path);
  if (type == "obj" || type == "model") return includes_.plan(v, path, type == "model");
  v_.fail(join_key(path, "type"), "unknown object type '" + quoted_prefix(type) +
                                      "' (expected sphere, box, plane, checkerboard, polygon, terrain, "
                                      "scatter, grid, obj, model or instances)");
}

std::optional<Transform> ObjectReader::placement(const Json& v, const std::string& path) {
  if (const Json* t = v_.find(v, "transform")) return sections_.transform(*t, join_key(path, "transform"));
  return std::nullopt;
}

// A sphere, a box or a polygon entry: one object of one material.
ObjectReader::Make ObjectReader::solid(const Json& v, const std::string& path, const std::string& type) {
  const auto key = [&](const char* k) { return join_key(path, k); };
  Make make;
  if (type == "sphere") {
    v_.check_keys(v, path, {"type", "name", "center", "radius", "subdivisions", "material",
                         "transform"});
    const Vec3 c = v_.vec3(v_.require(v, path, "center"), key("center"));
    const float r = v_.positive(v_.require(v, path, "radius"), key("radius"));
    int sub = 3;
    if (const Json* s = v_.find(v, "subdivisions")) sub = v_.integer(*s, key("subdivisions"), 0, 10);
    const int mat = sections_.material_ref(v_.find(v, "material"), key("material"));
    budget_.add(icosphere_triangles(sub), path);
    make = [this, c, r, sub, mat](std::vector<Triangle>& tris) {
      building_.next_facet = add_icosphere(tris, c, r, sub, FacetTag{building_.next_object++, mat}, building_.next_facet);
    };
  } else if (type == "box") {
    v_.check_keys(v, path, {"type", "name", "min", "max", "center", "size", "material",
                         "transform"});
    Vec3 lo, hi;
    box_extent(v, path, lo, hi);
    const int mat = sections_.material_ref(v_.find(v, "material"), key("material"));
    budget_.add(12, 6, 1, path);
    make = [this, lo, hi, mat](std::vector<Triangle>& tris) {
      building_.next_facet = add_box(tris, lo, hi, FacetTag{building_.next_object++, mat}, building_.next_facet);
    };
  } else {  // polygon
    v_.check_keys(v, path, {"type", "name", "vertices", "material", "transform"});
    const Json& vs = v_.require(v, path, "vertices");
    v_.expect_array(vs, key("vertices"));
    if (vs.size() < 3) v_.fail(key("vertices"), "a polygon needs at least 3 vertices");
    if (vs.size() - 2 > OPSILA_MAX_FAN) check_fan_triangles(static_cast<long long>(vs.size()) - 2, v_.where(key("vertices")));
    std::vector<Vec3> pts;
    for (std::size_t k = 0; k < vs.size(); ++k)
      pts.push_back(v_.vec3(vs[k], join_index(key("vertices"), k)));
    const int mat = sections_.material_ref(v_.find(v, "material"), key("material"));
    budget_.add(pts.size() - 2, 1, 1, path);
    const std::string where_vertices = key("vertices");
    make = [this, pts, mat, where_vertices](std::vector<Triangle>& tris) {
      const std::size_t before = tris.size();
      building_.next_facet = add_polygon(tris, pts, FacetTag{building_.next_object++, mat}, building_.next_facet);
      // A degenerate facet, as in an OBJ (CONTRACT "Fan triangulation"):
      // not drawn, its id kept, one warning.
      if (tris.size() == before) v_.warn(where_vertices, "the polygon has zero area: not drawn; its facet id is kept");
    };
  }
  return make;
}

// A plane, or a checkerboard of two materials.
ObjectReader::Make ObjectReader::plane(const Json& v, const std::string& path, bool checker) {
  const auto key = [&](const char* k) { return join_key(path, k); };
  if (checker)
    v_.check_keys(v, path, {"type", "name", "center", "size", "squares", "materials",
                         "transform"});
  else
    v_.check_keys(v, path, {"type", "name", "center", "size", "material", "transform"});
  Vec3 c{0, 0, 0};
  if (const Json* x = v_.find(v, "center")) c = v_.vec3(*x, key("center"));
  float sx, sz;
  v_.size2(v_.require(v, path, "size"), key("size"), sx, sz);
  if (checker) {
    int nx = 8, nz = 8;
    if (const Json* s = v_.find(v, "squares")) v_.count2(*s, key("squares"), 100000, nx, nz);
    const std::vector<int> mats = sections_.material_list(v_.require(v, path, "materials"), key("materials"));
    if (mats.size() != 2) v_.fail(key("materials"), "expected exactly 2 materials");
    budget_.add(std::size_t(2) * nx * nz, std::size_t(nx) * nz, 1, path);
    return [this, c, sx, sz, nx, nz, mats](std::vector<Triangle>& tris) {
      building_.next_facet = add_checkerboard(tris, c, sx, sz, nx, nz, building_.next_object++, mats[0], mats[1],
                                     building_.next_facet);
    };
  } else {
    const int mat = sections_.material_ref(v_.find(v, "material"), key("material"));
    budget_.add(2, 1, 1, path);
    return [this, c, sx, sz, mat](std::vector<Triangle>& tris) {
      building_.next_facet = add_plane(tris, c, sx, sz, FacetTag{building_.next_object++, mat}, building_.next_facet);
    };
  }
}

void ObjectReader::warn_dropped(const std::string& path, std::size_t dropped) {
  if (dropped > 0)
    v_.warn(path, std::to_string(dropped) + " zero-area triangle(s) left out (too small for float); facet ids kept");
}

// What the entry has made since the last flush: placed, settled and, on
// several ranks, dealt (scene_share.cpp). A generator flushes every few
// thousand items, so a rank never holds a whole generator's triangles.
void ObjectReader::flush_entry() {
  auto& tris = scene_.triangles;
  Entry& entry = building_.entry;
  const std::size_t first = entry.first, first_attribute = entry.first_attribute;
  if (entry.placed) {
    transform_triangles(tris, first, *entry.placed);
    transform_normals(scene_.attributes, first_attribute, *entry.placed);
  }
  entry.dropped += settle(tris, first, entry.path);
  for (std::size_t k = first; k < tris.size(); ++k)
    for (const Vec3& v : {tris[k].v0, tris[k].v1, tris[k].v2}) {
      building_.lo = min(building_.lo, v);
      building_.hi = max(building_.hi, v);
    }
  if (tris.size() > first)
    if (const std::string beyond = scene_extent_beyond(building_.lo, building_.hi); !beyond.empty())
      v_.fail(entry.path, beyond);
  if (dealer_.active() && entry.share.windowed)
    dealer_.count_window(scene_, first);
  else if (dealer_.active())
    dealer_.deal(scene_, entry.share, first, first_attribute, budget_.planned());
  entry.first = tris.size();
  entry.first_attribute = scene_.attributes.size();
}

// After placement: zero-area triangles (possible after extreme scaling)
// are dropped, facets whose normal overflows float are refused.
std::size_t ObjectReader::settle(std::vector<Triangle>& tris, std::size_t first, const std::string& path) {
  std::size_t keep = first, dropped = 0;
  for (std::size_t k = first; k < tris.size(); ++k) {
    const Triangle& t = tris[k];
    const float e1[3] = {t.v1[0] - t.v0[0], t.v1[1] - t.v0[1], t.v1[2] - t.v0[2]};
    const float e2[3] = {t.v2[0] - t.v0[0], t.v2[1] - t.v0[1], t.v2[2] - t.v0[2]};
    const float c[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                        e1[0] * e2[1] - e1[1] * e2[0]};
    if (!std::isfinite(c[0]) || !std::isfinite(c[1]) || !std::isfinite(c[2]))
      v_.fail(path, "object too large: facet " + std::to_string(t.facet_id) +
                     " overflows float arithmetic");
    if (c[0] == 0 && c[1] == 0 && c[2] == 0) {
      ++dropped;
      continue;
    }
    if (keep != k) tris[keep] = t;  // nothing dropped yet: each in place already
    ++keep;
  }
  tris.resize(keep);
  return dropped;
}

void ObjectReader::box_extent(const Json& v, const std::string& path, Vec3& lo, Vec3& hi) const {
  const auto key = [&](const char* k) { return join_key(path, k); };
  const Json* mn = v_.find(v, "min");
  const Json* mx = v_.find(v, "max");
  const Json* ce = v_.find(v, "center");
  const Json* sz = v_.find(v, "size");
  if ((mn || mx) && (ce || sz)) v_.fail(path, "give either min/max or center/size, not both");
  if (mn || mx) {
    lo = v_.vec3(v_.require(v, path, "min"), key("min"));
    hi = v_.vec3(v_.require(v, path, "max"), key("max"));
    for (int a = 0; a < 3; ++a)
      if (!(hi[a] > lo[a])) v_.fail(key("max"), "must be greater than min on every axis");
    return;
  }
  if (!ce || !sz) v_.fail(path, "a box needs min and max, or center and size");
  const Vec3 c = v_.vec3(*ce, key("center"));
  Vec3 s;
  if (sz->is_number()) {
    const float x = v_.positive(*sz, key("size"));
    s = {x, x, x};
  } else if (sz->is_array() && sz->size() == 3) {
    for (int a = 0; a < 3; ++a) s[a] = v_.positive((*sz)[a], join_index(key("size"), a));
  } else {
    v_.fail(key("size"), std::string("expected a positive number or [x, y, z], not ") + kind(*sz));
  }
  for (int a = 0; a < 3; ++a) {
    lo[a] = static_cast<float>(double(c[a]) - 0.5 * s[a]);
    hi[a] = static_cast<float>(double(c[a]) + 0.5 * s[a]);
    if (!(hi[a] > lo[a]) || !std::isfinite(lo[a]) || !std::isfinite(hi[a]))
      v_.fail(key("size"), "too small or too large for the box's position");
  }
}

ObjectReader::Make ObjectReader::terrain(const Json& v, const std::string& path) {
  v_.check_keys(v, path, {"type", "name", "center", "size", "quads", "height", "features",
                       "octaves", "seed", "material", "materials", "transform"});
  const auto key = [&](const char* k) { return join_key(path, k); };
  TerrainDesc d;
  if (const Json* x = v_.find(v, "center")) d.center = v_.vec3(*x, key("center"));
  v_.size2(v_.require(v, path, "size"), key("size"), d.size_x, d.size_z);
  v_.count2(v_.require(v, path, "quads"), key("quads"), 100000, d.quads_x, d.quads_z);
  if (const Json* x = v_.find(v, "height")) d.height = v_.real(*x, key("height"));
  if (const Json* x = v_.find(v, "features")) {
    d.features = v_.positive(*x, key("features"));
    if (d.features > 1e6f) v_.fail(key("features"), "must be at most 1e6");
  }
  if (const Json* x = v_.find(v, "octaves")) d.octaves = v_.integer(*x, key("octaves"), 1, 16);
  if (const Json* x = v_.find(v, "seed")) d.seed = std::uint64_t(v_.integer(*x, key("seed"), 0, INT_MAX));
  int a = 0, b = 0;
  if (v_.find(v, "material") && v_.find(v, "materials"))
    v_.fail(path, "give either material or materials, not both");
  if (const Json* m = v_.find(v, "materials")) {
    const std::vector<int> mats = sections_.material_list(*m, key("materials"));
    if (mats.size() != 2) v_.fail(key("materials"), "expected exactly 2 materials");
    a = mats[0];
    b = mats[1];
  } else {
    a = b = sections_.material_ref(v_.find(v, "material"), key("material"));
  }
  const std::size_t all = terrain_triangles(d);
  budget_.add(all, all, 1, path, true);
  return [this, d, a, b, all](std::vector<Triangle>& tris) {
    const int object = building_.next_object++;
    if (!dealer_.active()) {
      building_.next_facet = add_terrain(tris, d, object, a, b, building_.next_facet);
      return;
    }
    std::size_t begin = 0, end = 0;  // this rank's window (scene_share.cpp)
    dealer_.window(building_.entry.share, all, object, budget_.planned(), begin, end);
    add_terrain_window(tris, d, object, a, b, building_.next_facet, begin, end);
    building_.next_facet += static_cast<int>(all);
  };
}

// Many spheres or boxes (scene_generators.h). On several ranks each item is
// dealt whole as it is made (a few thousand at a time): the entry is
// limited by the scene, an item by one rank.
ObjectReader::Make ObjectReader::generator(const Json& v, const std::string& path, bool grid) {
  const Generator g = read_generator(v_, sections_, v, path, grid);
  const std::size_t items = std::size_t(g.items);
  if (g.per_item > 0 && items > budget_.most() / g.per_item)
    v_.fail(path, std::to_string(items) + " items would make more than " + std::to_string(budget_.most()) +
                      " triangles (scenes/FORMAT.md, Limits)");
  budget_.add(items * g.per_item, items * g.per_item, items, path, g.per_item <= budget_.entry_limit());
  return [this, g](std::vector<Triangle>& tris) {
    if (dealer_.active()) building_.entry.share.expected = generator_triangles(g);  // for dealing them evenly
    make_items(g, tris, building_.next_object, building_.next_facet, [this] { flush_entry(); });
  };
}

}  // namespace scene_json
}  // namespace opsila
