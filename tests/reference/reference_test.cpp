// The sequential reference against values worked out by hand from docs/CONTRACT.md.
#include "reference/reference.h"

#include <gtest/gtest.h>

#include "formats/json/scene_file.h"
#include "test_scenes.h"

#include <cmath>
#include <condition_variable>
#include <cstring>
#include <mutex>
#include <random>
#include <thread>

namespace opsila {
namespace {

constexpr float kTol = 1e-5f;

MaterialDesc material(Vec3 ka, Vec3 kd, Vec3 ks = {0, 0, 0}, float ns = 1, int illum = 2, Vec3 tf = {0, 0, 0},
                      float ni = 1) {
  MaterialDesc m;
  m.ka = ka, m.kd = kd, m.ks = ks, m.ns = ns;  // colours, then the rest
  m.illum = illum, m.tf = tf, m.ni = ni;
  return m;
}

// A scene looking straight down -z from (0,0,5) at the origin; with an odd
// size the centre pixel's ray is exactly (0,0,-1).
Scene base_scene(int w = 3, int h = 3) {
  Scene s;
  s.width = w;
  s.height = h;
  s.camera.eye = {0, 0, 5};
  s.camera.look_at = {0, 0, 0};
  s.camera.up = {0, 1, 0};
  s.camera.fov_deg = 60;
  s.ambient = {0, 0, 0};
  s.background = {0, 0, 0};
  s.max_depth = 5;
  s.has_camera = true;
  s.has_lights = true;
  return s;
}

int add_material(Scene& s, const MaterialDesc& m) {
  s.materials.push_back(m);
  return static_cast<int>(s.materials.size()) - 1;
}

// Square [x0,x1] x [y0,y1] at height z, fan-triangulated from its first
// corner; counter-clockwise seen from +z (Ng = +z) unless `flip`.
void add_square(Scene& s, float x0, float x1, float y0, float y1, float z, int mat, int object, int facet,
                bool flip = false) {
  Vec3 a{x0, y0, z}, b{x1, y0, z}, c{x1, y1, z}, d{x0, y1, z};
  if (flip) std::swap(b, d);
  s.triangles.push_back({a, b, c, facet, object, mat});
  s.triangles.push_back({a, c, d, facet, object, mat, -1, 1});  // the fan's second triangle
  s.num_facets = std::max(s.num_facets, facet + 1);
  s.num_objects = std::max(s.num_objects, object + 1);
}

Vec3 pixel(const ImageResult& img, int x, int y) {
  const std::size_t i = 3 * (static_cast<std::size_t>(y) * img.width + x);
  return {img.rgb[i], img.rgb[i + 1], img.rgb[i + 2]};
}

void expect_rgb(const Vec3& got, float r, float g, float b, float tol = kTol) {
  EXPECT_NEAR(got[0], r, tol);
  EXPECT_NEAR(got[1], g, tol);
  EXPECT_NEAR(got[2], b, tol);
}

TEST(ReferenceCamera, CornerPixelDirectionsFollowSpecFormula) {
  CameraDesc cam;
  cam.eye = {1, 2, 3};
  cam.look_at = {1, 2, 2};  // f = (0,0,-1)
  cam.up = {0, 1, 0};
  cam.fov_deg = 90;  // s = 1
  const CameraFrame frame = camera_frame(cam, 4, 2);  // a = 2
  EXPECT_NEAR(frame.tan_half_fov, 1.0f, kTol);
  EXPECT_NEAR(frame.aspect, 2.0f, kTol);
  expect_rgb(frame.right, 1, 0, 0);
  expect_rgb(frame.up, 0, 1, 0);
  // (x,y) = (0,0): (2*0.5/4 - 1)*s*a = -1.5, (1 - 2*0.5/2)*s = 0.5.
  const float n00 = std::sqrt(1.5f * 1.5f + 0.25f + 1.0f);
  expect_rgb(primary_direction(frame, 4, 2, 0, 0), -1.5f / n00, 0.5f / n00, -1.0f / n00);
  // (3,1): +1.5, -0.5.
  expect_rgb(primary_direction(frame, 4, 2, 3, 1), 1.5f / n00, -0.5f / n00, -1.0f / n00);
  // (3,0): +1.5, +0.5 ; (0,1): -1.5, -0.5.
  expect_rgb(primary_direction(frame, 4, 2, 3, 0), 1.5f / n00, 0.5f / n00, -1.0f / n00);
  expect_rgb(primary_direction(frame, 4, 2, 0, 1), -1.5f / n00, -0.5f / n00, -1.0f / n00);
}

TEST(ReferenceCamera, TiltedUpVectorIsOrthogonalised) {
  CameraDesc cam;
  cam.eye = {0, 0, 0};
  cam.look_at = {0, 0, -1};
  cam.up = {0, 1, 1};  // not orthogonal to f: u = cross(r, f) must still be unit and orthogonal
  cam.fov_deg = 45;
  const CameraFrame frame = camera_frame(cam, 10, 10);
  expect_rgb(frame.up, 0, 1, 0);
  EXPECT_NEAR(frame.tan_half_fov, std::tan(22.5 * M_PI / 180.0), 1e-6);
}

// A 3 x 3 image of the plane z = 0 (a square of material `m`) lit by one
// light: the hand-computed cases below.
ImageResult lit_plane(Scene s, const MaterialDesc& m, const LightDesc& light) {
  add_square(s, -10, 10, -10, 10, 0, add_material(s, m), 0, 0);
  s.lights.push_back(light);
  return render_reference(s);
}

TEST(Reference, DiffusePlaneMatchesHandComputedLocalIntensity) {
  Scene s = base_scene();
  s.ambient = {0.1f, 0.2f, 0.3f};
  // n.Lv = 4/5
  const ImageResult img = lit_plane(s, material({0.2f, 0.3f, 0.4f}, {0.5f, 0.6f, 0.7f}), {{3, 0, 4}, {1.0f, 0.5f, 0.25f}});
  // The centre ray hits (0,0,0), on the quad's diagonal (a tie between its
  // two triangles, both facet 0). L = Ia*Ka + Il*Kd*0.8.
  expect_rgb(pixel(img, 1, 1), 0.1f * 0.2f + 1.0f * 0.5f * 0.8f, 0.2f * 0.3f + 0.5f * 0.6f * 0.8f,
             0.3f * 0.4f + 0.25f * 0.7f * 0.8f);
  EXPECT_EQ(img.item_buffer[2 * 4], 0);
  EXPECT_EQ(img.item_buffer[2 * 4 + 1], 0);
  EXPECT_EQ(img.rays.primary, 9u);
  EXPECT_EQ(img.rays.shadow, 9u);
  EXPECT_EQ(img.rays.secondary, 0u);
}

TEST(Reference, SpecularTermUsesReflectedLightVector) {
  const ImageResult img =
      lit_plane(base_scene(), material({0, 0, 0}, {0, 0, 0}, {0.5f, 0.25f, 1.0f}, 10), {{3, 0, 4}, {1, 1, 1}});
  // Rl = 2(n.Lv)n - Lv = (-0.6, 0, 0.8); Rl.(-D) = 0.8; Ks * 0.8^10.
  const float h = std::pow(0.8f, 10.0f);
  expect_rgb(pixel(img, 1, 1), 0.5f * h, 0.25f * h, 1.0f * h);
}

TEST(Reference, ShininessZeroGivesFullSpecular) {
  // powf(x, 0) = 1, so Ns = 0 adds Ks whenever the light is in front.
  const ImageResult img =
      lit_plane(base_scene(), material({0, 0, 0}, {0, 0, 0}, {0.3f, 0.3f, 0.3f}, 0), {{3, 0, 4}, {2, 2, 2}});
  expect_rgb(pixel(img, 1, 1), 0.6f, 0.6f, 0.6f);
}

TEST(Reference, LightBehindSurfaceGivesAmbientOnly) {
  Scene s = base_scene();
  s.ambient = {0.5f, 0.5f, 0.5f};
  const ImageResult img = lit_plane(s, material({0.2f, 0.4f, 0.6f}, {1, 1, 1}, {1, 1, 1}, 1), {{0, 0, -4}, {1, 1, 1}});
  expect_rgb(pixel(img, 1, 1), 0.1f, 0.2f, 0.3f);
  EXPECT_EQ(img.rays.shadow, 0u);  // n.Lv <= 0: no shadow ray is needed
}

TEST(Reference, BackFacingTriangleIsShadedWithFlippedNormal) {
  // Clockwise seen from the camera: Ng points away, entering = false, n = -Ng
  // faces the camera and the light, so the result equals the front-facing one.
  Scene front = base_scene(), back = base_scene();
  for (Scene* s : {&front, &back}) {
    const int m = add_material(*s, material({0, 0, 0}, {0.5f, 0.5f, 0.5f}));
    add_square(*s, -10, 10, -10, 10, 0, m, 0, 0, s == &back);
    s->lights.push_back({{3, 0, 4}, {1, 1, 1}});
  }
  const Vec3 a = pixel(render_reference(front), 1, 1), b = pixel(render_reference(back), 1, 1);
  expect_rgb(a, 0.4f, 0.4f, 0.4f);
  expect_rgb(b, a[0], a[1], a[2]);
}

TEST(Reference, OccluderBetweenPointAndLightCastsShadow) {
  Scene s = base_scene();
  s.ambient = {0.1f, 0.1f, 0.1f};
  const int floor = add_material(s, material({1, 1, 1}, {1, 1, 1}));
  add_square(s, -10, 10, -10, 10, 0, floor, 0, 0);
  s.lights.push_back({{4, 0, 4}, {1, 1, 1}});
  const Vec3 lit = pixel(render_reference(s), 1, 1);
  EXPECT_NEAR(lit[0], 0.1f + std::sqrt(0.5f), 1e-5f);  // n.Lv = cos 45 deg

  // A small square on the segment from (0,0,0) to the light, out of the
  // camera's view of the centre. Even a fully transparent one blocks.
  Scene shadowed = s;
  const int glass = add_material(shadowed, material({0, 0, 0}, {0, 0, 0}, {0, 0, 0}, 1, 4, {1, 1, 1}, 1));
  add_square(shadowed, 1.5f, 2.5f, -0.5f, 0.5f, 2, glass, 1, 1);
  const ImageResult img = render_reference(shadowed);
  expect_rgb(pixel(img, 1, 1), 0.1f, 0.1f, 0.1f);
  EXPECT_EQ(img.item_buffer[2 * 4 + 1], 0);  // the camera still sees the floor

  // The same square beyond the light does not block it.
  Scene beyond = s;
  add_square(beyond, 5.5f, 6.5f, -0.5f, 0.5f, 6, floor, 1, 1);
  expect_rgb(pixel(render_reference(beyond), 1, 1), lit[0], lit[1], lit[2]);
}

TEST(Reference, MissesGiveBackgroundAndEmptyItems) {
  Scene s = base_scene(4, 3);
  s.background = {0.25f, 0.5f, 0.75f};
  const int m = add_material(s, material({1, 1, 1}, {1, 1, 1}));
  add_square(s, -1, 1, -1, 1, 10, m, 0, 0);  // behind the camera
  const ImageResult img = render_reference(s);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 4; ++x) expect_rgb(pixel(img, x, y), 0.25f, 0.5f, 0.75f);
  for (std::int32_t id : img.item_buffer) EXPECT_EQ(id, -1);
  EXPECT_EQ(img.rays.primary_hits, 0u);
}

TEST(Reference, MirrorReflectsBackgroundAndDepthOneIsLocalOnly) {
  Scene s = base_scene();
  s.background = {0.2f, 0.4f, 1.0f};
  const int m = add_material(s, material({0, 0, 0}, {0, 0, 0}, {0.8f, 0.6f, 0.4f}, 1, 3));
  add_square(s, -10, 10, -10, 10, 0, m, 0, 0);
  s.max_depth = 2;
  ImageResult img = render_reference(s);
  // No light, no ambient: the mirror's own term is 0; the reflected ray
  // goes back up and misses: kr * background.
  expect_rgb(pixel(img, 1, 1), 0.16f, 0.24f, 0.4f);
  EXPECT_EQ(img.rays.secondary, 9u);

  s.max_depth = 1;
  img = render_reference(s);
  expect_rgb(pixel(img, 1, 1), 0, 0, 0);
  EXPECT_EQ(img.rays.secondary, 0u);
}

TEST(Reference, GlassWithIndexOneTransmitsStraightThroughWeightedByTf) {
  Scene s = base_scene();
  s.ambient = {1, 1, 1};
  const int glass = add_material(s, material({0, 0, 0}, {0, 0, 0}, {0, 0, 0}, 1, 4, {0.5f, 0.7f, 0.9f}, 1));
  const int red = add_material(s, material({0.9f, 0.1f, 0.1f}, {0, 0, 0}));
  const int blue = add_material(s, material({0.1f, 0.1f, 0.9f}, {0, 0, 0}));
  add_square(s, -10, 10, -10, 10, 0, glass, 0, 0);
  // Behind the glass: red where x < 0.2, blue where x > 0.2. Straight rays
  // through the centre land on red; a bent ray would not need to.
  add_square(s, -10, 0.2f, -10, 10, -2, red, 1, 1);
  add_square(s, 0.2f, 10, -10, 10, -2, blue, 1, 2);
  const ImageResult img = render_reference(s);
  expect_rgb(pixel(img, 1, 1), 0.5f * 0.9f, 0.7f * 0.1f, 0.9f * 0.1f);
  EXPECT_EQ(img.item_buffer[2 * 4 + 1], 0);  // primary hit is the glass
  // Right column: x > 0.2 at z = -2 along a straight ray.
  const Vec3 right = pixel(img, 2, 1);
  expect_rgb(right, 0.5f * 0.1f, 0.7f * 0.1f, 0.9f * 0.9f);
}

TEST(Reference, WeightsMultiplyDownTheTreeAndDepthLimitsLevels) {
  Scene s = base_scene();
  s.background = {1, 1, 1};
  const int glass = add_material(s, material({0, 0, 0}, {0, 0, 0}, {0, 0, 0}, 1, 6, {0.5f, 0.5f, 0.5f}, 1));
  add_square(s, -10, 10, -10, 10, 0, glass, 0, 0);
  add_square(s, -10, 10, -10, 10, -1, glass, 0, 1);
  s.max_depth = 3;  // primary -> through glass 1 -> through glass 2 -> background
  expect_rgb(pixel(render_reference(s), 1, 1), 0.25f, 0.25f, 0.25f);
  s.max_depth = 2;  // the level-1 node (glass 2) may not spawn: its local term is 0
  expect_rgb(pixel(render_reference(s), 1, 1), 0, 0, 0);
}

TEST(Reference, TotalInternalReflectionHasNoTransmittedRay) {
  // 1x1 image: the only ray goes from the eye to the look-at point, 60 degrees
  // off the plane's normal. Ng = -z (clockwise from above), so the ray is
  // leaving the glass: eta = Ni, c = 0.5, k = 1 - Ni^2 * 0.75.
  auto make = [](float ni) {
    Scene s = base_scene(1, 1);
    const float a = 60.0f * static_cast<float>(M_PI) / 180.0f;
    s.camera.eye = {0, -5 * std::sin(a), 5 * std::cos(a)};
    s.background = {0.5f, 0.5f, 0.5f};
    const int m = add_material(s, material({0, 0, 0}, {0, 0, 0}, {0, 0, 0}, 1, 6, {1, 1, 1}, ni));
    add_square(s, -10, 10, -10, 10, 0, m, 0, 0, true);
    return s;
  };
  const ImageResult tir = render_reference(make(1.5f));  // k < 0
  expect_rgb(pixel(tir, 0, 0), 0, 0, 0);
  EXPECT_EQ(tir.rays.secondary, 0u);
  const ImageResult through = render_reference(make(1.1f));  // k = 1 - 1.21*0.75 > 0
  expect_rgb(pixel(through, 0, 0), 0.5f, 0.5f, 0.5f);
  EXPECT_EQ(through.rays.secondary, 1u);
}

TEST(Reference, RefractionBendsByEtaFormula) {
  // Entering glass (Ni = 1.5) at 45 degrees, the transmitted direction is
  // eta*D + (eta*c - sqrt(k))n; it must reach the patch where that lands.
  const float ni = 1.5f, eta = 1.0f / ni;
  const float c = std::sqrt(0.5f);
  const float k = 1.0f - eta * eta * (1.0f - c * c);
  // D = (0, sin45, -cos45), n = (0,0,1): T = (0, eta*sin45, -eta*c + (eta*c - sqrt k)) = (0, eta*sin45, -sqrt k).
  const float ty = eta * std::sqrt(0.5f), tz = -std::sqrt(k);
  const float land_y = ty / -tz * 4.0f;  // reaches z = -4 at this y
  Scene s = base_scene(1, 1);
  s.camera.eye = {0, -5, 5};
  s.ambient = {1, 1, 1};
  const int glass = add_material(s, material({0, 0, 0}, {0, 0, 0}, {0, 0, 0}, 1, 4, {1, 1, 1}, ni));
  const int green = add_material(s, material({0, 1, 0}, {0, 0, 0}));
  const int grey = add_material(s, material({0.1f, 0.1f, 0.1f}, {0, 0, 0}));
  add_square(s, -10, 10, -10, 10, 0, glass, 0, 0);
  add_square(s, -1, 1, land_y - 0.05f, land_y + 0.05f, -4, green, 1, 1);
  add_square(s, -20, 20, -20, 20, -4.5f, grey, 1, 2);
  expect_rgb(pixel(render_reference(s), 0, 0), 0, 1, 0);
}

TEST(Reference, ItemBufferNamesObjectAndFacetOfPrimaryHit) {
  Scene s = base_scene(2, 1);
  s.camera.fov_deg = 90;
  const int m = add_material(s, material({1, 1, 1}, {0, 0, 0}));
  add_square(s, -10, 0, -10, 10, 0, m, 3, 7);   // left half
  add_square(s, 0, 10, -10, 10, 0, m, 5, 11);   // right half
  const ImageResult img = render_reference(s);
  ASSERT_EQ(img.item_buffer.size(), 4u);
  EXPECT_EQ(img.item_buffer[0], 3);
  EXPECT_EQ(img.item_buffer[1], 7);
  EXPECT_EQ(img.item_buffer[2], 5);
  EXPECT_EQ(img.item_buffer[3], 11);
}

// The one hit order (kernels/hit_order.h): coincident squares of two
// objects show the lower object's, whichever the scene lists first.
TEST(Reference, CoincidentFacetsGoToTheLowerObjectWhateverTheirListing) {
  for (bool lower_first : {true, false}) {
    Scene s = base_scene(3, 3);
    const int red = add_material(s, material({1, 0, 0}, {0, 0, 0}));
    const int blue = add_material(s, material({0, 0, 1}, {0, 0, 0}));
    s.ambient = {1, 1, 1};
    const auto lower = [&] { add_square(s, -10, 10, -10, 10, 0, blue, 0, 2); };
    const auto upper = [&] { add_square(s, -10, 10, -10, 10, 0, red, 1, 9); };
    if (lower_first) lower(), upper();
    else upper(), lower();
    const ImageResult img = render_reference(s);
    for (int i = 0; i < 9; ++i) {
      EXPECT_EQ(img.item_buffer[2 * i], 0);
      EXPECT_EQ(img.item_buffer[2 * i + 1], 2);
      expect_rgb(pixel(img, i % 3, i / 3), 0, 0, 1);
    }
  }
}

// Ids that the order could not rank as the contract does (facet ids that
// fall as object ids rise; no reader makes them) are refused, not drawn.
TEST(Reference, FacetIdsThatFallAsObjectIdsRiseAreRefused) {
  Scene s = base_scene(3, 3);
  const int m = add_material(s, material({1, 0, 0}, {0, 0, 0}));
  add_square(s, -10, 10, -10, 10, 0, m, 0, 9);
  add_square(s, -10, 10, -10, 10, 0, m, 1, 2);
  EXPECT_THROW(render_reference(s), std::logic_error);
}

TEST(Reference, PrimaryRaysAcceptHitsCloserThanEpsilon) {
  // A large scene (big epsilon) with a small square right in front of the eye.
  Scene s = base_scene(1, 1);
  s.ambient = {1, 1, 1};
  const int near_m = add_material(s, material({0, 1, 0}, {0, 0, 0}));
  const int far_m = add_material(s, material({1, 0, 0}, {0, 0, 0}));
  add_square(s, -1000, 1000, -1000, 1000, -1000, far_m, 0, 0);
  add_square(s, -0.01f, 0.01f, -0.01f, 0.01f, 4.999f, near_m, 1, 1);  // t = 0.001 < epsilon ~ 0.3
  const ReferenceTracer tracer(s);
  EXPECT_GT(tracer.epsilon(), 0.1f);
  const ImageResult img = render_reference(s);
  expect_rgb(pixel(img, 0, 0), 0, 1, 0);
}

TEST(Reference, ThreadsAndRowRangesGiveTheSameImage) {
  Scene s = base_scene(17, 13);
  s.ambient = {0.1f, 0.1f, 0.1f};
  const int m = add_material(s, material({1, 1, 1}, {0.7f, 0.7f, 0.7f}, {0.5f, 0.5f, 0.5f}, 20, 3));
  add_square(s, -3, 3, -3, 3, 0, m, 0, 0);
  add_square(s, -1, 1, -1, 1, 1, m, 1, 1, true);
  s.lights.push_back({{2, 2, 6}, {1, 1, 1}});
  const ImageResult one = render_reference(s, 1);
  const ImageResult two = render_reference(s, 2);
  // Same computation per pixel: bit-identical.
  EXPECT_EQ(one.rgb, two.rgb);
  EXPECT_EQ(one.item_buffer, two.item_buffer);
  EXPECT_EQ(one.rays.total(), two.rays.total());

  ImageResult rows = blank_image(s.width, s.height);
  render_reference_rows(s, 5, 9, rows);
  for (int y = 5; y < 9; ++y)
    for (int x = 0; x < 17; ++x) {
      const Vec3 a = pixel(one, x, y), b = pixel(rows, x, y);
      expect_rgb(b, a[0], a[1], a[2], 0);
    }
  EXPECT_EQ(rows.rays.primary, 4u * 17u);
}

// Brute force over all triangles, the same test in the same precision: the
// BVH must not change which triangle is nearest.
int brute_force_facet(const Scene& s, const Vec3& eye, const Vec3& d) {
  float best = INFINITY;
  int best_facet = -1;
  for (const Triangle& t : s.triangles) {
    const float e1[3] = {t.v1[0] - t.v0[0], t.v1[1] - t.v0[1], t.v1[2] - t.v0[2]};
    const float e2[3] = {t.v2[0] - t.v0[0], t.v2[1] - t.v0[1], t.v2[2] - t.v0[2]};
    const float p[3] = {d[1] * e2[2] - d[2] * e2[1], d[2] * e2[0] - d[0] * e2[2], d[0] * e2[1] - d[1] * e2[0]};
    const float det = e1[0] * p[0] + e1[1] * p[1] + e1[2] * p[2];
    if (det == 0) continue;
    const float inv = 1 / det;
    const float sv[3] = {eye[0] - t.v0[0], eye[1] - t.v0[1], eye[2] - t.v0[2]};
    const float u = (sv[0] * p[0] + sv[1] * p[1] + sv[2] * p[2]) * inv;
    if (u < 0 || u > 1) continue;
    const float q[3] = {sv[1] * e1[2] - sv[2] * e1[1], sv[2] * e1[0] - sv[0] * e1[2], sv[0] * e1[1] - sv[1] * e1[0]};
    const float v = (d[0] * q[0] + d[1] * q[1] + d[2] * q[2]) * inv;
    if (v < 0 || u + v > 1) continue;
    const float tt = (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]) * inv;
    if (tt > 0 && tt < best) {
      best = tt;
      best_facet = t.facet_id;
    }
  }
  return best_facet;
}

