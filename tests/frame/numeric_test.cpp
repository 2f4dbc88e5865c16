// Numerical edge cases (docs/RELIABILITY.md): shared edges and vertices (no
// cracks), rays grazing or parallel to facets, very large and very small
// coordinates, Ni = 1, Ns = 0, total internal reflection, lights in a facet's
// plane. Each compares the OpenCL renderer with hand-computed values and/or
// the sequential reference (host/reference/reference.h).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "prepare/prepare_banks.h"
#include "reference/reference.h"
#include "frame/renderer.h"
#include "test_device.h"
#include "test_scenes.h"
#include "test_util.h"

namespace opsila {
namespace {

ClRuntime& runtime() { return test::shared_runtime(); }

RenderResult render_cl(const Scene& s, int pes = 4) {
  RenderSettings settings;
  settings.num_pes = pes;
  return render(s, settings, runtime());
}

std::size_t non_finite(const std::vector<float>& rgb) {
  std::size_t n = 0;
  for (float v : rgb) n += !std::isfinite(v);
  return n;
}

using test::item_agreement;

Scene empty_scene(int w, int h, Vec3 eye, Vec3 look_at, float fov, int depth) {
  Scene s;
  s.width = w;
  s.height = h;
  s.camera.eye = eye;
  s.camera.look_at = look_at;
  s.camera.fov_deg = fov;
  s.max_depth = depth;
  s.ambient = {1, 1, 1};
  s.background = {0, 0, 0};
  s.has_camera = s.has_lights = true;
  return s;
}

int material(Scene& s, Vec3 ka, Vec3 kd, Vec3 ks, float ns, Vec3 tf, float ni, int illum) {
  return test::add_material(s, ka, kd, ks, ns, tf, ni, illum);
}

// ------------------------------------------------------- shared edges: cracks

// A grid of quads in the plane through `origin` spanned by `du`, `dv`, each
// quad two triangles, the diagonal alternating, so that vertices are shared
// by 4, 6 or 8 triangles. Vertices are computed once and reused exactly.
void add_grid(Scene& s, Vec3 origin, Vec3 du, Vec3 dv, int nu, int nv, int object, int mat) {
  auto at = [&](int i, int j) {
    return Vec3{origin[0] + i * du[0] + j * dv[0], origin[1] + i * du[1] + j * dv[1],
                origin[2] + i * du[2] + j * dv[2]};
  };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const Vec3 a = at(i, j), b = at(i + 1, j), c = at(i + 1, j + 1), d = at(i, j + 1);
      const int f = s.num_facets++;
      if ((i + j) % 2) {
        s.triangles.push_back({a, b, c, f, object, mat});
        s.triangles.push_back({a, c, d, f, object, mat, -1, 1});
      } else {
        s.triangles.push_back({a, b, d, f, object, mat});
        s.triangles.push_back({b, c, d, f, object, mat, -1, 1});
      }
    }
}

std::size_t red_pixels(const std::vector<float>& rgb) {
  std::size_t n = 0;
  for (std::size_t p = 0; p < rgb.size(); p += 3) n += rgb[p] != 0.0f;
  return n;
}

std::size_t missed_items(const std::vector<std::int32_t>& items) {
  std::size_t n = 0;
  for (std::size_t i = 0; i < items.size(); i += 2) n += items[i] < 0;
  return n;
}

// Straight at a plane grid whose vertices sit where the pixel-centre rays
// land (to rounding), and whose edges run along pixel rows and columns:
// every primary ray meets the grid on an edge or at a vertex. The background
// is red and the grid has no red: a red pixel is a crack.
TEST(Numeric, NoCracksWherePixelRaysHitGridVertices) {
  for (int size : {64, 65}) {
    Scene s = empty_scene(size, size, {0, 0, 0}, {0, 0, -1}, 90, 1);
    s.background = {1, 0, 0};
    const int grey = material(s, {0, 0.5f, 0.5f}, {0, 0, 0}, {0, 0, 0}, 1, {0, 0, 0}, 1, 2);
    const float step = 2.0f / size;  // pixel pitch on the plane z = -1
    const float first = -1.0f + 0.5f * step - 8 * step;
    add_grid(s, {first, first, -1}, {step, 0, 0}, {0, step, 0}, size + 16, size + 16, 0, grey);
    s.num_objects = 1;
    for (int pes : {1, 4, 16}) {
      RenderResult r = render_cl(s, pes);
      EXPECT_EQ(missed_items(r.item_buffer), 0u) << size << "x" << size << ", " << pes << " PEs";
      EXPECT_EQ(red_pixels(r.rgb), 0u) << size << "x" << size << ", " << pes << " PEs";
    }
  }
}

// The box [-1, 1]^3 from inside: six faces of grids from one exact vertex
// lattice, so faces meet exactly along the cube's edges.
Scene mirror_box(int depth) {
  Scene s = empty_scene(96, 72, {0.3f, -0.2f, 0.1f}, {1, 1, 1}, 70, depth);
  s.background = {1, 0, 0};
  const int mirror = material(s, {0, 0.2f, 0.3f}, {0, 0, 0}, {0.6f, 0.6f, 0.6f}, 1, {0, 0, 0}, 1, 3);
  const int n = 16;
  const float h = 2.0f / n;  // exact
  add_grid(s, {-1, -1, -1}, {h, 0, 0}, {0, h, 0}, n, n, 0, mirror);  // z = -1
  add_grid(s, {-1, -1, 1}, {0, h, 0}, {h, 0, 0}, n, n, 1, mirror);   // z = +1
  add_grid(s, {-1, -1, -1}, {0, h, 0}, {0, 0, h}, n, n, 2, mirror);  // x = -1
  add_grid(s, {1, -1, -1}, {0, 0, h}, {0, h, 0}, n, n, 3, mirror);   // x = +1
  add_grid(s, {-1, -1, -1}, {0, 0, h}, {h, 0, 0}, n, n, 4, mirror);  // y = -1
  add_grid(s, {-1, 1, -1}, {h, 0, 0}, {0, 0, h}, n, n, 5, mirror);   // y = +1
  s.num_objects = 6;
  return s;
}

// Follows a ray bouncing inside the mirror box in double precision. True if
// one of its first `bounces` reflection points lies within `reach` of another
// face: there CONTRACT's rule (secondary rays ignore hits with t <= epsilon) lets
// the reflected ray pass the corner. Escaping any other way is a crack.
bool bounces_near_an_edge(const Vec3& eye, const Vec3& dir, int bounces, double reach) {
  double p[3] = {eye[0], eye[1], eye[2]}, d[3] = {dir[0], dir[1], dir[2]};
  for (int b = 0; b < bounces; ++b) {
    double t = INFINITY;
    int axis = 0;
    for (int a = 0; a < 3; ++a)
      if (d[a] != 0) {
        const double ta = ((d[a] > 0 ? 1.0 : -1.0) - p[a]) / d[a];
        if (ta < t) t = ta, axis = a;
      }
    for (int a = 0; a < 3; ++a) p[a] += t * d[a];
    for (int a = 0; a < 3; ++a)
      if (a != axis && 1.0 - std::fabs(p[a]) < reach) return true;
    d[axis] = -d[axis];
  }
  return false;
}

// From inside a closed box of mirrors made of grids, looking into a corner
// (three faces, their shared edges and the corner vertex in view). The
// background is red, the box has no red: every primary ray must hit a facet;
// a reflected ray may only escape where CONTRACT's epsilon lets it pass a corner.
TEST(Numeric, NoCracksInsideAClosedMirrorBox) {
  for (int pes : {1, 8}) {
    const Scene primary = mirror_box(1);
    RenderResult r = render_cl(primary, pes);
    EXPECT_EQ(missed_items(r.item_buffer), 0u) << pes << " PEs";
    EXPECT_EQ(red_pixels(r.rgb), 0u) << pes << " PEs";
  }
  const Scene s = mirror_box(4);
  const double reach = 2.0 * s.epsilon();
  for (int pes : {1, 8}) {
    RenderResult r = render_cl(s, pes);
    EXPECT_EQ(non_finite(r.rgb), 0u);
    std::size_t escaped = 0;
    test::for_each_primary_ray(s, [&](int x, int y, const Vec3& dir) {
      if (r.rgb[3 * (std::size_t(y) * s.width + x)] == 0.0f) return;
      ++escaped;
      EXPECT_TRUE(bounces_near_an_edge(s.camera.eye, dir, s.max_depth - 1, reach))
          << pes << " PEs: pixel " << x << "," << y << " leaked away from any edge";
    });
    EXPECT_LE(escaped, std::size_t(s.width * s.height / 500)) << pes << " PEs";
  }
}

// A tilted view of a fine grid: the edges cross pixel rays at every angle.
TEST(Numeric, NoCracksInATiltedGrid) {
  Scene s = empty_scene(120, 90, {0.31f, 2.7f, 1.9f}, {-0.4f, 0, -2.3f}, 60, 1);
  s.background = {1, 0, 0};
  const int grey = material(s, {0, 0.5f, 0.5f}, {0, 0, 0}, {0, 0, 0}, 1, {0, 0, 0}, 1, 2);
  add_grid(s, {-20, 0, -30}, {0.37f, 0, 0.05f}, {-0.05f, 0, 0.37f}, 110, 110, 0, grey);
  s.num_objects = 1;
  RenderResult r = render_cl(s, 4);
  ImageResult ref = render_reference(s);
  // The horizon shows background; below it, nothing may leak through.
  std::size_t leaks = 0;
  for (int y = 0; y < s.height; ++y)
    for (int x = 0; x < s.width; ++x) {
      const std::size_t i = std::size_t(y) * s.width + x;
      if (ref.item_buffer[2 * i] >= 0 && r.item_buffer[2 * i] < 0) ++leaks;
    }
  EXPECT_EQ(leaks, 0u);
  EXPECT_GE(item_agreement(r.item_buffer, ref.item_buffer), 0.99);
}

// --------------------------------------------------- grazing and parallel rays

// The eye in the floor's plane, then just above it: the middle row of pixels
// (odd height) runs parallel to the floor, rows below it graze the floor. A
// wall edge-on to the eye (its plane contains the eye) shows at most as a
// line. Exactly parallel rays never hit a facet (zero determinant).
TEST(Numeric, RaysGrazingAndParallelToFacets) {
  for (float height : {0.0f, 0.05f}) {
    // A narrow view (10 degrees): each pixel row below the horizon meets the
    // floor at a grazing angle of a fraction of a degree.
    Scene s = empty_scene(61, 41, {0, height, 6}, {0, height, 0}, 10, 3);
    s.ambient = {0.2f, 0.2f, 0.2f};
    s.background = {0.1f, 0.2f, 0.4f};
    const int floor_mat =
        material(s, {0.6f, 0.6f, 0.6f}, {0.5f, 0.5f, 0.5f}, {0.3f, 0.3f, 0.3f}, 10, {0, 0, 0}, 1, 3);
    const int wall_mat = material(s, {0.2f, 0.5f, 0.2f}, {0.4f, 0.7f, 0.3f}, {0, 0, 0}, 1, {0, 0, 0}, 1, 2);
    const int back_mat = material(s, {0.5f, 0.2f, 0.2f}, {0.7f, 0.3f, 0.3f}, {0, 0, 0}, 1, {0, 0, 0}, 1, 2);
    add_grid(s, {-12, 0, -60}, {2, 0, 0}, {0, 0, 2.5f}, 12, 26, 0, floor_mat);  // y = 0, z up to 5
    add_grid(s, {0, -2, -4}, {0, 0, 1}, {0, 1, 0}, 6, 4, 1, wall_mat);          // x = 0, edge-on to the eye
    add_grid(s, {-12, -3, -61}, {2, 0, 0}, {0, 1, 0}, 12, 6, 2, back_mat);      // back wall
    s.num_objects = 3;
    s.lights.push_back({{3, 4, 4}, {0.8f, 0.8f, 0.8f}});
    const RenderResult r = render_cl(s, 4);
    const ImageResult ref = render_reference(s);
    EXPECT_EQ(non_finite(r.rgb), 0u);
    EXPECT_EQ(non_finite(ref.rgb), 0u);
    const int mid = s.height / 2, centre = s.width / 2;
    for (int x = 0; x < s.width; ++x)
      EXPECT_NE(r.item_buffer[2 * (std::size_t(mid) * s.width + x)], 0) << "a parallel ray hit the floor, x=" << x;
    for (int y = 0; y < s.height; ++y)
      EXPECT_NE(r.item_buffer[2 * (std::size_t(y) * s.width + centre)], 1) << "an in-plane ray hit the wall, y=" << y;
    std::size_t floor_hits = 0;
    for (std::size_t i = 0; i < r.item_buffer.size(); i += 2) floor_hits += r.item_buffer[i] == 0;
    if (height > 0) EXPECT_GT(floor_hits, std::size_t(4 * s.width)) << "rows below the horizon graze the floor";
    EXPECT_GE(item_agreement(r.item_buffer, ref.item_buffer), 0.98) << "eye height " << height;
    EXPECT_GE(test::clamped_psnr(r.rgb, ref.rgb), 35.0) << "eye height " << height;
    EXPECT_LE(test::fraction_off(r.rgb, ref.rgb, 2), 0.03) << "eye height " << height;
  }
}

// ----------------------------------------------------- large and small scenes

Scene scaled(const Scene& s, double k) {
  Scene out = s;
  auto scale = [k](Vec3& v) {
    for (float& c : v) c = static_cast<float>(double(c) * k);
  };
  for (Triangle& t : out.triangles) scale(t.v0), scale(t.v1), scale(t.v2);
  for (LightDesc& l : out.lights) scale(l.position);
  scale(out.camera.eye);
  scale(out.camera.look_at);
  return out;
}

// Epsilon is 1e-4 of the scene's diagonal, so the image must not depend on
// the unit. Powers of two scale every float exactly: the image must be the
// same up to the constants in the kernels. Powers of ten round every vertex:
// the same up to pixels whose rays pass within rounding of an edge.
TEST(Numeric, LargeAndSmallCoordinatesGiveTheSameImage) {
  const Scene base_scene = test::mirror_glass_scene(48, 4);
  check_scene_extent(base_scene, "base");
  const RenderResult base = render_cl(base_scene);
  for (int e : {-20, 20, 40, 50}) {
    const double k = std::ldexp(1.0, e);
    const Scene s = scaled(base_scene, k);
    check_scene_extent(s, "scaled");
    const RenderResult r = render_cl(s);
    EXPECT_EQ(non_finite(r.rgb), 0u) << "scale 2^" << e;
    EXPECT_GE(test::clamped_psnr(r.rgb, base.rgb), 60.0) << "scale 2^" << e;
    EXPECT_GE(item_agreement(r.item_buffer, base.item_buffer), 0.999) << "scale 2^" << e;
  }
  for (double k : {1e-6, 1e6, 1e9, 1e12, 1e15}) {
    const Scene s = scaled(base_scene, k);
    const RenderResult r = render_cl(s);
    EXPECT_EQ(non_finite(r.rgb), 0u) << "scale " << k;
    EXPECT_GE(test::clamped_psnr(r.rgb, base.rgb), 40.0) << "scale " << k;
    EXPECT_LE(test::fraction_off(r.rgb, base.rgb, 2), 0.01) << "scale " << k;
    EXPECT_GE(item_agreement(r.item_buffer, base.item_buffer), 0.99) << "scale " << k;
  }
  // The reference agrees at the small and large ends it shares with the kernels.
  for (double k : {1e-6, 1e6}) {
    const Scene s = scaled(base_scene, k);
    EXPECT_GE(test::clamped_psnr(render_cl(s).rgb, render_reference(s).rgb), 40.0) << "scale " << k;
  }
}

// ------------------------------------------------------------ materials

// A pane with Ni = 1 and Tf = 1 (nothing else) in front of a backdrop, lit
// by ambient light only: rays go straight through, so the image is the one
// without the pane.
TEST(Numeric, GlassWithIndexOneDoesNotBend) {
  Scene without = empty_scene(64, 48, {0.2f, 0.1f, 5}, {0, 0, 0}, 40, 3);
  without.background = {0.1f, 0.1f, 0.1f};
  const int a = material(without, {0.9f, 0.3f, 0.1f}, {0, 0, 0}, {0, 0, 0}, 1, {0, 0, 0}, 1, 2);
  const int b = material(without, {0.1f, 0.4f, 0.9f}, {0, 0, 0}, {0, 0, 0}, 1, {0, 0, 0}, 1, 2);
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 10; ++j)
      test::add_quad(without, {-5.0f + i, -5.0f + j, -3}, {-4.0f + i, -5.0f + j, -3}, {-4.0f + i, -4.0f + j, -3},
                     {-5.0f + i, -4.0f + j, -3}, 0, (i + j) % 2 ? a : b);
  without.num_objects = 1;
  Scene with = without;
  const int pane = material(with, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}, 1, {1, 1, 1}, 1.0f, 6);
  test::add_quad(with, {-1.3f, -0.9f, 1}, {1.1f, -0.9f, 1}, {1.1f, 1.2f, 1}, {-1.3f, 1.2f, 1}, 1, pane);
  with.num_objects = 2;

  const RenderResult r_without = render_cl(without), r_with = render_cl(with);
  // The pane is really there: the primary rays of its pixels hit it.
  std::size_t on_pane = 0;
  for (std::size_t i = 0; i < r_with.item_buffer.size(); i += 2) on_pane += r_with.item_buffer[i] == 1;
  EXPECT_GT(on_pane, 64u * 48u / 8);
  EXPECT_GE(test::clamped_psnr(r_with.rgb, r_without.rgb), 50.0);
  EXPECT_LE(test::fraction_off(r_with.rgb, r_without.rgb, 1), 0.005);
  const ImageResult ref = render_reference(with);
  EXPECT_GE(test::clamped_psnr(r_with.rgb, ref.rgb), 50.0);
}

