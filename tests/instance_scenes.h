// Instanced scenes built in code: a floor of the scene's own and models
// placed at many transforms (rotated, scaled unevenly, mirrored, glass),
// and the same scene with every instance written out as objects of its own,
// for the tests of the renderer, the reference and the partition.
#pragma once

#include <array>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "scene/instances.h"
#include "test_scenes.h"

namespace opsila::test {

// The triangles `build` adds to a scratch scene, as a model: facet ids from
// 0, object 0, materials of `s` (the scratch scene shares s's table).
template <class Build>
inline int add_prototype(Scene& s, const std::string& name, Build build) {
  Scene scratch;
  scratch.materials = s.materials;
  build(scratch);
  Prototype p;
  p.name = name;
  p.triangles = std::move(scratch.triangles);
  int first = p.triangles.empty() ? 0 : p.triangles.front().facet_id;
  Box b;
  for (Triangle& t : p.triangles) {
    t.facet_id -= first;
    t.object_id = 0;
    b.grow(t.v0), b.grow(t.v1), b.grow(t.v2);
    p.num_facets = std::max(p.num_facets, t.facet_id + 1);
  }
  p.lo = b.lo, p.hi = b.hi;
  s.prototypes.push_back(std::move(p));
  return static_cast<int>(s.prototypes.size()) - 1;
}

// Model to world: translate(t) * Ry(deg) * Rx(deg_x) * scale(sx, sy, sz).
inline std::array<double, 12> placement(Vec3 t, double ry_deg, double rx_deg, Vec3 scale) {
  const double a = ry_deg * M_PI / 180, b = rx_deg * M_PI / 180;
  const double cy = std::cos(a), sy = std::sin(a), cx = std::cos(b), sx = std::sin(b);
  // Ry * Rx, then the columns scaled.
  const double r[9] = {cy, sy * sx, sy * cx, 0, cx, -sx, -sy, cy * sx, cy * cx};
  std::array<double, 12> m{};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) m[std::size_t(4 * i + j)] = r[3 * i + j] * scale[std::size_t(j)];
    m[std::size_t(4 * i + 3)] = t[std::size_t(i)];
  }
  return m;
}