TEST(Reference, BvhFindsTheSameNearestFacetAsBruteForce) {
  Scene s = base_scene(48, 36);
  s.camera.eye = {0, 0, 12};
  s.camera.fov_deg = 50;
  const int m = add_material(s, material({1, 1, 1}, {0, 0, 0}));
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> pos(-4, 4), off(-0.8f, 0.8f);
  for (int i = 0; i < 3000; ++i) {
    const Vec3 c{pos(rng), pos(rng), pos(rng)};
    s.triangles.push_back({{c[0] + off(rng), c[1] + off(rng), c[2] + off(rng)},
                           {c[0] + off(rng), c[1] + off(rng), c[2] + off(rng)},
                           {c[0] + off(rng), c[1] + off(rng), c[2] + off(rng)},
                           i, 0, m});
  }
  s.num_facets = 3000;
  s.num_objects = 1;
  const ImageResult img = render_reference(s);
  int hits = 0;
  test::for_each_primary_ray(s, [&](int x, int y, const Vec3& dir) {
    const int expected = brute_force_facet(s, s.camera.eye, dir);
    EXPECT_EQ(img.item_buffer[2 * (y * s.width + x) + 1], expected) << "pixel " << x << "," << y;
    hits += expected >= 0;
  });
  EXPECT_GT(hits, 100);
}

