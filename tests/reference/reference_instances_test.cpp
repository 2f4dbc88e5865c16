// The reference tracer's instances: a scene with a model placed at several
// transforms against the same scene with every instance written out as
// facets of its own (flattened), and the hit order's instance tie-break.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "reference/reference.h"
#include "scene/instances.h"

namespace opsila {
namespace {

MaterialDesc coloured(Vec3 kd, Vec3 ks = {0, 0, 0}, int illum = 2) {
  MaterialDesc m;
  m.ka = kd * 0.2f;
  m.kd = kd;
  m.ks = ks;
  m.ns = 20;
  m.illum = illum;
  return m;
}

// Two lights and a camera that looks down at the floor from the side, so
// that instances shade the floor and each other.
Scene lit_scene(int w, int h) {
  Scene s;
  s.width = w, s.height = h;
  s.camera.eye = {0.5f, 6, 9};
  s.camera.look_at = {0, 0.5f, 0};
  s.camera.fov_deg = 50;
  s.lights = {{{4, 8, 6}, {0.7f, 0.7f, 0.7f}}, {{-5, 6, -2}, {0.4f, 0.4f, 0.5f}}};
  s.ambient = {0.2f, 0.2f, 0.2f};
  s.background = {0.05f, 0.05f, 0.1f};
  s.max_depth = 3;
  s.has_camera = s.has_lights = true;
  return s;
}

// The quad a, b, c, d as facet `facet` of `object` (a fan of two).
void add_quad(std::vector<Triangle>& out, Vec3 a, Vec3 b, Vec3 c, Vec3 d, int facet, int object, int mat) {
  out.push_back({a, b, c, facet, object, mat, -1, 0});
  out.push_back({a, c, d, facet, object, mat, -1, 1});
}

// The unit cube [-0.5, 0.5]^3 as a prototype, a facet per side, outward
// counter-clockwise, sides alternating between two materials.
Prototype cube(int mat0, int mat1) {
  Prototype p;
  p.name = "cube";
  const float h = 0.5f;
  auto at = [h](int x, int y, int z) { return Vec3{x ? h : -h, y ? h : -h, z ? h : -h}; };
  const int sides[6][4][3] = {{{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}}, {{1, 0, 0}, {0, 0, 0}, {0, 1, 0}, {1, 1, 0}},
                              {{1, 0, 1}, {1, 0, 0}, {1, 1, 0}, {1, 1, 1}}, {{0, 0, 0}, {0, 0, 1}, {0, 1, 1}, {0, 1, 0}},
                              {{0, 1, 1}, {1, 1, 1}, {1, 1, 0}, {0, 1, 0}}, {{0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}}};
  for (int f = 0; f < 6; ++f) {
    Vec3 v[4];
    for (int k = 0; k < 4; ++k) v[k] = at(sides[f][k][0], sides[f][k][1], sides[f][k][2]);
    add_quad(p.triangles, v[0], v[1], v[2], v[3], f, 0, f % 2 ? mat1 : mat0);
  }
  p.num_facets = 6;
  p.lo = splat(-h), p.hi = splat(h);
  return p;
}

// An octahedron of radius 0.7 whose vertex normals point out from its
// centre (a sphere, smooth shaded): its attributes appended to the scene's.
Prototype ball(Scene& s, int mat) {
  Prototype p;
  p.name = "ball";
  const float r = 0.7f;
  const Vec3 axis[3] = {{r, 0, 0}, {0, r, 0}, {0, 0, r}};
  int facet = 0;
  for (int sx = -1; sx <= 1; sx += 2)
    for (int sy = -1; sy <= 1; sy += 2)
      for (int sz = -1; sz <= 1; sz += 2) {
        Vec3 a = float(sx) * axis[0], b = float(sy) * axis[1], c = float(sz) * axis[2];
        if (sx * sy * sz < 0) std::swap(b, c);  // outward winding
        VertexAttributes at;
        at.normal = {normalize(a), normalize(b), normalize(c)};
        at.has_normals = true;
        s.attributes.push_back(at);
        p.triangles.push_back({a, b, c, facet++, 0, mat, static_cast<int>(s.attributes.size()) - 1, 0});
      }
  p.num_facets = facet;
  p.lo = splat(-r), p.hi = splat(r);
  return p;
}

// Model to world: rotation by `deg` about the unit `axis`, then the
// non-uniform scale `scale` applied first, then the translation.
std::array<double, 12> placement(Vec3 axis, double deg, Vec3 scale, Vec3 move) {
  const double a = deg * M_PI / 180, c = std::cos(a), s = std::sin(a), x = axis[0], y = axis[1], z = axis[2];
  const double r[3][3] = {{c + x * x * (1 - c), x * y * (1 - c) - z * s, x * z * (1 - c) + y * s},
                          {y * x * (1 - c) + z * s, c + y * y * (1 - c), y * z * (1 - c) - x * s},
                          {z * x * (1 - c) - y * s, z * y * (1 - c) + x * s, c + z * z * (1 - c)}};
  std::array<double, 12> m{};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) m[std::size_t(4 * i + j)] = r[i][j] * scale[std::size_t(j)];
    m[std::size_t(4 * i + 3)] = move[std::size_t(i)];
  }
  return m;
}

