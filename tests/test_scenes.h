// Small scenes built in code for the renderer tests: mirrors, glass and
// shadows in a few hundred facets, so that PoCL runs them in seconds.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <utility>
#include <vector>

#include "scene/camera.h"
#include "scene/scene.h"

namespace opsila::test {

// Every pixel's primary ray (through its centre), row by row:
// body(x, y, direction), the rays the tests work out by hand.
template <class Body>
void for_each_primary_ray(const Scene& s, const Body& body) {
  const CameraFrame frame = camera_frame(s.camera, s.width, s.height);
  for (int y = 0; y < s.height; ++y)
    for (int x = 0; x < s.width; ++x) body(x, y, primary_direction(frame, s.width, s.height, x, y));
}

inline int add_material(Scene& s, Vec3 ka, Vec3 kd, Vec3 ks, float ns, Vec3 tf, float ni, int illum) {
  MaterialDesc m;
  m.ka = ka, m.kd = kd, m.ks = ks, m.ns = ns, m.tf = tf, m.ni = ni, m.illum = illum;
  s.materials.push_back(m);
  return static_cast<int>(s.materials.size()) - 1;
}

inline void add_quad(Scene& s, Vec3 a, Vec3 b, Vec3 c, Vec3 d, int object, int material) {
  int f = s.num_facets++;
  s.triangles.push_back({a, b, c, f, object, material});
  s.triangles.push_back({a, c, d, f, object, material, -1, 1});  // the fan's second triangle
}

// Icosphere with outward counter-clockwise faces.
inline void add_sphere(Scene& s, Vec3 c, float r, int level, int object, int material) {
  const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
  std::vector<Vec3> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                         {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<int, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                       {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                       {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                       {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  auto unit = [](Vec3 p) {
    float l = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    return Vec3{p[0] / l, p[1] / l, p[2] / l};
  };
  for (auto& p : v) p = unit(p);
  for (int k = 0; k < level; ++k) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back(unit({(v[a][0] + v[b][0]) / 2, (v[a][1] + v[b][1]) / 2, (v[a][2] + v[b][2]) / 2}));
      return mid[key] = static_cast<int>(v.size()) - 1;
    };
    std::vector<std::array<int, 3>> g;
    for (auto& tri : f) {
      int a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]), cc = midpoint(tri[2], tri[0]);
      g.push_back({tri[0], a, cc});
      g.push_back({tri[1], b, a});
      g.push_back({tri[2], cc, b});
      g.push_back({a, b, cc});
    }
    f = g;
  }
  for (auto& tri : f) {
    Vec3 p[3];
    for (int k = 0; k < 3; ++k) p[k] = {c[0] + r * v[tri[k]][0], c[1] + r * v[tri[k]][1], c[2] + r * v[tri[k]][2]};
    s.triangles.push_back({p[0], p[1], p[2], s.num_facets++, object, material});
  }
}

// The view and two lights the mirror-glass and textured scenes share: a 4:3
// image `width` pixels wide, looking down at the floor from the front.
inline void two_lights_and_view(Scene& s, int width) {
  s.lights.push_back({{3, 7, 5}, {0.7f, 0.7f, 0.7f}});
  s.lights.push_back({{-4, 5, 3}, {0.35f, 0.35f, 0.45f}});
  s.camera.eye = {0, 3, 8};
  s.camera.look_at = {0, 1, 0};
  s.camera.fov_deg = 55;
  s.width = width;
  s.height = width * 3 / 4;
  s.background = {0.25f, 0.35f, 0.55f};
  s.has_camera = s.has_lights = true;
}

// Checkerboard floor, a mirror wall, a glass sphere, a mirror sphere and a
// row of diffuse blocks casting shadows; two lights.
inline Scene mirror_glass_scene(int width, int depth = 5) {
  Scene s;
  int plain = add_material(s, {0.8f, 0.8f, 0.8f}, {0.8f, 0.8f, 0.8f}, {0, 0, 0}, 1, {0, 0, 0}, 1, 2);
  int dark = add_material(s, {0.2f, 0.2f, 0.6f}, {0.2f, 0.2f, 0.7f}, {0, 0, 0}, 1, {0, 0, 0}, 1, 2);
  int mirror = add_material(s, {0.05f, 0.05f, 0.05f}, {0.1f, 0.1f, 0.1f}, {0.8f, 0.8f, 0.8f}, 60, {0, 0, 0}, 1, 3);
  int glass = add_material(s, {0, 0, 0}, {0.02f, 0.02f, 0.02f}, {0.15f, 0.15f, 0.15f}, 90, {0.85f, 0.85f, 0.85f},
                           1.5f, 7);
  int red = add_material(s, {0.5f, 0.1f, 0.1f}, {0.7f, 0.1f, 0.1f}, {0.3f, 0.3f, 0.3f}, 20, {0, 0, 0}, 1, 2);
  int obj = 0;
  for (int i = 0; i < 8; ++i)
    for (int j = 0; j < 8; ++j) {
      float x0 = -6 + 1.5f * i, z0 = -6 + 1.5f * j;
      add_quad(s, {x0, 0, z0}, {x0, 0, z0 + 1.5f}, {x0 + 1.5f, 0, z0 + 1.5f}, {x0 + 1.5f, 0, z0}, obj,
               (i + j) % 2 ? plain : dark);
    }
  ++obj;
  add_quad(s, {-5, 0, -4}, {5, 0, -4}, {5, 4, -4}, {-5, 4, -4}, obj++, mirror);
  add_sphere(s, {-1.2f, 1.2f, 0.5f}, 1.1f, 2, obj++, glass);
  add_sphere(s, {1.8f, 1.0f, -1.0f}, 0.9f, 2, obj++, mirror);
  for (int i = 0; i < 5; ++i) {
    float x = -4 + 2.0f * i, z = 2.5f;
    add_quad(s, {x, 0.0f, z}, {x + 0.6f, 0.0f, z}, {x + 0.6f, 1.2f, z}, {x, 1.2f, z}, obj++, red);
  }
  s.num_objects = obj;
  two_lights_and_view(s, width);
  s.max_depth = depth;
  s.ambient = {0.1f, 0.1f, 0.1f};
  return s;
}

// A w x h texture whose texel (i, j) has sRGB codes (r, g, b) = f(i, j).
template <typename F>
inline Texture make_texture(int w, int h, F code) {
  Texture t;
  t.path = "generated";
  t.width = w;
  t.height = h;
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      const std::array<int, 3> c = code(i, j);
      t.texels.push_back(std::uint32_t(c[0]) | std::uint32_t(c[1]) << 8 | std::uint32_t(c[2]) << 16);
    }
  return t;
}