TEST(Reference, RayCountsFollowTheTree) {
  Scene s = base_scene(2, 2);
  const int mirror = add_material(s, material({0, 0, 0}, {0.5f, 0.5f, 0.5f}, {0.5f, 0.5f, 0.5f}, 1, 3));
  add_square(s, -10, 10, -10, 10, 0, mirror, 0, 0);
  s.lights.push_back({{0, 0, 4}, {1, 1, 1}});
  s.lights.push_back({{0, 0, -4}, {1, 1, 1}});  // behind: never needs a shadow ray
  const ImageResult img = render_reference(s);
  EXPECT_EQ(img.rays.primary, 4u);
  EXPECT_EQ(img.rays.primary_hits, 4u);
  EXPECT_EQ(img.rays.shadow, 4u);     // one per hit, front light only
  EXPECT_EQ(img.rays.secondary, 4u);  // reflections that then miss
  EXPECT_EQ(img.rays.total(), 12u);
}

// The ray sample of --balance work: every primary ray's tree, as segments;
// an endless tree (facing glass slabs at depth 31) is cut at the cap, so the
// sample ends, and soon.
TEST(Reference, RaySampleFollowsTheTreesAndStaysBounded) {
  Scene s = load_scene_from_string(R"({"image": {"size": [64, 48]}, "depth": 31,
    "camera": {"eye": [0, 0, 0.5], "look_at": [0, 0, -1]},
    "lights": [{"position": [0, 0, 0]}],
    "materials": {"glass": {"kr": 0.9, "kt": 0.9, "Ni": 1.5}},
    "objects": [{"type": "box", "min": [-50, -50, -1.1], "max": [50, 50, -1], "material": "glass"},
                {"type": "box", "min": [-50, -50, 1], "max": [50, 50, 1.1], "material": "glass"}]})",
                                    "slabs.json", "");
  const ReferenceTracer tracer(s);
  const RaySample endless = tracer.sample_rays(100);
  EXPECT_LE(endless.rays.size(), ReferenceTracer::kMaxSampleRays);
  EXPECT_GE(endless.rays.size(), ReferenceTracer::kMaxSampleRays - 8) << "the trees should fill the cap";
  s.max_depth = 2;  // primary ray, one reflected and one transmitted, shadow rays of both levels
  const RaySample shallow = ReferenceTracer(s).sample_rays(100);
  int primary = 0;
  for (const RaySegment& r : shallow.rays) primary += r.origin == s.camera.eye;
  EXPECT_GE(primary, 60);
  EXPECT_GT(shallow.rays.size(), std::size_t(3 * primary)) << "reflected, transmitted and shadow rays are kept";
}