// A floor (object 0, facet 0) and a wall (object 1, facet 1) of the
// scene's own, cubes and balls placed at five transforms; with `mirror`
// one cube material reflects.
Scene instanced_scene(bool smooth, bool mirror, int w = 120, int h = 90) {
  Scene s = lit_scene(w, h);
  s.materials = {coloured({0.6f, 0.6f, 0.5f}), coloured({0.8f, 0.2f, 0.2f}, {0.5f, 0.5f, 0.5f}, mirror ? 3 : 2),
                 coloured({0.2f, 0.3f, 0.9f}, {0.3f, 0.3f, 0.3f}), coloured({0.3f, 0.8f, 0.3f}, {0.6f, 0.6f, 0.6f})};
  add_quad(s.triangles, {-4, 0, 4}, {4, 0, 4}, {4, 0, -4}, {-4, 0, -4}, 0, 0, 0);
  add_quad(s.triangles, {-4, 0, -3}, {4, 0, -3}, {4, 4, -3}, {-4, 4, -3}, 1, 1, 2);
  s.num_objects = 2, s.num_facets = 2;
  s.smooth = smooth;
  s.prototypes = {cube(1, 2), ball(s, 3)};
  const std::array<double, 12> places[5] = {
      placement({0, 1, 0}, 30, {1, 1, 1}, {-2, 0.52f, 0}),
      placement({0.6f, 0.8f, 0}, 50, {1.5f, 0.6f, 1}, {0.5f, 1.2f, 1}),
      placement({0, 0, 1}, -20, {0.7f, 2, 0.9f}, {2.5f, 1.1f, -1}),
      placement({0, 1, 0}, 0, {1, 1.4f, 1}, {-0.5f, 0.98f, 2.2f}),
      placement({0.48f, 0.6f, 0.64f}, 75, {1.2f, 0.8f, 0.5f}, {1.5f, 2.6f, -1.8f})};
  for (int i = 0; i < 5; ++i) s.instances.push_back(make_instance(i % 3 == 1 ? 1 : 0, places[i], "test"));
  return s;
}

Vec3 to_world(const std::array<double, 12>& m, const Vec3& v) {
  Vec3 out;
  for (int r = 0; r < 3; ++r)
    out[std::size_t(r)] = static_cast<float>(m[std::size_t(4 * r)] * v[0] + m[std::size_t(4 * r + 1)] * v[1] +
                                              m[std::size_t(4 * r + 2)] * v[2] + m[std::size_t(4 * r + 3)]);
  return out;
}