// Ns = 0: pow(x, 0) = 1 for every x, 0 included (C's powf and OpenCL's pow
// agree), so the highlight is the full Ks wherever n.Lv > 0, even where the
// reflected light points away from the eye (max(0, Rl.(-D)) = 0).
TEST(Numeric, ShininessZeroGivesTheFullSpecularColour) {
  Scene s = empty_scene(48, 36, {-3, 3, 2}, {0, 0, -1}, 60, 1);
  s.ambient = {0, 0, 0};
  const Vec3 ks{0.25f, 0.5f, 0.75f};
  const int shiny = material(s, {0, 0, 0}, {0, 0, 0}, ks, 0.0f, {0, 0, 0}, 1, 2);
  add_grid(s, {-20, 0, -20}, {40, 0, 0}, {0, 0, 40}, 1, 1, 0, shiny);
  s.num_objects = 1;
  const Vec3 light{-30, 0.5f, -1};
  s.lights.push_back({light, {1, 1, 1}});
  const RenderResult r = render_cl(s);
  const ImageResult ref = render_reference(s);

  // Hand computation (double precision): which floor points see the
  // reflected light direction pointing away from the eye?
  std::size_t floor_pixels = 0, away = 0;
  test::for_each_primary_ray(s, [&](int x, int y, const Vec3& d) {
    const std::size_t i = std::size_t(y) * s.width + x;
    if (r.item_buffer[2 * i] != 0) return;
    ++floor_pixels;
    const double t = -double(s.camera.eye[1]) / d[1];
    double p[3], l[3], len = 0;
    for (int k = 0; k < 3; ++k) p[k] = s.camera.eye[k] + t * d[k], l[k] = light[k] - p[k], len += l[k] * l[k];
    len = std::sqrt(len);
    for (double& c : l) c /= len;
    const double rl[3] = {-l[0], 2 * l[1] - l[1], -l[2]};  // 2(n.L)n - L with n = +y
    const double r_dot_v = -(rl[0] * d[0] + rl[1] * d[1] + rl[2] * d[2]);
    if (r_dot_v < -1e-3) ++away;
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(r.rgb[3 * i + c], ks[c], 1e-6) << "pixel " << x << "," << y;
      EXPECT_NEAR(ref.rgb[3 * i + c], ks[c], 1e-6) << "reference pixel " << x << "," << y;
    }
  });
  EXPECT_GT(floor_pixels, std::size_t(s.width * s.height / 3));
  EXPECT_GT(away, floor_pixels / 4) << "the scene must exercise pow(0, 0)";
}

