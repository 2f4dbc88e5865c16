// The generators of the JSON scene format (scenes/FORMAT.md, "grid" and
// "scatter"): an entry read into a description, its keys checked, then its
// items made from it. Internal to formats/json.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "formats/json/scene_sections.h"
#include "formats/json/scene_values.h"

namespace opsila {
namespace scene_json {

constexpr int kMaxGeneratorItems = 1000000;  // FORMAT.md "Limits"

struct Generator {
  bool grid = false;
  long long items = 0;
  int counts[3] = {1, 1, 1};  // a grid's items along x, y, z
  Vec3 lo, hi;
  float jitter = 0;
  std::vector<bool> shape_is_box{false};
  float rmin = 0.5f, rmax = 0.5f;
  int subdivisions = 2;
  std::vector<int> materials{0};
  std::vector<double> cumulative;  // running sums of the materials' weights
  double total = 0;                // their total
  std::uint64_t seed = 1;
  std::size_t per_item = 0;  // the triangles of its largest shape
};

// What generators and instances share (scenes/FORMAT.md): the item count
// of `v` (its `count`, or the product of a grid's `counts`, into counts),
// at most kMaxGeneratorItems.
long long generator_items(SceneValues& values, const Json& v, const std::string& path, bool grid, int counts[3]);
// The region `min`, `max` of `v` (max >= min on every axis).
void read_region(SceneValues& values, const Json& v, const std::string& path, Vec3& lo, Vec3& hi);
// A number or [min, max] (max >= min) at `path`, positive when `positive`.
void read_range(SceneValues& values, const Json& v, const std::string& path, bool positive, float& lo, float& hi);
// The centre of item n of a grid of counts[0..2] cells over [lo, hi] (x
// fastest, then y, then z), moved by jitter x half a cell x (2u - 1) on
// each axis.
void grid_centre(const int counts[3], const Vec3& lo, const Vec3& hi, float jitter, long long n, const double u[3],
                 double centre[3]);

// A generator entry ("grid" when `grid`), its keys and values checked.
Generator read_generator(SceneValues& values, SceneSections& sections, const Json& v, const std::string& path,
                         bool grid);

// The exact triangle count of its items (for dealing them evenly): the
// shapes drawn alone.
std::size_t generator_triangles(const Generator& g);

// Makes its items, each its own object and facets from the ids given, into
// `tris`; `flush` is called before an item every few thousand items (or
// about kFlushTriangles triangles made since the last call).
void make_items(const Generator& g, std::vector<Triangle>& tris, int& next_object, int& next_facet,
                const std::function<void()>& flush);

}  // namespace scene_json
}  // namespace opsila