// Holders of shares as threads of one process: the joins a level's hits
// go through (the MPI ranks' in dist/collective_balance.cpp).
class ThreadJoin {
 public:
  explicit ThreadJoin(int holders) : slots_(std::size_t(holders)) {}
  struct Holder : SampleJoin {
    ThreadJoin* all;
    int me;
    Holder(ThreadJoin* a, int h) : all(a), me(h) {}
    int holder() const override { return me; }
    void min(std::vector<std::uint64_t>& v) const override {
      const std::vector<std::vector<unsigned char>> got = all->exchange(me, bytes(v));
      for (const auto& b : got)
        for (std::size_t i = 0; i < v.size(); ++i) {
          std::uint64_t x;
          std::memcpy(&x, b.data() + i * sizeof x, sizeof x);
          v[i] = std::min(v[i], x);
        }
    }
    std::vector<unsigned char> all_gather(const std::vector<unsigned char>& mine) const override {
      std::vector<unsigned char> out;
      for (const auto& b : all->exchange(me, mine)) out.insert(out.end(), b.begin(), b.end());
      return out;
    }
    static std::vector<unsigned char> bytes(const std::vector<std::uint64_t>& v) {
      std::vector<unsigned char> b(v.size() * sizeof(std::uint64_t));
      if (!v.empty()) std::memcpy(b.data(), v.data(), b.size());
      return b;
    }
  };

