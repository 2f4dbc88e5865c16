// The "instances" entry of JSON scenes (scenes/FORMAT.md, "Instances"): a
// model held once as a prototype in its own frame, placed by a list and a
// grid; the scene's own ids unchanged; one-line errors; every rank of a
// share keeping every instance.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "test_util.h"
#include "formats/json/scene_file.h"
#include "scene/instances.h"

namespace opsila {
namespace {

const std::string kSource = OPSILA_SOURCE_DIR;
const std::string kScenes = kSource + "/scenes";
const std::string kData = kSource + "/tests/data";

using test::expect_error;

Scene json(const std::string& text, const std::string& dir = kData, const SceneShare& share = SceneShare()) {
  return load_scene_from_string(text, "s.json", dir, kMaxTriangles, share);
}

// A floor, then `instances` (an entry's text), then a sphere.
std::string scene_with(const std::string& instances) {
  return "{\"objects\": [\n"
         "{\"type\": \"plane\", \"size\": 100},\n" +
         instances +
         ",\n"
         "{\"type\": \"sphere\", \"center\": [0, 5, 0], \"radius\": 1, \"subdivisions\": 0}]}";
}

const std::string kGrid =
    "{\"type\": \"instances\", \"name\": \"forest\", \"model\": {\"type\": \"model\", \"file\": \"cube.obj\"},\n"
    " \"transforms\": [{\"translate\": [1, 0, -5]}, {\"scale\": 2, \"rotate\": [0, 30, 0], \"translate\": [4, 0, -5]}],\n"
    " \"grid\": {\"counts\": [4, 1, 3], \"min\": [-10, 0, -10], \"max\": [10, 0, 10], \"jitter\": 0.5,\n"
    "          \"scale\": [0.8, 1.2], \"rotate_y\": [0, 360], \"seed\": 7}}";

bool near_point(const Vec3& a, const Vec3& b) {
  for (int k = 0; k < 3; ++k)
    if (std::fabs(a[k] - b[k]) > 1e-5f * std::max({1.0f, std::fabs(a[k]), std::fabs(b[k])})) return false;
  return true;
}

Vec3 to_world(const InstanceDesc& in, const Vec3& p) {
  Vec3 out;
  for (int r = 0; r < 3; ++r) {
    const double* m = &in.to_world[std::size_t(4 * r)];
    out[r] = static_cast<float>(m[0] * p[0] + m[1] * p[1] + m[2] * p[2] + m[3]);
  }
  return out;
}

TEST(JsonInstances, AListAndAGridMakeOnePrototypeAndTheirInstances) {
  const Scene s = json(scene_with(kGrid));
  // The scene's own: the plane (object 0, facet 0), the sphere (object 1, facets 1..20).
  EXPECT_EQ(s.num_objects, 2);
  EXPECT_EQ(s.num_facets, 21);
  ASSERT_EQ(s.triangles.size(), 22u);
  EXPECT_EQ(s.triangles.back().object_id, 1);
  // cube.obj: two objects, 6 quads; one prototype, object 0, its facets 0..5.
  ASSERT_EQ(s.prototypes.size(), 1u);
  const Prototype& p = s.prototypes[0];
  EXPECT_EQ(p.name, "cube.obj");
  EXPECT_EQ(p.num_facets, 6);
  ASSERT_EQ(p.triangles.size(), 12u);
  for (std::size_t k = 0; k < p.triangles.size(); ++k) {
    EXPECT_EQ(p.triangles[k].object_id, 0);
    EXPECT_EQ(p.triangles[k].facet_id, int(k / 2));
    EXPECT_EQ(p.triangles[k].fan, int(k % 2));
    for (const Vec3& v : {p.triangles[k].v0, p.triangles[k].v1, p.triangles[k].v2})
      EXPECT_TRUE(min(v, p.lo) == p.lo && max(v, p.hi) == p.hi);
  }
  EXPECT_EQ(s.materials[p.triangles[0].material].name, "red");  // the model's materials in the scene's table
  ASSERT_EQ(s.instances.size(), 2u + 12u);
  for (const InstanceDesc& in : s.instances) {
    EXPECT_EQ(in.prototype, 0);
    for (const Vec3& q : {Vec3{0, 0, 0}, Vec3{1, -2, 3}, p.hi})
      EXPECT_TRUE(near_point(apply_point(in.to_object, to_world(in, q)), q));
  }
  EXPECT_EQ(to_world(s.instances[0], {0, 0, 0}), (Vec3{1, 0, -5}));
  EXPECT_TRUE(near_point(to_world(s.instances[1], {1, 0, 0}),
                         Vec3{4 + 2 * float(std::cos(M_PI / 6)), 0, -5 - 2 * float(std::sin(M_PI / 6))}));
  // The scene's bounds hold every instance's box.
  Vec3 lo, hi, l, h;
  s.bounds(lo, hi);
  for (const InstanceDesc& in : s.instances) {
    instance_box(s, in, l, h);
    EXPECT_TRUE(min(lo, l) == lo && max(hi, h) == hi);
  }
}

TEST(JsonInstances, GridPlacementsAreDeterministicAndInTheirRanges) {
  const Scene a = json(scene_with(kGrid)), b = json(scene_with(kGrid));
  ASSERT_EQ(a.instances.size(), b.instances.size());
  for (std::size_t k = 0; k < a.instances.size(); ++k) EXPECT_EQ(a.instances[k].to_world, b.instances[k].to_world);
  // Grid cells of 5 x 20 x 6.67 (x fastest): centre +- jitter x half a cell.
  const double step[3] = {20.0 / 4, 0, 20.0 / 3};
  for (long long n = 0; n < 12; ++n) {
    const InstanceDesc& in = a.instances[std::size_t(2 + n)];
    const long long cell[3] = {n % 4, 0, n / 4};
    for (int ax : {0, 2}) {
      const double centre = -10 + step[ax] * (double(cell[ax]) + 0.5);
      EXPECT_LE(std::fabs(in.to_world[std::size_t(4 * ax + 3)] - centre), 0.5 * 0.5 * step[ax] + 1e-9);
    }
    EXPECT_EQ(in.to_world[7], 0.0);
    // rotate_y(angle) * scale(s): column 0 is s (cos a, 0, -sin a), column 1 is (0, s, 0).
    const double s = in.to_world[5];
    EXPECT_GE(s, 0.8 - 1e-6);
    EXPECT_LE(s, 1.2 + 1e-6);
    EXPECT_NEAR(std::hypot(in.to_world[0], in.to_world[8]), s, 1e-9);
    EXPECT_EQ(in.to_world[4], 0.0);
  }
  // Another seed, other placements.
  std::string other = kGrid;
  other.replace(other.find("\"seed\": 7"), 9, "\"seed\": 8");
  EXPECT_NE(json(scene_with(other)).instances[2].to_world, a.instances[2].to_world);
}

TEST(JsonInstances, AnInlineShapeWithItsOwnTransformAndInstancesAlone) {
  const Scene s = json(
      "{\"objects\": [{\"type\": \"instances\", \"comment\": \"balls\",\n"
      " \"model\": {\"type\": \"sphere\", \"center\": [0, 0, 0], \"radius\": 1, \"subdivisions\": 1,\n"
      "            \"transform\": {\"translate\": [0, 1, 0]}},\n"
      " \"transforms\": [{\"translate\": [3, 0, 0]}, {\"translate\": [-3, 0, 0]}]}]}");
  EXPECT_TRUE(s.warnings.empty());
  EXPECT_EQ(s.num_objects, 0);
  EXPECT_EQ(s.num_facets, 0);
  EXPECT_TRUE(s.triangles.empty());
  ASSERT_EQ(s.prototypes.size(), 1u);
  EXPECT_EQ(s.prototypes[0].num_facets, 80);
  EXPECT_NEAR(s.prototypes[0].lo[1], 0.0f, 1e-6);  // the model's transform applies in its frame
  EXPECT_NEAR(s.prototypes[0].hi[1], 2.0f, 1e-6);
  EXPECT_EQ(s.instances.size(), 2u);
  Vec3 lo, hi;
  s.bounds(lo, hi);
  EXPECT_LE(lo[0], -4.0f);
  EXPECT_GE(hi[0], 4.0f);
  EXPECT_GT(s.epsilon(), 0.0f);
}

TEST(JsonInstances, EveryRankOfAShareKeepsEveryInstanceInItsBounds) {
  const std::string text = scene_with(kGrid);
  const Scene whole = json(text);
  Vec3 lo, hi;
  whole.bounds(lo, hi);
  for (int r = 0; r < 3; ++r) {
    SCOPED_TRACE(r);
    SceneShare share;
    share.rank = r, share.ranks = 3;
    const Scene s = json(text, kData, share);
    ASSERT_EQ(s.prototypes.size(), 1u);
    EXPECT_EQ(s.prototypes[0].triangles.size(), 12u);
    ASSERT_EQ(s.instances.size(), whole.instances.size());
    for (std::size_t k = 0; k < s.instances.size(); ++k) EXPECT_EQ(s.instances[k].to_world, whole.instances[k].to_world);
    Vec3 l, h;
    for (const InstanceDesc& in : s.instances) {
      instance_box(s, in, l, h);
      EXPECT_TRUE(min(s.share.lo, l) == s.share.lo && max(s.share.hi, h) == s.share.hi);
    }
    EXPECT_EQ(s.share.total_triangles, whole.triangles.size());  // instances are not dealt
  }
}

// CONTRACT: the framing and epsilon follow the drawn facets' box; an
// instance's counts as the same facets placed without one. Its walks' box
// is wider (instance_holding_box): at 1e6 from the origin, some 15 units,
// which had framed the sphere out of the picture.
TEST(JsonInstances, BoundsFramingAndEpsilonAreThoseOfTheFacetsPlaced) {
  for (const char* at : {"0", "1e4", "1e6"}) {
    SCOPED_TRACE(at);
    const std::string sphere = "{\"type\": \"sphere\", \"center\": [0, 0, 0], \"radius\": 1, \"subdivisions\": 1}";
    const Scene placed = json("{\"objects\": [{\"type\": \"instances\", \"model\": " + sphere +
                              ", \"transforms\": [{\"translate\": [" + at + ", 0, 0]}]}]}");
    const Scene plain = json("{\"objects\": [{\"type\": \"sphere\", \"center\": [" + std::string(at) +
                             ", 0, 0], \"radius\": 1, \"subdivisions\": 1}]}");
    Vec3 lo, hi, l, h;
    placed.bounds(lo, hi);
    plain.bounds(l, h);
    EXPECT_EQ(lo, l);
    EXPECT_EQ(hi, h);
    EXPECT_EQ(placed.epsilon(), plain.epsilon());
    EXPECT_EQ(placed.camera.eye, plain.camera.eye);
    EXPECT_EQ(placed.camera.look_at, plain.camera.look_at);
    instance_holding_box(placed, placed.instances[0], l, h);
    EXPECT_TRUE(min(lo, l) == l && max(hi, h) == h) << "the walks' box holds the facets";
    EXPECT_LT(l[0], lo[0]);
  }
}

TEST(JsonInstances, ErrorsNameFileLineAndKey) {
  const auto entry = [](const std::string& body) { return scene_with("{\"type\": \"instances\", " + body + "}"); };
  const std::string cube = "\"model\": {\"type\": \"model\", \"file\": \"cube.obj\"}";
  const struct {
    std::string text;
    std::vector<std::string> fragments;
  } cases[] = {
      {entry("\"transforms\": [{}]"), {"s.json:3:", "objects[1]", "missing key 'model'"}},
      {entry("\"model\": {\"type\": \"instances\"}, \"transforms\": [{}]"),
       {"s.json:3:", "objects[1].model.type", "do not nest"}},
      {entry("\"model\": {\"type\": \"grid\"}, \"transforms\": [{}]"), {"objects[1].model.type", "generator"}},
      {entry("\"model\": {\"type\": \"scatter\"}, \"transforms\": [{}]"), {"objects[1].model.type", "generator"}},
      {entry(cube), {"s.json:3:", "objects[1]", "needs transforms, a grid or both"}},
      {entry(cube + ", \"transforms\": []"), {"objects[1].transforms", "no placements"}},
      {entry(cube + ", \"transforms\": [{\"scale\": 0}]"), {"objects[1].transforms[0].scale", "positive"}},
      {entry(cube + ", \"transforms\": [{\"scale\": [1, -1, 1]}]"), {"objects[1].transforms[0].scale[1]", "positive"}},
      {entry(cube + ", \"grid\": {\"counts\": 2, \"min\": [0,0,0], \"max\": [1,1,1], \"scale\": [-1, 2]}"),
       {"objects[1].grid.scale[0]", "positive"}},
      {entry(cube + ", \"grid\": {\"counts\": 2, \"min\": [0,0,0], \"max\": [1,1,1], \"scale\": [2, 1]}"),
       {"objects[1].grid.scale", "max < min"}},
      {entry(cube + ", \"grid\": {\"counts\": [1000, 1000, 2], \"min\": [0,0,0], \"max\": [1,1,1]}"),
       {"s.json:3:", "objects[1].grid.counts", "more than 1000000"}},
      {entry(cube + ", \"grid\": {\"counts\": 2, \"min\": [0,0,0], \"max\": [1,1,1], \"jitter\": 2}"),
       {"objects[1].grid.jitter", "[0, 1]"}},
      {entry("\"model\": {\"type\": \"model\", \"file\": \"no_such.obj\"}, \"transforms\": [{}]"),
       {"s.json:3:", "objects[1].model.file", "no_such.obj"}},
      {entry("\"model\": {\"type\": \"cone\"}, \"transforms\": [{}]"), {"objects[1].model.type", "unknown object type"}},
      // Scales 1e-20 and 1e20: the determinant is 1, the inverse not of use.
      {entry(cube + ", \"transforms\": [{\"scale\": [1e-20, 1, 1e20]}]"),
       {"objects[1].transforms[0]", "singular or nearly so (determinant 1 for a largest entry of 1e+20"}},
      // A placement past the renderer's extent: named, not only the file.
      {entry(cube + ", \"transforms\": [{}, {\"scale\": 1e30}]"),
       {"s.json:3:", "objects[1].transforms[1]: with the model placed there, scene extent too large"}},
      {entry(cube + ", \"transforms\": [{}], \"grid\": {\"counts\": [2, 1, 1], \"min\": [0,0,0], \"max\": [2e30,0,0]}"),
       {"s.json:3:", "objects[1].grid: placement 2: with the model placed there, scene extent too large"}},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.text);
    expect_error([&] { json(c.text); }, c.fragments);
  }
}

TEST(JsonInstances, UnknownKeysAreWarningsNamingLineAndKey) {
  const Scene s = json(scene_with(
      "{\"type\": \"instances\", \"model\": {\"type\": \"model\", \"file\": \"cube.obj\"}, \"colour\": 1,\n"
      " \"grid\": {\"counts\": 2, \"min\": [0,0,0], \"max\": [1,1,1], \"spin\": 3}}"));
  ASSERT_EQ(s.warnings.size(), 2u);
  EXPECT_NE(s.warnings[0].find("s.json:3: objects[1].colour: unknown key 'colour'"), std::string::npos) << s.warnings[0];
  EXPECT_NE(s.warnings[1].find("s.json:4: objects[1].grid.spin: unknown key 'spin'"), std::string::npos) << s.warnings[1];
  EXPECT_EQ(s.instances.size(), 8u);
}

TEST(JsonInstances, PlacementsCountAgainstTheTriangleLimit) {
  const std::string text = scene_with(
      "{\"type\": \"instances\", \"model\": {\"type\": \"model\", \"file\": \"cube.obj\"},\n"
      " \"grid\": {\"counts\": [10, 1, 10], \"min\": [0,0,0], \"max\": [1,1,1]}}");
  // The plane 2, the cube 12 and 100 placements 600 (kInstanceTriangles
  // each), the sphere 20.
  static_assert(kInstanceTriangles == 6, "the figures below");
  EXPECT_EQ(load_scene_from_string(text, "s.json", kData, 634).instances.size(), 100u);
  expect_error([&] { load_scene_from_string(text, "s.json", kData, 633); },
               {"s.json:5:", "objects[2]", "would make 20 more triangles (614 so far)", "at most 633"});
  expect_error([&] { load_scene_from_string(text, "s.json", kData, 613); },
               {"s.json:3:", "objects[1]", "would make 612 more triangles (2 so far)", "at most 613"});
}

TEST(JsonInstances, OnSeveralRanksTheyKeepOneRanksLimitTogether) {
  const std::string forest =
      "{\"type\": \"instances\", \"model\": {\"type\": \"model\", \"file\": \"cube.obj\"},\n"
      " \"grid\": {\"counts\": [30, 1, 1], \"min\": [0,0,0], \"max\": [1,1,1]}}";
  const std::string text = scene_with(forest + ",\n" + forest);
  SceneShare share;
  share.rank = 0, share.ranks = 2;
  // Each entry 12 + 180 triangles, held by both ranks: 384, over one rank's 380.
  EXPECT_EQ(load_scene_from_string(text, "s.json", kData, 384, share).instances.size(), 60u);
  expect_error([&] { load_scene_from_string(text, "s.json", kData, 380, share); },
               {"s.json:5:", "objects[2]", "384 triangles, which every rank holds; at most 380"});
}

TEST(JsonInstances, ForestLoads) {
  const Scene s = load_scene(kScenes + "/forest.json");
  EXPECT_EQ(s.prototypes.size(), 1u);
  EXPECT_GE(s.instances.size(), 1500u);
  EXPECT_LE(s.instances.size(), 2500u);
  EXPECT_EQ(s.width, 800);
  EXPECT_EQ(s.height, 600);
  EXPECT_EQ(s.lights.size(), 2u);
}

}  // namespace
}  // namespace opsila
