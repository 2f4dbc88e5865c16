// The generators of the JSON scene format (scene_generators.h): their keys
// checked and counted, then their items made.
#include "formats/json/scene_generators.h"

#include <algorithm>
#include <climits>

#include "formats/json/primitives.h"

namespace opsila {
namespace scene_json {

namespace {

constexpr long long kFlushItems = 4096;                        // generator items between flushes, at most
constexpr std::size_t kFlushTriangles = std::size_t(1) << 18;  // and about this many triangles

// The running sums of a generator's material weights (equal when left
// out); returns their total.
double material_weights(SceneValues& values, const Json& v, const std::string& path, std::size_t materials,
                        std::vector<double>& cumulative) {
  const auto key = [&](const char* k) { return join_key(path, k); };
  double total = 0;
  const Json* w = SceneValues::find(v, "weights");
  if (!w) {
    for (std::size_t k = 0; k < materials; ++k) cumulative.push_back(total += 1.0);
    return total;
  }
  values.expect_array(*w, key("weights"));
  if (w->size() != materials)
    values.fail(key("weights"), "needs one weight per material (" + std::to_string(materials) + ")");
  for (std::size_t k = 0; k < w->size(); ++k) {
    const double x = values.number((*w)[k], join_index(key("weights"), k));
    if (x < 0) values.fail(join_index(key("weights"), k), "must not be negative");
    total += x;
    cumulative.push_back(total);
  }
  if (!(total > 0)) values.fail(key("weights"), "must not all be zero");
  return total;
}

// The shapes to draw from ("shapes"); whether any is a sphere, any a box.
void read_shapes(SceneValues& values, const Json& v, const std::string& path, Generator& g, bool& want_sphere,
                 bool& want_box) {
  want_sphere = true, want_box = false;
  const Json* s = SceneValues::find(v, "shapes");
  if (!s) return;
  const std::string key = join_key(path, "shapes");
  values.expect_array(*s, key);
  if (s->empty()) values.fail(key, "needs at least one shape");
  g.shape_is_box.clear();
  want_sphere = false;
  for (std::size_t k = 0; k < s->size(); ++k) {
    const std::string n = values.string((*s)[k], join_index(key, k));
    if (n != "sphere" && n != "box") values.fail(join_index(key, k), "unknown shape '" + n + "' (expected sphere or box)");
    g.shape_is_box.push_back(n == "box");
    want_sphere = want_sphere || n == "sphere";
    want_box = want_box || n == "box";
  }
}

bool is_box(const Generator& g, double u_shape) {
  const std::size_t n = g.shape_is_box.size();
  return g.shape_is_box[std::min<std::size_t>(std::size_t(u_shape * n), n - 1)];
}

}  // namespace

long long generator_items(SceneValues& values, const Json& v, const std::string& path, bool grid, int counts[3]) {
  const auto key = [&](const char* k) { return join_key(path, k); };
  const int kMaxItems = kMaxGeneratorItems;
  if (!grid) return values.integer(values.require(v, path, "count"), key("count"), 1, kMaxItems);
  const Json& c = values.require(v, path, "counts");
  if (c.is_number()) {
    counts[0] = counts[1] = counts[2] = values.integer(c, key("counts"), 1, 1000);
  } else if (c.is_array() && c.size() == 3) {
    for (int a = 0; a < 3; ++a) counts[a] = values.integer(c[a], join_index(key("counts"), a), 1, 100000);
  } else {
    values.fail(key("counts"), std::string("expected an integer or [nx, ny, nz], not ") + kind(c));
  }
  const long long items = 1LL * counts[0] * counts[1] * counts[2];
  if (items > kMaxItems) values.fail(key("counts"), "more than " + std::to_string(kMaxItems) + " items");
  return items;
}

void read_region(SceneValues& values, const Json& v, const std::string& path, Vec3& lo, Vec3& hi) {
  lo = values.vec3(values.require(v, path, "min"), join_key(path, "min"));
  hi = values.vec3(values.require(v, path, "max"), join_key(path, "max"));
  for (int a = 0; a < 3; ++a)
    if (!(hi[a] >= lo[a])) values.fail(join_key(path, "max"), "must not be less than min on any axis");
}

void read_range(SceneValues& values, const Json& v, const std::string& path, bool positive, float& lo, float& hi) {
  const auto one = [&](const Json& x, const std::string& p) { return positive ? values.positive(x, p) : values.real(x, p); };
  if (v.is_array() && v.size() == 2) {
    lo = one(v[0], join_index(path, 0));
    hi = one(v[1], join_index(path, 1));
    if (hi < lo) values.fail(path, "[min, max] with max < min");
  } else {
    lo = hi = one(v, path);
  }
}

void grid_centre(const int counts[3], const Vec3& lo, const Vec3& hi, float jitter, long long n, const double u[3],
                 double centre[3]) {
  const long long cell[3] = {n % counts[0], (n / counts[0]) % counts[1], n / (1LL * counts[0] * counts[1])};
  for (int a = 0; a < 3; ++a) {
    const double step = (double(hi[a]) - lo[a]) / counts[a];
    centre[a] = lo[a] + step * (cell[a] + 0.5) + jitter * 0.5 * step * (2.0 * u[a] - 1.0);
  }
}

// Many spheres/boxes, each its own object, from a fixed-seed PCG32. Per item
// seven numbers are drawn in a fixed order: shape, radius, x, y, z,
// material, angle (see FORMAT.md), so a scene is the same everywhere.
Generator read_generator(SceneValues& values, SceneSections& sections, const Json& v, const std::string& path,
                         bool grid) {
  if (grid)
    values.check_keys(v, path, {"type", "name", "counts", "min", "max", "jitter", "shapes", "radius",
                                "subdivisions", "materials", "weights", "seed", "transform"});
  else
    values.check_keys(v, path, {"type", "name", "count", "min", "max", "shapes", "radius",
                                "subdivisions", "materials", "weights", "seed", "transform"});
  const auto key = [&](const char* k) { return join_key(path, k); };
  Generator g;
  g.grid = grid;
  read_region(values, v, path, g.lo, g.hi);
  g.items = generator_items(values, v, path, grid, g.counts);
  if (const Json* j = SceneValues::find(v, "jitter")) {
    g.jitter = values.real(*j, key("jitter"));
    if (!(g.jitter >= 0 && g.jitter <= 1)) values.fail(key("jitter"), "must be in [0, 1]");
  }
  bool want_sphere = true, want_box = false;
  read_shapes(values, v, path, g, want_sphere, want_box);
  if (const Json* r = SceneValues::find(v, "radius")) read_range(values, *r, key("radius"), true, g.rmin, g.rmax);
  if (const Json* s = SceneValues::find(v, "subdivisions")) g.subdivisions = values.integer(*s, key("subdivisions"), 0, 10);
  if (const Json* m = SceneValues::find(v, "materials")) g.materials = sections.material_list(*m, key("materials"));
  g.total = material_weights(values, v, path, g.materials.size(), g.cumulative);
  if (const Json* s = SceneValues::find(v, "seed")) g.seed = std::uint64_t(values.integer(*s, key("seed"), 0, INT_MAX));
  g.per_item = std::max(want_sphere ? icosphere_triangles(g.subdivisions) : 0, want_box ? std::size_t(12) : 0);
  return g;
}

std::size_t generator_triangles(const Generator& g) {
  Pcg32 dry(g.seed);
  std::size_t triangles = 0;
  for (long long n = 0; n < g.items; ++n) {
    triangles += is_box(g, dry.uniform()) ? 12 : icosphere_triangles(g.subdivisions);
    for (int k = 0; k < 6; ++k) dry.next();
  }
  return triangles;
}

void make_items(const Generator& g, std::vector<Triangle>& tris, int& next_object, int& next_facet,
                const std::function<void()>& flush) {
  std::size_t since = tris.size();  // the triangles made before the last flush
  Pcg32 rng(g.seed);
  for (long long n = 0; n < g.items; ++n) {
    if (n > 0 && (n % kFlushItems == 0 || tris.size() - since >= kFlushTriangles)) {
      flush();
      since = tris.size();
    }
    const double u_shape = rng.uniform(), u_radius = rng.uniform();
    const double ux = rng.uniform(), uy = rng.uniform(), uz = rng.uniform();
    const double u_mat = rng.uniform(), u_angle = rng.uniform();
    const bool box = is_box(g, u_shape);
    const double r = g.rmin + (double(g.rmax) - g.rmin) * u_radius;
    double centre[3];
    const double u[3] = {ux, uy, uz};
    if (g.grid) {
      grid_centre(g.counts, g.lo, g.hi, g.jitter, n, u, centre);
    } else {
      for (int a = 0; a < 3; ++a) centre[a] = g.lo[a] + (double(g.hi[a]) - g.lo[a]) * u[a];
    }
    std::size_t m = 0;
    const double pick = u_mat * g.total;
    while (m + 1 < g.cumulative.size() && pick >= g.cumulative[m]) ++m;
    const FacetTag tag{next_object++, g.materials[m]};
    const Vec3 c{static_cast<float>(centre[0]), static_cast<float>(centre[1]), static_cast<float>(centre[2])};
    const float rf = static_cast<float>(r);
    if (box) {
      const std::size_t start = tris.size();
      next_facet = add_box(tris, {-rf, -rf, -rf}, {rf, rf, rf}, tag, next_facet);
      Transform place;
      place.rotate_deg = {0, static_cast<float>(90.0 * u_angle), 0};
      place.translate = c;
      transform_triangles(tris, start, place);
    } else {
      next_facet = add_icosphere(tris, c, rf, g.subdivisions, tag, next_facet);
    }
  }
}

}  // namespace scene_json
}  // namespace opsila