  // Every holder's bytes, once each has given its own.
  std::vector<std::vector<unsigned char>> exchange(int me, const std::vector<unsigned char>& mine) {
    std::unique_lock<std::mutex> lock(m_);
    slots_[std::size_t(me)] = mine;
    wait(lock);
    std::vector<std::vector<unsigned char>> got = slots_;
    wait(lock);  // nobody gives the next round's bytes before all have read these
    return got;
  }

 private:
  void wait(std::unique_lock<std::mutex>& lock) {
    const std::uint64_t round = round_;
    if (++arrived_ == slots_.size()) {
      arrived_ = 0;
      ++round_;
      cv_.notify_all();
    } else {
      cv_.wait(lock, [&] { return round_ != round; });
    }
  }
  std::vector<std::vector<unsigned char>> slots_;
  std::mutex m_;
  std::condition_variable cv_;
  std::size_t arrived_ = 0;
  std::uint64_t round_ = 0;
};

bool same_segments(const RaySample& a, const RaySample& b) {
  if (a.rays.size() != b.rays.size() || a.stride != b.stride) return false;
  for (std::size_t i = 0; i < a.rays.size(); ++i)
    if (a.rays[i].origin != b.rays[i].origin || a.rays[i].direction != b.rays[i].direction ||
        std::memcmp(&a.rays[i].t_max, &b.rays[i].t_max, sizeof(float)) != 0)
      return false;
  return true;
}