// Rays leaving glass (Ni = 1.5) through a plane: beyond the critical angle
// (sin > 1/1.5) there is no transmitted ray. Background blue, nothing else
// lit: blue = Ka + kr * background (reflected, misses) + kt * background
// (transmitted, when there is one).
TEST(Numeric, TotalInternalReflection) {
  for (bool leaving : {true, false}) {
    Scene s = empty_scene(41, 41, {0, 0, 0}, {0, 0, -1}, 120, 2);
    s.background = {0, 0, 1};
    const int glass = material(s, {0.2f, 0.2f, 0.2f}, {0, 0, 0}, {0.5f, 0.5f, 0.5f}, 1, {1, 1, 1}, 1.5f, 7);
    // Counter-clockwise seen from the camera: Ng towards it (rays enter).
    const Vec3 a{-100, -100, -1}, b{100, -100, -1}, c{100, 100, -1}, d{-100, 100, -1};
    if (leaving)
      test::add_quad(s, a, d, c, b, 0, glass);
    else
      test::add_quad(s, a, b, c, d, 0, glass);
    s.num_objects = 1;
    const RenderResult r = render_cl(s);
    const ImageResult ref = render_reference(s);
    std::size_t tir = 0, checked = 0;
    test::for_each_primary_ray(s, [&](int x, int y, const Vec3& dir) {
      const double cos_t = -double(dir[2]), eta = leaving ? 1.5 : 1.0 / 1.5;
      const double k = 1 - eta * eta * (1 - cos_t * cos_t);
      if (std::fabs(k) < 1e-3) return;  // too close to the critical angle to call
      ++checked;
      tir += k < 0;
      const std::size_t i = std::size_t(y) * s.width + x;
      const float blue = 0.2f + 0.5f + (k < 0 ? 0.0f : 1.0f);
      EXPECT_NEAR(r.rgb[3 * i + 2], blue, 1e-5) << (leaving ? "leaving" : "entering") << " pixel " << x << "," << y;
      EXPECT_NEAR(r.rgb[3 * i + 0], 0.2f, 1e-5);
      EXPECT_NEAR(ref.rgb[3 * i + 2], blue, 1e-5) << "reference pixel " << x << "," << y;
    });
    EXPECT_GT(checked, 41u * 41u * 9 / 10);
    if (leaving)
      EXPECT_GT(tir, checked / 4) << "the view must reach beyond the critical angle";
    else
      EXPECT_EQ(tir, 0u);
  }
}