// The same scene without instances: instance i's triangles in the world as
// object num_objects + i, its facet ids after every facet before it (so
// they rise with the objects), its vertex normals taken to the world.
Scene flattened(const Scene& s, std::vector<int>& facet_base) {
  Scene f = s;
  f.prototypes.clear();
  f.instances.clear();
  facet_base.clear();
  for (std::size_t i = 0; i < s.instances.size(); ++i) {
    const InstanceDesc& in = s.instances[i];
    const Prototype& p = s.prototypes[std::size_t(in.prototype)];
    facet_base.push_back(f.num_facets);
    for (Triangle t : p.triangles) {
      t.v0 = to_world(in.to_world, t.v0), t.v1 = to_world(in.to_world, t.v1), t.v2 = to_world(in.to_world, t.v2);
      if (t.attributes >= 0) {
        VertexAttributes a = s.attributes[std::size_t(t.attributes)];
        for (Vec3& n : a.normal) n = instance_normal(in.to_object, n);
        f.attributes.push_back(a);
        t.attributes = static_cast<int>(f.attributes.size()) - 1;
      }
      t.object_id = s.num_objects + static_cast<int>(i);
      t.facet_id += facet_base.back();
      f.triangles.push_back(t);
    }
    f.num_facets += p.num_facets;
  }
  f.num_objects += static_cast<int>(s.instances.size());
  return f;
}

// Pixels (of w x h) whose colour differs by more than `tol` in a channel,
// and those whose item differs once the flattened facet ids are mapped
// back to the model's.
struct Differences {
  int colour = 0, items = 0;
};
Differences compare(const Scene& s, const ImageResult& inst, const ImageResult& flat, const std::vector<int>& base,
                    float tol) {
  Differences d;
  for (std::size_t p = 0; p < std::size_t(s.width) * std::size_t(s.height); ++p) {
    bool colour = false;
    for (int c = 0; c < 3; ++c) colour = colour || std::fabs(inst.rgb[3 * p + c] - flat.rgb[3 * p + c]) > tol;
    d.colour += colour;
    int object = flat.item_buffer[2 * p], facet = flat.item_buffer[2 * p + 1];
    if (object >= s.num_objects) facet -= base[std::size_t(object - s.num_objects)];
    d.items += object != inst.item_buffer[2 * p] || facet != inst.item_buffer[2 * p + 1];
  }
  return d;
}

// How many pixels show `object`.
int pixels_of(const ImageResult& img, int object) {
  int n = 0;
  for (std::size_t p = 0; 2 * p < img.item_buffer.size(); ++p) n += img.item_buffer[2 * p] == object;
  return n;
}

// 900 small cubes over the floor, each turned its own way: enough to
// give the instances' BVH many levels.
Scene crowd() {
  Scene s = instanced_scene(false, true);
  s.instances.clear();
  for (int i = 0; i < 900; ++i) {
    const float x = -3.5f + 7.0f * float(i % 30) / 29, z = -2.5f + 6.0f * float(i / 30) / 29;
    const std::array<double, 12> at =
        placement({0, 1, 0}, 7.0 * i, {0.12f, 0.1f + 0.01f * float(i % 7), 0.15f}, {x, 0.3f, z});
    s.instances.push_back(make_instance(0, at, "test"));
  }
  return s;
}

// The instanced render against the flattened one, with at least `seen`
// instances in view.
void expect_same_as_flattened(const Scene& s, int seen) {
  std::vector<int> base;
  const Scene f = flattened(s, base);
  const ImageResult inst = render_reference(s, 2), flat = render_reference(f, 2);
  const Differences d = compare(s, inst, flat, base, 2e-3f);
  const int pixels = s.width * s.height;
  int in_view = 0;
  for (int i = 0; i < static_cast<int>(s.instances.size()); ++i) in_view += pixels_of(inst, s.num_objects + i) > 0;
  EXPECT_GE(in_view, seen);
  EXPECT_NEAR(double(inst.rays.primary_hits), double(flat.rays.primary_hits), 5.0);
  // Only rounding at edges (the model-frame ray against the world's
  // vertices) may tell them apart.
  EXPECT_LT(d.colour, pixels / 200) << "pixels of other colours";
  EXPECT_LT(d.items, pixels / 200) << "pixels of other items";
}