// The sample on a scene split into shares, each traced by its own holder
// and joined level by level, is the whole scene's, segment for segment:
// the least hit in (t, object, facet, triangle) is found whatever holds
// which facet. Shares are runs of the file order cut anywhere (even inside
// a polygon), or objects dealt round (object o to holder o mod H, so a
// lower object can lie on a higher holder). Two boxes lie on each other
// with different materials, so their hits tie in t and the facets' keys
// decide which material spawns the next rays.
TEST(Reference, RaySampleOnSharesIsTheWholeScenes) {
  const Scene whole = load_scene_from_string(R"({"image": {"size": [160, 120]}, "depth": 5, "smooth": true,
    "camera": {"eye": [0, 3, 9], "look_at": [0, 0.5, 0]},
    "lights": [{"position": [4, 8, 6]}, {"position": [-5, 6, -2]}],
    "materials": {"mirror": {"kd": 0.1, "kr": 0.8}, "glass": {"kd": 0.05, "kr": 0.1, "kt": 0.9, "Ni": 1.5},
                  "matte": {"kd": [0.7, 0.6, 0.5]}},
    "objects": [{"type": "box", "min": [-6, -1, -6], "max": [6, -0.9, 6], "material": "matte"},
                {"type": "box", "min": [1, -0.9, -1], "max": [2.5, 1, 0.5], "material": "glass"},
                {"type": "box", "min": [1, -0.9, -1], "max": [2.5, 1, 0.5], "material": "mirror"},
                {"type": "sphere", "center": [-1.5, 0.5, 0], "radius": 1.2, "subdivisions": 3, "material": "glass"},
                {"type": "sphere", "center": [0.5, 0.2, 2], "radius": 0.6, "subdivisions": 2, "material": "mirror"}]})",
                                          "shares.json", "");
  // 19,200 primary rays: more than one chunk of a level is traced and joined.
  const RaySample expected = ReferenceTracer(whole).sample_rays(160 * 120);
  ASSERT_GT(expected.rays.size(), 40000u) << "primary rays and their trees";
  const std::size_t n = whole.triangles.size();
  Vec3 lo, hi;
  whole.bounds(lo, hi);
  for (const bool dealt : {false, true})
  for (int holders : {2, 3}) {
    SCOPED_TRACE(std::to_string(holders) + (dealt ? " holders, objects dealt" : " holders, runs"));
    std::vector<Scene> shares;
    for (int h = 0; h < holders; ++h) {
      Scene share = whole;
      share.triangles.clear();
      // Uneven runs: the cuts fall 7 facets off the even ones.
      const std::size_t b = h == 0 ? 0 : n * std::size_t(h) / std::size_t(holders) + 7;
      const std::size_t e = h + 1 == holders ? n : n * std::size_t(h + 1) / std::size_t(holders) + 7;
      for (std::size_t i = 0; i < n; ++i)
        if (dealt ? whole.triangles[i].object_id % holders == h : i >= b && i < e)
          share.triangles.push_back(whole.triangles[i]);
      share.share.rank = h;
      share.share.ranks = holders;
      share.share.total_triangles = n;
      share.share.lo = lo;
      share.share.hi = hi;
      shares.push_back(std::move(share));
    }
    ThreadJoin join(holders);
    std::vector<RaySample> got(static_cast<std::size_t>(holders));
    std::vector<std::thread> threads;
    for (int h = 0; h < holders; ++h)
      threads.emplace_back([&, h] {
        const ThreadJoin::Holder me(&join, h);
        got[std::size_t(h)] = ReferenceTracer(shares[std::size_t(h)]).sample_rays(160 * 120, &me);
      });
    for (std::thread& t : threads) t.join();
    for (int h = 0; h < holders; ++h)
      EXPECT_TRUE(same_segments(got[std::size_t(h)], expected)) << "holder " << h << " of " << holders;
  }
}