// A light in the floor's plane, beside the floor and then on it: for every
// floor point n.Lv = 0 in exact arithmetic, so the floor shows its ambient
// term only (to rounding: n.Lv is a rounding error, times Kd; Ks = 0).
// Blocks standing on the floor are lit as usual and, with the light beside
// the floor, agree with the reference. With the light on the floor, a shadow
// ray meets the floor at t = |light - P| itself, which CONTRACT's open interval
// excludes but rounding may not: which block pixels are lit is then not
// defined to the last bit (docs/RELIABILITY.md), so only the floor is checked.
TEST(Numeric, LightInTheFacetPlane) {
  for (const Vec3 light : {Vec3{6, 0, 2.5f}, Vec3{0.5f, 0, 2.5f}}) {
    Scene s = empty_scene(64, 48, {1, 5, 7}, {0, 0, 0}, 50, 2);
    s.ambient = {0.2f, 0.2f, 0.2f};
    const int floor_mat = material(s, {0.5f, 0.5f, 0.5f}, {0.8f, 0.8f, 0.8f}, {0, 0, 0}, 1, {0, 0, 0}, 1, 2);
    const int block = material(s, {0.3f, 0.1f, 0.1f}, {0.8f, 0.3f, 0.2f}, {0, 0, 0}, 1, {0, 0, 0}, 1, 2);
    add_grid(s, {-4, 0, -4}, {1, 0, 0}, {0, 0, 1}, 8, 8, 0, floor_mat);
    // Two blocks (two faces each), facing the light from different sides.
    test::add_quad(s, {-2, 0, 1}, {-1, 0, 1}, {-1, 1.5f, 1}, {-2, 1.5f, 1}, 1, block);
    test::add_quad(s, {-1, 0, 1}, {-1, 0, 0}, {-1, 1.5f, 0}, {-1, 1.5f, 1}, 1, block);
    test::add_quad(s, {1, 0, -1}, {2, 0, -1}, {2, 1, -1}, {1, 1, -1}, 2, block);
    test::add_quad(s, {1, 0, -1}, {1, 0, -2}, {1, 1, -2}, {1, 1, -1}, 2, block);
    s.num_objects = 3;
    s.lights.push_back({light, {0.9f, 0.9f, 0.9f}});
    const RenderResult r = render_cl(s);
    const ImageResult ref = render_reference(s);
    EXPECT_EQ(non_finite(r.rgb), 0u);
    std::size_t floor_pixels = 0;
    for (std::size_t i = 0; i < r.item_buffer.size() / 2; ++i) {
      if (r.item_buffer[2 * i] != 0) continue;
      ++floor_pixels;
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(r.rgb[3 * i + c], 0.2f * 0.5f, 1e-5) << "floor pixel " << i;
    }
    EXPECT_GT(floor_pixels, r.item_buffer.size() / 8);
    EXPECT_GE(item_agreement(r.item_buffer, ref.item_buffer), 0.99) << "light x " << light[0];
    const bool beside_the_floor = light[0] > 4;
    if (!beside_the_floor) continue;
    EXPECT_GE(test::clamped_psnr(r.rgb, ref.rgb), 40.0);
    EXPECT_LE(test::fraction_off(r.rgb, ref.rgb, 2), 0.01);
  }
}

}  // namespace
}  // namespace opsila