TEST(ReferenceInstances, RenderAsTheirTrianglesPlacedInTheWorld) {
  expect_same_as_flattened(instanced_scene(false, false), 5);
}

TEST(ReferenceInstances, SmoothNormalsAndMirrorsAsTheFlattenedScene) {
  expect_same_as_flattened(instanced_scene(true, true), 5);
}

TEST(ReferenceInstances, ManyInstancesAsTheFlattenedScene) { expect_same_as_flattened(crowd(), 600); }

TEST(ReferenceInstances, AWrongPlacementIsSeen) {
  // The comparison can fail: one instance moved a little.
  Scene s = instanced_scene(false, false);
  std::vector<int> base;
  const Scene f = flattened(s, base);
  s.instances[1] = make_instance(s.instances[1].prototype,
                                 placement({0.6f, 0.8f, 0}, 50, {1.5f, 0.6f, 1}, {0.6f, 1.2f, 1}), "test");
  const Differences d = compare(s, render_reference(s, 2), render_reference(f, 2), base, 2e-3f);
  EXPECT_GT(d.colour, s.width * s.height / 200);
}

TEST(ReferenceInstances, SameBytesTwiceAndOnAnyThreadCount) {
  const Scene s = instanced_scene(true, true, 64, 48);
  const ImageResult a = render_reference(s, 1), b = render_reference(s, 2), c = render_reference(s, 2);
  for (const ImageResult* other : {&b, &c}) {
    ASSERT_EQ(a.rgb.size(), other->rgb.size());
    EXPECT_EQ(0, std::memcmp(a.rgb.data(), other->rgb.data(), a.rgb.size() * sizeof(float)));
    EXPECT_EQ(a.item_buffer, other->item_buffer);
  }
}

// A square prototype [-1, 1]^2 in z = 0, facet `facet` of `facets`, facing +z.
Prototype square(int facet, int facets, int mat) {
  Prototype p;
  p.name = "square";
  add_quad(p.triangles, {-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}, facet, 0, mat);
  p.num_facets = facets;
  p.lo = {-1, -1, 0}, p.hi = {1, 1, 0};
  return p;
}

// Squares placed one on another, seen from +z: the same transform (the
// same distances, bit for bit) so that only the ids decide.
Scene stacked(const std::vector<int>& prototypes, const std::array<double, 12>& at) {
  Scene s = lit_scene(24, 24);
  s.camera.eye = {0.25f, 0.5f, 6};
  s.camera.look_at = {0.25f, 0.5f, 0};
  s.materials = {coloured({1, 0, 0}), coloured({0, 1, 0}), coloured({0, 0, 1})};
  // Far behind them, so the scene has a facet of its own.
  add_quad(s.triangles, {-9, -9, -5}, {9, -9, -5}, {9, 9, -5}, {-9, 9, -5}, 0, 0, 2);
  s.num_objects = 1, s.num_facets = 1;
  // Prototype 0 is facet 1 of its model, 1 is facet 0, both in z = 0.
  s.prototypes = {square(1, 2, 0), square(0, 1, 1)};
  for (int p : prototypes) s.instances.push_back(make_instance(p, at, "test"));
  return s;
}