// The sample's order on a tie: the facet of the lower object id wins, so
// the box listed first decides whether the rays reflect (a mirror) or pass
// (glass).
TEST(Reference, RaySampleTiesGoToTheLowerObject) {
  const auto sample_of = [](const char* first, const char* second) {
    const std::string text = std::string(R"({"image": {"size": [32, 24]}, "depth": 2,
      "camera": {"eye": [0, 0, 5], "look_at": [0, 0, 0]},
      "materials": {"mirror": {"kd": 0.1, "kr": 0.8}, "glass": {"kd": 0.1, "kt": 0.9, "Ni": 1}},
      "objects": [{"type": "box", "min": [-9, -9, -1], "max": [9, 9, 0], "material": ")") + first + R"("},
                  {"type": "box", "min": [-9, -9, -1], "max": [9, 9, 0], "material": ")" + second + R"("}]})";
    return ReferenceTracer(load_scene_from_string(text, "tie.json", "")).sample_rays(100);
  };
  const auto reflected = [](const RaySample& s) {
    int n = 0;
    // Back towards the eye, and on to the sky (a shadow segment ends at its light).
    for (const RaySegment& r : s.rays) n += r.direction[2] > 0 && std::isinf(r.t_max);
    return n;
  };
  const RaySample mirror_first = sample_of("mirror", "glass"), glass_first = sample_of("glass", "mirror");
  EXPECT_GT(reflected(mirror_first), 50);
  EXPECT_EQ(reflected(glass_first), 0);
}