// Vertex attributes of one triangle.
inline int add_attributes(Scene& s, std::array<Vec3, 3> n, std::array<std::array<float, 2>, 3> uv, bool normals,
                          bool uvs) {
  VertexAttributes a;
  a.normal = n;
  a.uv = uv;
  a.has_normals = normals;
  a.has_uv = uvs;
  s.attributes.push_back(a);
  return static_cast<int>(s.attributes.size()) - 1;
}

// CONTRACT's barycentric attributes at work: a texture-mapped floor (coordinates
// running past [0, 1), so the map repeats), a textured sphere and a plain
// sphere with vertex normals (smooth when scene.smooth), a mirror that
// reflects them, and one facet with coordinates but no map. Two lights.
inline Scene textured_smooth_scene(int width, bool smooth) {
  Scene s;
  s.materials.push_back(MaterialDesc::default_material());
  s.textures.push_back(make_texture(16, 16, [](int i, int j) {
    const bool dark = ((i / 4) + (j / 4)) % 2 == 1;
    return std::array<int, 3>{dark ? 40 : 230, dark ? 90 : 200, (i * 16) % 256};
  }));
  s.textures.push_back(make_texture(5, 3, [](int i, int j) { return std::array<int, 3>{50 * i, 120 * j % 256, 200}; }));
  int floor = add_material(s, {0.3f, 0.3f, 0.3f}, {0.9f, 0.9f, 0.9f}, {0, 0, 0}, 1, {0, 0, 0}, 1, 2);
  s.materials[floor].map_kd = 0;
  s.materials[floor].map_ka = 0;
  int ball = add_material(s, {0.2f, 0.2f, 0.2f}, {0.8f, 0.8f, 0.8f}, {0.3f, 0.3f, 0.3f}, 30, {0, 0, 0}, 1, 2);
  s.materials[ball].map_kd = 1;
  int shiny = add_material(s, {0.1f, 0.1f, 0.2f}, {0.3f, 0.3f, 0.7f}, {0.6f, 0.6f, 0.6f}, 40, {0, 0, 0}, 1, 3);
  int mirror = add_material(s, {0.02f, 0.02f, 0.02f}, {0.05f, 0.05f, 0.05f}, {0.85f, 0.85f, 0.85f}, 80, {0, 0, 0}, 1, 3);
  int obj = 0;
  // Floor: one quad facet, coordinates 0..3 (the map repeats three times).
  const Vec3 up{0, 1, 0};
  const Vec3 a{-5, 0, -5}, b{-5, 0, 5}, c{5, 0, 5}, d{5, 0, -5};
  int f = s.num_facets++;
  Triangle t1{a, b, c, f, obj, floor};
  t1.attributes = add_attributes(s, {up, up, up}, {{{-0.2f, 3.1f}, {-0.2f, -0.1f}, {2.9f, -0.1f}}}, false, true);
  Triangle t2{a, c, d, f, obj, floor};
  t2.attributes = add_attributes(s, {up, up, up}, {{{-0.2f, 3.1f}, {2.9f, -0.1f}, {2.9f, 3.1f}}}, false, true);
  s.triangles.push_back(t1);
  s.triangles.push_back(t2);
  ++obj;
  add_quad(s, {-5, 0, -4}, {5, 0, -4}, {5, 4, -4}, {-5, 4, -4}, obj++, mirror);
  // Spheres: vertex normals = directions from the centre; the textured one
  // gets longitude/latitude coordinates.
  const auto sphere = [&](Vec3 centre, float r, int material, bool uv) {
    const std::size_t first = s.triangles.size();
    add_sphere(s, centre, r, 2, obj++, material);
    for (std::size_t k = first; k < s.triangles.size(); ++k) {
      Triangle& t = s.triangles[k];
      std::array<Vec3, 3> n;
      std::array<std::array<float, 2>, 3> st;
      const Vec3* v[3] = {&t.v0, &t.v1, &t.v2};
      for (int q = 0; q < 3; ++q) {
        for (int e = 0; e < 3; ++e) n[q][e] = ((*v[q])[e] - centre[e]) / r;
        st[q] = {0.5f + std::atan2(n[q][2], n[q][0]) / 6.2831853f, 0.5f + std::asin(std::max(-1.0f, std::min(1.0f, n[q][1]))) / 3.1415927f};
      }
      t.attributes = add_attributes(s, n, st, true, uv);
    }
  };
  sphere({-1.3f, 1.1f, 0.3f}, 1.0f, ball, true);
  sphere({1.5f, 0.9f, -0.8f}, 0.9f, shiny, false);
  // Coordinates without a map: nothing changes.
  f = s.num_facets++;
  Triangle plain{{2.5f, 0.01f, 1.5f}, {3.5f, 0.01f, 2.5f}, {3.5f, 0.01f, 1.0f}, f, obj++, 0};
  plain.attributes = add_attributes(s, {up, up, up}, {{{0, 0}, {1, 0}, {1, 1}}}, false, true);
  s.triangles.push_back(plain);
  s.num_objects = obj;
  two_lights_and_view(s, width);
  s.max_depth = 4;
  s.ambient = {0.15f, 0.15f, 0.15f};
  s.smooth = smooth;
  return s;
}

