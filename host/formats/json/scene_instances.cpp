// The "instances" entry of the JSON scene format (scenes/FORMAT.md,
// "Instances"): one model built once in its own frame (a Prototype) and
// placed by a list of transforms and a generated grid (InstanceDesc, made
// by scene/instances.h). Every rank of a scene read in shares keeps the
// model and every placement: they are built whole, never dealt.
#include <climits>
#include <memory>
#include <stdexcept>

#include "formats/json/scene_generators.h"
#include "formats/json/scene_objects.h"
#include "scene/instances.h"

namespace opsila {
namespace scene_json {

namespace {

// The "grid" of an instances entry, its keys checked.
struct PlacementGrid {
  long long items = 0;
  int counts[3] = {1, 1, 1};
  Vec3 lo, hi;
  float jitter = 0;
  float scale_lo = 1, scale_hi = 1;
  float angle_lo = 0, angle_hi = 0;
  std::uint64_t seed = 1;
};

PlacementGrid read_grid(SceneValues& values, const Json& v, const std::string& path) {
  values.expect_object(v, path);
  values.check_keys(v, path, {"counts", "min", "max", "jitter", "scale", "rotate_y", "seed"});
  const auto key = [&](const char* k) { return join_key(path, k); };
  PlacementGrid g;
  g.items = generator_items(values, v, path, true, g.counts);
  read_region(values, v, path, g.lo, g.hi);
  if (const Json* j = SceneValues::find(v, "jitter")) {
    g.jitter = values.real(*j, key("jitter"));
    if (!(g.jitter >= 0 && g.jitter <= 1)) values.fail(key("jitter"), "must be in [0, 1]");
  }
  if (const Json* s = SceneValues::find(v, "scale")) read_range(values, *s, key("scale"), true, g.scale_lo, g.scale_hi);
  if (const Json* r = SceneValues::find(v, "rotate_y")) read_range(values, *r, key("rotate_y"), false, g.angle_lo, g.angle_hi);
  if (const Json* s = SceneValues::find(v, "seed")) g.seed = std::uint64_t(values.integer(*s, key("seed"), 0, INT_MAX));
  return g;
}

// Placement n of the grid, from the next five numbers of `rng`: jitter x,
// y, z, scale, angle. translate(centre) · rotate_y(angle) · scale(s).
std::array<double, 12> grid_placement(const PlacementGrid& g, long long n, Pcg32& rng) {
  double u[3];
  for (double& x : u) x = rng.uniform();
  const double u_scale = rng.uniform(), u_angle = rng.uniform();
  double centre[3];
  grid_centre(g.counts, g.lo, g.hi, g.jitter, n, u, centre);
  const double s = g.scale_lo + (double(g.scale_hi) - g.scale_lo) * u_scale;
  const double turn[3] = {0, g.angle_lo + (double(g.angle_hi) - g.angle_lo) * u_angle, 0};
  const double scale[3] = {s, s, s};
  return transform_matrix(centre, turn, scale);
}


}  // namespace

std::function<void()> ObjectReader::instances(const Json& v, const std::string& path) {
  v_.check_keys(v, path, {"type", "name", "model", "transforms", "grid"});
  const std::string mkey = join_key(path, "model");
  const Json& m = v_.require(v, path, "model");
  v_.expect_object(m, mkey);
  const std::string type = v_.string(v_.require(m, mkey, "type"), join_key(mkey, "type"));
  if (const Json* name = v_.find(m, "name")) v_.string(*name, join_key(mkey, "name"));
  if (type == "instances") v_.fail(join_key(mkey, "type"), "instances do not nest: the model must be a shape or a model file");
  if (type == "grid" || type == "scatter")
    v_.fail(join_key(mkey, "type"), "a generator cannot be a model: it makes many objects (use a shape or a model file)");
  const std::size_t from = budget_.planned();
  Make make;
  std::optional<Transform> placed;
  {
    const ShareDealer::Whole whole(dealer_);  // every rank reads the model whole
    make = shape(m, mkey, type);
    placed = placement(m, mkey);
  }
  const Json* list = v_.find(v, "transforms");
  const Json* grid = v_.find(v, "grid");
  if (!list && !grid) v_.fail(path, "needs transforms, a grid or both (its placements)");
  if (list) v_.expect_array(*list, join_key(path, "transforms"));
  const PlacementGrid g = grid ? read_grid(v_, *grid, join_key(path, "grid")) : PlacementGrid{};
  const std::size_t count = (list ? list->size() : 0) + std::size_t(g.items);
  if (count == 0) v_.fail(join_key(path, "transforms"), "no placements: the list is empty and there is no grid");
  if (count > std::size_t(kMaxGeneratorItems))
    v_.fail(path, std::to_string(count) + " placements; an entry may have at most " +
                      std::to_string(kMaxGeneratorItems) + " (scenes/FORMAT.md, Limits)");
  budget_.hold_everywhere(from, count, path);
  // Placed now (a singular transform is refused before anything is built),
  // for the prototype this entry will make.
  const int index = prototypes_planned_++;
  auto placements = std::make_shared<std::vector<InstanceDesc>>();
  placements->reserve(count);
  for (std::size_t k = 0; list && k < list->size(); ++k) {
    const std::string tkey = join_index(join_key(path, "transforms"), k);
    placements->push_back(make_instance(index, sections_.transform((*list)[k], tkey).matrix(), v_.place(tkey)));
  }
  if (grid) {
    const std::string where = v_.place(join_key(path, "grid"));
    Pcg32 rng(g.seed);
    for (long long n = 0; n < g.items; ++n) placements->push_back(make_instance(index, grid_placement(g, n, rng), where));
  }
  std::string name = mkey;  // for messages: the model's file, if it has one
  if (const Json* f = v_.find(m, "file"); f && f->is_string()) name = f->get<std::string>();
  const std::string where = v_.place(path);
  const std::size_t listed = list ? list->size() : 0;
  return [this, make, placed, mkey, name, placements, index, where, listed] {
    scene_.prototypes.push_back(prototype(make, placed, mkey));
    scene_.prototypes.back().name = name;
    if (static_cast<int>(scene_.prototypes.size()) != index + 1) throw std::logic_error("instances: prototypes out of order");
    const std::size_t first = scene_.instances.size();
    scene_.instances.insert(scene_.instances.end(), placements->begin(), placements->end());
    placements->clear();
    placements->shrink_to_fit();
    check_placed_extent(first, where, listed);
  };
}

// The instances from `first` on, each placed box added to the scene's so
// far: the placement that takes it past the renderer's extent is named
// (a transform's index, or the grid's item), not only the file.
void ObjectReader::check_placed_extent(std::size_t first, const std::string& where, std::size_t listed) {
  for (std::size_t i = first; i < scene_.instances.size(); ++i) {
    Vec3 lo, hi;
    instance_box(scene_, scene_.instances[i], lo, hi);
    building_.lo = min(building_.lo, lo);
    building_.hi = max(building_.hi, hi);
    const std::string beyond = scene_extent_beyond(building_.lo, building_.hi);
    if (beyond.empty()) continue;
    const std::size_t k = i - first;
    throw InputError(where + (k < listed ? ".transforms[" + std::to_string(k) + "]"
                                         : ".grid: placement " + std::to_string(k - listed + 1)) +
                     ": with the model placed there, " + beyond);
  }
}

// The model built in its own frame (its transform applied there), ids from
// 0: facets in its order with their fans, object 0 for all.
Prototype ObjectReader::prototype(const Make& make, const std::optional<Transform>& placed, const std::string& path) {
  const ShareDealer::Whole whole(dealer_);
  const int next_object = building_.next_object, next_facet = building_.next_facet;
  building_.next_object = building_.next_facet = 0;
  const std::size_t first_attribute = scene_.attributes.size();
  Prototype p;
  make(p.triangles);
  if (placed) {
    transform_triangles(p.triangles, 0, *placed);
    transform_normals(scene_.attributes, first_attribute, *placed);
  }
  warn_dropped(path, settle(p.triangles, 0, path));
  p.num_facets = building_.next_facet;
  building_.next_object = next_object, building_.next_facet = next_facet;
  if (p.triangles.empty()) v_.fail(path, "the model makes no facets");
  p.lo = p.hi = p.triangles.front().v0;
  for (Triangle& t : p.triangles) {
    t.object_id = 0;
    for (const Vec3& x : {t.v0, t.v1, t.v2}) p.lo = min(p.lo, x), p.hi = max(p.hi, x);
  }
  return p;
}

}  // namespace scene_json
}  // namespace opsila