TEST(ReferenceInstances, CoplanarInstancesGoToTheLowerInstance) {
  const std::array<double, 12> at = placement({0, 0, 1}, 0, {1.5f, 1.5f, 1}, {0.25f, 0.5f, 0});
  // Instance 0 wins though its facet id (1) is above instance 1's (0):
  // the instance comes before the facet in the key.
  for (const std::vector<int>& order : {std::vector<int>{0, 1}, std::vector<int>{1, 0}, std::vector<int>{1, 0, 0}}) {
    const Scene s = stacked(order, at);
    const ImageResult img = render_reference(s);
    const int hits = pixels_of(img, s.num_objects);
    EXPECT_GT(hits, 100);
    for (std::size_t i = 1; i < order.size(); ++i) EXPECT_EQ(pixels_of(img, s.num_objects + int(i)), 0);
    const Vec3 kd = s.materials[std::size_t(order[0])].kd;
    for (std::size_t p = 0; 2 * p < img.item_buffer.size(); ++p) {
      if (img.item_buffer[2 * p] != s.num_objects) continue;
      EXPECT_EQ(img.item_buffer[2 * p + 1], order[0] == 0 ? 1 : 0);
      // The winner's material: its colour channel alone is lit.
      for (int c = 0; c < 3; ++c) EXPECT_EQ(img.rgb[3 * p + std::size_t(c)] > 0.0f, kd[std::size_t(c)] > 0.0f);
    }
  }
}

TEST(ReferenceInstances, TheScenesOwnFacetsComeBeforeInstances) {
  // An identity placement: the model's ray is the world's, bit for bit.
  Scene s = stacked({0}, placement({0, 0, 1}, 0, {1, 1, 1}, {0, 0, 0}));
  add_quad(s.triangles, {-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}, 1, 1, 2);
  s.num_objects = 2, s.num_facets = 2;
  const ImageResult img = render_reference(s);
  EXPECT_EQ(pixels_of(img, s.num_objects), 0);
  EXPECT_GT(pixels_of(img, 1), 50);
}

TEST(ReferenceInstances, ShadowsFallFromInstancesOnly) {
  // The square instance between a light and the far facet darkens it.
  Scene s = stacked({0}, placement({1, 0, 0}, 0, {1, 1, 1}, {0, 0, 2}));
  s.lights = {{{0, 0, 8}, {1, 1, 1}}};
  s.ambient = {0, 0, 0};
  s.camera.eye = {3, 0, 6};
  s.camera.look_at = {0, 0, -5};
  const ImageResult lit = render_reference(s);
  s.instances.clear();
  const ImageResult bare = render_reference(s);
  int darkened = 0;
  for (std::size_t p = 0; 2 * p < lit.item_buffer.size(); ++p)
    darkened += lit.item_buffer[2 * p] == 0 && lit.rgb[3 * p + 2] == 0.0f && bare.rgb[3 * p + 2] > 0.0f;
  EXPECT_GT(darkened, 5);
}

TEST(ReferenceInstances, RaySampleEndsAtInstances) {
  const Scene s = instanced_scene(false, true, 64, 48);
  std::vector<int> base;
  const Scene f = flattened(s, base);
  Scene bare = s;
  bare.instances.clear();
  const RaySample a = ReferenceTracer(s).sample_rays(500), b = ReferenceTracer(f).sample_rays(500),
                  c = ReferenceTracer(bare).sample_rays(500);
  ASSERT_GT(a.rays.size(), 500u);
  // The primary segments (from the eye, in pixel order) end where the
  // flattened scene's do, but for a few rays at edges.
  const auto primary = [&](const RaySample& r) {
    std::vector<float> t;
    for (const RaySegment& seg : r.rays)
      if (seg.origin == s.camera.eye) t.push_back(seg.t_max);
    return t;
  };
  const std::vector<float> ta = primary(a), tb = primary(b), tc = primary(c);
  ASSERT_EQ(ta.size(), tb.size());
  EXPECT_GT(ta.size(), 400u);
  std::size_t near = 0, on_instances = 0;
  for (std::size_t i = 0; i < ta.size(); ++i) {
    near += ta[i] == tb[i] || std::fabs(ta[i] - tb[i]) <= 1e-4f * std::fabs(tb[i]);
    on_instances += ta[i] < tc[i];
  }
  EXPECT_GT(near, ta.size() * 98 / 100);
  EXPECT_GT(on_instances, 20u);
}

}  // namespace
}  // namespace opsila
