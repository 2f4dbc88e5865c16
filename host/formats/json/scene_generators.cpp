// The generators of the JSON scene format (scenes/FORMAT.md, "grid" and
// "scatter"): their keys checked and counted, then their items made.
#include "formats/json/scene_reader.h"

namespace opsila {
namespace scene_json {

// A generator's item count: `count`, or the product of `counts` (grid).
long long SceneReader::generator_items(const Json& v, const std::string& path, bool grid, int counts[3]) {
  const auto key = [&](const char* k) { return join_key(path, k); };
  const int kMaxItems = kMaxGeneratorItems;
  if (!grid) return integer(require(v, path, "count"), key("count"), 1, kMaxItems);
  const Json& c = require(v, path, "counts");
  if (c.is_number()) {
    counts[0] = counts[1] = counts[2] = integer(c, key("counts"), 1, 1000);
  } else if (c.is_array() && c.size() == 3) {
    for (int a = 0; a < 3; ++a) counts[a] = integer(c[a], join_index(key("counts"), a), 1, 100000);
  } else {
    fail(key("counts"), std::string("expected an integer or [nx, ny, nz], not ") + kind(c));
  }
  const long long items = 1LL * counts[0] * counts[1] * counts[2];
  if (items > kMaxItems) fail(key("counts"), "more than " + std::to_string(kMaxItems) + " items");
  return items;
}

// The running sums of a generator's material weights (equal when left
// out); returns their total.
double SceneReader::material_weights(const Json& v, const std::string& path, std::size_t materials,
                                     std::vector<double>& cumulative) {
  const auto key = [&](const char* k) { return join_key(path, k); };
  double total = 0;
  const Json* w = find(v, "weights");
  if (!w) {
    for (std::size_t k = 0; k < materials; ++k) cumulative.push_back(total += 1.0);
    return total;
  }
  expect_array(*w, key("weights"));
  if (w->size() != materials)
    fail(key("weights"), "needs one weight per material (" + std::to_string(materials) + ")");
  for (std::size_t k = 0; k < w->size(); ++k) {
    const double x = number((*w)[k], join_index(key("weights"), k));
    if (x < 0) fail(join_index(key("weights"), k), "must not be negative");
    total += x;
    cumulative.push_back(total);
  }
  if (!(total > 0)) fail(key("weights"), "must not all be zero");
  return total;
}

// Many spheres/boxes, each its own object, from a fixed-seed PCG32. Per item
// seven numbers are drawn in a fixed order: shape, radius, x, y, z,
// material, angle (see FORMAT.md), so a scene is the same everywhere.
std::function<void(std::vector<Triangle>&)> SceneReader::generator(const Json& v, const std::string& path,
                                                                   bool grid) {
  if (grid)
    check_keys(v, path, {"type", "name", "counts", "min", "max", "jitter", "shapes", "radius",
                         "subdivisions", "materials", "weights", "seed", "transform"});
  else
    check_keys(v, path, {"type", "name", "count", "min", "max", "shapes", "radius",
                         "subdivisions", "materials", "weights", "seed", "transform"});
  const auto key = [&](const char* k) { return join_key(path, k); };
  const Vec3 lo = vec3(require(v, path, "min"), key("min"));
  const Vec3 hi = vec3(require(v, path, "max"), key("max"));
  for (int a = 0; a < 3; ++a)
    if (!(hi[a] >= lo[a])) fail(key("max"), "must not be less than min on any axis");
  int counts[3] = {1, 1, 1};
  const long long items = generator_items(v, path, grid, counts);
  float jitter = 0;
  if (const Json* j = find(v, "jitter")) {
    jitter = real(*j, key("jitter"));
    if (!(jitter >= 0 && jitter <= 1)) fail(key("jitter"), "must be in [0, 1]");
  }
  bool want_sphere = true, want_box = false;
  std::vector<bool> shape_is_box{false};
  if (const Json* s = find(v, "shapes")) {
    expect_array(*s, key("shapes"));
    if (s->empty()) fail(key("shapes"), "needs at least one shape");
    shape_is_box.clear();
    want_sphere = false;
    for (std::size_t k = 0; k < s->size(); ++k) {
      const std::string n = string((*s)[k], join_index(key("shapes"), k));
      if (n != "sphere" && n != "box")
        fail(join_index(key("shapes"), k), "unknown shape '" + n + "' (expected sphere or box)");
      shape_is_box.push_back(n == "box");
      want_sphere = want_sphere || n == "sphere";
      want_box = want_box || n == "box";
    }
  }
  float rmin = 0.5f, rmax = 0.5f;
  if (const Json* r = find(v, "radius")) {
    if (r->is_array() && r->size() == 2) {
      rmin = positive((*r)[0], join_index(key("radius"), 0));
      rmax = positive((*r)[1], join_index(key("radius"), 1));
      if (rmax < rmin) fail(key("radius"), "[min, max] with max < min");
    } else {
      rmin = rmax = positive(*r, key("radius"));
    }
  }
  int sub = 2;
  if (const Json* s = find(v, "subdivisions")) sub = integer(*s, key("subdivisions"), 0, 10);
  std::vector<int> mats{0};
  if (const Json* m = find(v, "materials")) mats = material_list(*m, key("materials"));
  std::vector<double> cumulative;
  const double total = material_weights(v, path, mats.size(), cumulative);
  std::uint64_t seed = 1;
  if (const Json* s = find(v, "seed")) seed = std::uint64_t(integer(*s, key("seed"), 0, INT_MAX));

  const std::size_t per_item =
      std::max(want_sphere ? icosphere_triangles(sub) : 0, want_box ? std::size_t(12) : 0);
  if (per_item > 0 && std::size_t(items) > max_triangles_ / per_item)
    fail(path, std::to_string(items) + " items would make more than " +
                   std::to_string(max_triangles_) + " triangles (scenes/FORMAT.md, Limits)");
  // On several ranks each item is dealt whole as it is made (a few thousand
  // at a time): the entry is limited by the scene, an item by one rank.
  budget(std::size_t(items) * per_item, std::size_t(items) * per_item, std::size_t(items), path,
         per_item <= entry_limit_);
  return [=](std::vector<Triangle>& tris) {
    build_items(tris, grid, items, counts, lo, hi, jitter, shape_is_box, rmin, rmax, sub, mats,
                cumulative, total, seed);
  };
}

void SceneReader::build_items(std::vector<Triangle>& tris, bool grid, long long items, const int counts[3],
                              const Vec3& lo, const Vec3& hi, float jitter,
                              const std::vector<bool>& shape_is_box, float rmin, float rmax, int sub,
                              const std::vector<int>& mats, const std::vector<double>& cumulative,
                              double total, std::uint64_t seed) {
  const auto is_box = [&](double u_shape) {
    return shape_is_box[std::min<std::size_t>(std::size_t(u_shape * shape_is_box.size()), shape_is_box.size() - 1)];
  };
  if (share_.ranks > 1) {  // the items' exact triangle count, for dealing them evenly: the shapes drawn alone
    Pcg32 dry(seed);
    entry_.expected = 0;
    for (long long n = 0; n < items; ++n) {
      entry_.expected += is_box(dry.uniform()) ? 12 : icosphere_triangles(sub);
      for (int k = 0; k < 6; ++k) dry.next();
    }
  }
  Pcg32 rng(seed);
  for (long long n = 0; n < items; ++n) {
    if (n > 0 && (n % kFlushItems == 0 || tris.size() - entry_.first >= kFlushTriangles)) flush_entry();
    const double u_shape = rng.uniform(), u_radius = rng.uniform();
    const double ux = rng.uniform(), uy = rng.uniform(), uz = rng.uniform();
    const double u_mat = rng.uniform(), u_angle = rng.uniform();
    const bool box = is_box(u_shape);
    const double r = rmin + (double(rmax) - rmin) * u_radius;
    double centre[3];
    const double u[3] = {ux, uy, uz};
    if (grid) {
      const long long cell[3] = {n % counts[0], (n / counts[0]) % counts[1],
                                 n / (1LL * counts[0] * counts[1])};
      for (int a = 0; a < 3; ++a) {
        const double step = (double(hi[a]) - lo[a]) / counts[a];
        centre[a] = lo[a] + step * (cell[a] + 0.5) + jitter * 0.5 * step * (2.0 * u[a] - 1.0);
      }
    } else {
      for (int a = 0; a < 3; ++a) centre[a] = lo[a] + (double(hi[a]) - lo[a]) * u[a];
    }
    std::size_t m = 0;
    const double pick = u_mat * total;
    while (m + 1 < cumulative.size() && pick >= cumulative[m]) ++m;
    const FacetTag tag{next_object_++, mats[m]};
    const Vec3 c{static_cast<float>(centre[0]), static_cast<float>(centre[1]),
                 static_cast<float>(centre[2])};
    const float rf = static_cast<float>(r);
    if (box) {
      const std::size_t start = tris.size();
      next_facet_ = add_box(tris, {-rf, -rf, -rf}, {rf, rf, rf}, tag, next_facet_);
      Transform place;
      place.rotate_deg = {0, static_cast<float>(90.0 * u_angle), 0};
      place.translate = c;
      transform_triangles(tris, start, place);
    } else {
      next_facet_ = add_icosphere(tris, c, rf, sub, tag, next_facet_);
    }
  }
}

}  // namespace scene_json
}  // namespace opsila