// Where the nearest hit is decided by the hit order's ids, not by distance
// (kernels/hit_order.h): a grid of non-planar quads (two fan triangles
// meeting at a crease), non-planar hexagons (fans of four), and coincident
// facets of two objects (the same quad in two colours; the same square cut
// along either diagonal), seen directly and in a mirror sphere. Facet ids
// grow with object ids, as every reader numbers them. cells: the grid's
// quads per side.
inline Scene tie_scene(int width, int cells) {
  Scene s;
  const int grey = add_material(s, {0.1f, 0.1f, 0.1f}, {0.7f, 0.7f, 0.6f}, {0.3f, 0.3f, 0.3f}, 20, {0, 0, 0}, 1, 2);
  const int red = add_material(s, {0.1f, 0, 0}, {0.9f, 0.1f, 0.1f}, {0, 0, 0}, 1, {0, 0, 0}, 1, 1);
  const int blue = add_material(s, {0, 0, 0.1f}, {0.1f, 0.2f, 0.9f}, {0, 0, 0}, 1, {0, 0, 0}, 1, 1);
  const int mirror = add_material(s, {0, 0, 0}, {0.1f, 0.1f, 0.1f}, {0.8f, 0.8f, 0.8f}, 50, {0, 0, 0}, 1, 3);
  int obj = 0;
  const auto height = [](float x, float z) {
    return 0.4f * std::sin(1.7f * x) * std::cos(1.3f * z) + 0.1f * std::sin(5.1f * x + 2.3f * z);
  };
  const float step = 8.0f / float(cells);
  for (int j = 0; j < cells; ++j)
    for (int i = 0; i < cells; ++i) {
      const float x0 = -4 + step * float(i), z0 = -4 + step * float(j), x1 = x0 + step, z1 = z0 + step;
      add_quad(s, {x0, height(x0, z0), z0}, {x0, height(x0, z1) + 0.03f, z1}, {x1, height(x1, z1), z1},
               {x1, height(x1, z0) - 0.03f, z0}, obj, grey);
    }
  ++obj;
  for (int h = 0; h < 3; ++h) {  // non-planar hexagons standing up: fans of four
    const float cx = -2.0f + 2.0f * float(h);
    const int f = s.num_facets++;
    std::vector<Vec3> v;
    for (int k = 0; k < 6; ++k) {
      const float a = 1.0471976f * float(k);
      v.push_back({cx + 0.7f * std::cos(a), 1.2f + 0.7f * std::sin(a), -1.5f + 0.25f * float(k % 2)});
    }
    for (int k = 1; k + 1 < 6; ++k) s.triangles.push_back({v[0], v[std::size_t(k)], v[std::size_t(k) + 1], f, obj, grey, -1, k - 1});
    ++obj;
  }
  const Vec3 a{-3.5f, 0.9f, 1.0f}, b{-3.5f, 2.4f, 1.0f}, c{-1.5f, 2.4f, 1.0f}, d{-1.5f, 0.9f, 1.0f};
  add_quad(s, a, b, c, d, obj++, red);  // coincident, same triangles: the lower object (red) shows
  add_quad(s, a, b, c, d, obj++, blue);
  const Vec3 e{1.0f, 0.9f, 1.0f}, g{1.0f, 2.4f, 1.0f}, h{3.0f, 2.4f, 1.0f}, k{3.0f, 0.9f, 1.0f};
  add_quad(s, e, g, h, k, obj++, blue);  // coincident, the other diagonal: float noise may not decide
  add_quad(s, g, h, k, e, obj++, red);
  add_sphere(s, {0.0f, 2.2f, -3.2f}, 1.0f, 2, obj++, mirror);
  s.num_objects = obj;
  s.camera.eye = {0.3f, 4.5f, 8.0f};
  s.camera.look_at = {0.0f, 0.6f, 0.0f};
  s.camera.fov_deg = 50;
  s.width = width;
  s.height = width * 3 / 4;
  s.lights.push_back({{4, 8, 6}, {0.9f, 0.9f, 0.9f}});
  s.lights.push_back({{-6, 5, 2}, {0.4f, 0.4f, 0.5f}});
  s.ambient = {0.1f, 0.1f, 0.1f};
  s.max_depth = 3;
  return s;
}

}  // namespace opsila::test