// The BVH is built on several threads when a node is big enough, each half
// apart and spliced in place: the same tree as one thread builds, so the
// same image, item buffer, rays and sample.
TEST(Reference, BvhBuiltOnThreadsIsTheSameTree) {
  Scene s = load_scene_from_string(R"({"image": {"size": [48, 36]}, "depth": 3,
    "camera": {"eye": [0, 30, 60], "look_at": [0, 0, 0]},
    "materials": {"mirror": {"kd": 0.2, "kr": 0.7}},
    "objects": [{"type": "terrain", "size": [100, 100], "quads": [300, 300], "height": 12},
                {"type": "sphere", "center": [0, 18, 0], "radius": 8, "subdivisions": 3, "material": "mirror"}]})",
                                    "threads.json", "");
  ASSERT_GT(s.triangles.size(), std::size_t(1) << 17) << "big enough for the halves of the root to go apart";
  const auto render_with = [&](int threads) {
    ImageResult img = blank_image(s.width, s.height);
    const ReferenceTracer tracer(s, nullptr, threads);
    tracer.render_rows(0, s.height, img, img.rays);
    return std::make_pair(img, tracer.sample_rays(300));
  };
  const auto [one, one_sample] = render_with(1);
  for (int threads : {2, 3, 4}) {
    const auto [many, many_sample] = render_with(threads);
    EXPECT_TRUE(std::memcmp(one.rgb.data(), many.rgb.data(), one.rgb.size() * sizeof(float)) == 0) << threads;
    EXPECT_EQ(one.item_buffer, many.item_buffer) << threads;
    EXPECT_EQ(one.rays.total(), many.rays.total()) << threads;
    EXPECT_TRUE(same_segments(one_sample, many_sample)) << threads;
  }
}

}  // namespace
}  // namespace opsila