// A floor, a mirror and a glass sphere of the scene's own, and a grid of
// `nx` x `nz` instances of two models (a sphere, a box) with turns, uneven
// scales and a few mirrors; two lights.
inline Scene instanced_scene(int width, int nx = 6, int nz = 5) {
  Scene s;
  const int plain = add_material(s, {0.8f, 0.8f, 0.8f}, {0.8f, 0.8f, 0.8f}, {0, 0, 0}, 1, {0, 0, 0}, 1, 2);
  const int red = add_material(s, {0.7f, 0.2f, 0.1f}, {0.7f, 0.2f, 0.1f}, {0.3f, 0.3f, 0.3f}, 30, {0, 0, 0}, 1, 2);
  const int mirror = add_material(s, {0.05f, 0.05f, 0.05f}, {0.1f, 0.1f, 0.1f}, {0.8f, 0.8f, 0.8f}, 60, {0, 0, 0}, 1, 3);
  const int glass = add_material(s, {0.02f, 0.02f, 0.02f}, {0.02f, 0.02f, 0.02f}, {0.1f, 0.1f, 0.1f}, 100,
                                 {0.9f, 0.9f, 0.9f}, 1.5f, 6);
  add_quad(s, {-8, 0, -8}, {-8, 0, 6}, {8, 0, 6}, {8, 0, -8}, 0, plain);
  add_sphere(s, {2.5f, 1.2f, 1.5f}, 0.9f, 2, 1, glass);
  add_quad(s, {-6, 0, -6}, {6, 0, -6}, {6, 4, -6}, {-6, 4, -6}, 2, mirror);
  s.num_objects = 3;
  const int ball = add_prototype(s, "ball", [&](Scene& m) { add_sphere(m, {0, 0.5f, 0}, 0.5f, 2, 0, red); });
  const int block = add_prototype(s, "block", [&](Scene& m) {
    add_quad(m, {-0.5f, 0, -0.5f}, {0.5f, 0, -0.5f}, {0.5f, 0, 0.5f}, {-0.5f, 0, 0.5f}, 0, mirror);  // bottom
    add_quad(m, {-0.5f, 1, -0.5f}, {-0.5f, 1, 0.5f}, {0.5f, 1, 0.5f}, {0.5f, 1, -0.5f}, 0, plain);   // top
    add_quad(m, {-0.5f, 0, 0.5f}, {0.5f, 0, 0.5f}, {0.5f, 1, 0.5f}, {-0.5f, 1, 0.5f}, 0, red);       // front
    add_quad(m, {0.5f, 0, -0.5f}, {-0.5f, 0, -0.5f}, {-0.5f, 1, -0.5f}, {0.5f, 1, -0.5f}, 0, plain); // back
    add_quad(m, {0.5f, 0, 0.5f}, {0.5f, 0, -0.5f}, {0.5f, 1, -0.5f}, {0.5f, 1, 0.5f}, 0, mirror);    // right
    add_quad(m, {-0.5f, 0, -0.5f}, {-0.5f, 0, 0.5f}, {-0.5f, 1, 0.5f}, {-0.5f, 1, -0.5f}, 0, red);   // left
  });
  for (int k = 0; k < nx * nz; ++k) {
    const int i = k % nx, j = k / nx;
    const Vec3 at{-4.5f + 9.0f * float(i) / float(nx - 1), 0.0f, -4.5f + 5.5f * float(j) / float(nz - 1)};
    const Vec3 scale{0.5f + 0.1f * float(k % 3), 0.6f + 0.15f * float(k % 4), 0.5f + 0.05f * float(k % 5)};
    s.instances.push_back(make_instance(k % 3 == 0 ? block : ball, placement(at, 17.0 * k, 0.0, scale), "test"));
  }
  two_lights_and_view(s, width);
  return s;
}

// The same scene with every instance's triangles taken to the world (the
// double transform, rounded) as an object of its own: instance i becomes
// object num_objects + i, its facets numbered after the scene's own.
inline Scene flattened(const Scene& s) {
  Scene f = s;
  f.prototypes.clear();
  f.instances.clear();
  for (std::size_t i = 0; i < s.instances.size(); ++i) {
    const InstanceDesc& in = s.instances[i];
    const int base = f.num_facets;
    for (Triangle t : s.prototypes[std::size_t(in.prototype)].triangles) {
      for (Vec3* v : {&t.v0, &t.v1, &t.v2}) {
        Vec3 w;
        for (int r = 0; r < 3; ++r) {
          const double* row = &in.to_world[std::size_t(4 * r)];
          w[std::size_t(r)] = static_cast<float>(row[0] * (*v)[0] + row[1] * (*v)[1] + row[2] * (*v)[2] + row[3]);
        }
        *v = w;
      }
      t.object_id = s.num_objects + static_cast<int>(i);
      t.facet_id += base;
      f.num_facets = std::max(f.num_facets, t.facet_id + 1);
      f.triangles.push_back(t);
    }
  }
  f.num_objects = s.num_objects + static_cast<int>(s.instances.size());
  return f;
}

// The item buffer of flattened(s) as s's renders say it: an instance's
// facet as its model's facet id.
inline std::vector<std::int32_t> as_instance_items(const Scene& s, std::vector<std::int32_t> items) {
  std::vector<int> base(s.instances.size());
  int next = s.num_facets;
  for (std::size_t i = 0; i < s.instances.size(); ++i) {
    base[i] = next;
    next += s.prototypes[std::size_t(s.instances[i].prototype)].num_facets;
  }
  for (std::size_t k = 0; k + 1 < items.size(); k += 2)
    if (items[k] >= s.num_objects) items[k + 1] -= base[std::size_t(items[k] - s.num_objects)];
  return items;
}

}  // namespace opsila::test
