// `opsila bench --rays-out`: the traversal alone's rays and answers in one
// file, whose counts are the bench's, and whose answers an independent
// brute-force test in doubles agrees with wherever the answer is not
// decided by rounding (a ray through an edge, a hit at the segment's end).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include <nlohmann/json.hpp>

#include "bench/ray_file.h"
#include "core/errors.h"
#include "test_util.h"

namespace opsila {
namespace {

struct D3 {
  double x, y, z;
};
D3 sub(D3 a, D3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
D3 cross(D3 a, D3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
double dot(D3 a, D3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
D3 at(const float* f) { return {f[0], f[1], f[2]}; }

// Möller–Trumbore in doubles: t, and how far inside the triangle the hit
// lies (the least barycentric; negative outside). NaN t for a parallel ray.
double hit_t(const float* tri, const float* ray, double* inside) {
  const D3 o = at(ray), d = at(ray + 4), v0 = at(tri), e1 = sub(at(tri + 3), v0), e2 = sub(at(tri + 6), v0);
  const D3 p = cross(d, e2);
  const double det = dot(e1, p);
  *inside = -1;
  if (det == 0) return std::nan("");
  const D3 s = sub(o, v0), q = cross(s, e1);
  const double u = dot(s, p) / det, v = dot(d, q) / det;
  *inside = std::min({u, v, 1 - u - v});
  return dot(e2, q) / det;
}

// Every triangle a ray meets in (tmin, tmax): the least t of a clear hit,
// and whether an unclear one (near an edge or the segment's ends) lies
// before it, which makes the answer rounding's to give.
struct Met {
  double t = std::numeric_limits<double>::infinity();
  int tri = -1;
  bool unclear = false;
};
Met brute_force(const RayFile& f, const float* ray, double tmax) {
  const double tmin = ray[3], eps = 1e-5;
  Met m;
  double unclear_t = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < f.triangles.size() / 9; ++i) {
    double inside;
    const double t = hit_t(&f.triangles[9 * i], ray, &inside);
    if (!(inside > -eps) || !(t > tmin - eps * (1 + tmin)) || !(t < tmax + eps * (1 + t))) continue;
    const bool clear = inside > eps && t > tmin + eps * (1 + tmin) && t < tmax - eps * (1 + t);
    if (!clear)
      unclear_t = std::min(unclear_t, t);
    else if (t < m.t)
      m.t = t, m.tri = static_cast<int>(i);
  }
  m.unclear = std::isfinite(unclear_t) && unclear_t <= m.t * (1 + eps);
  return m;
}

TEST(BenchRaysOut, TheFileHoldsTheBenchsRaysAndAnswersABruteForceTestAgreesWith) {
  test::TempDir dir;
  const std::string rays = dir.file("w.rays"), json = dir.file("w.json");
  const test::RunResult r = test::run_opsila({"bench", std::string(OPSILA_SOURCE_DIR) + "/scenes/whitted.json",
                                              "--size", "40x30", "--depth", "3", "--quick", "--scatter-max", "4",
                                              "--repeats", "1", "--json", json, "--rays-out", rays});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const RayFile f = parse_ray_file(test::read_file(rays), rays);
  const nlohmann::json j = nlohmann::json::parse(test::read_file(json));
  ASSERT_EQ(f.nearest.size() / 8, j["traversal_alone"]["nearest_rays"].get<std::size_t>());
  ASSERT_EQ(f.any.size() / 8, j["traversal_alone"]["any_rays"].get<std::size_t>());
  ASSERT_EQ(f.nearest_hit.size(), f.nearest.size() / 8);
  ASSERT_GT(f.triangles.size(), 0u);
  int checked = 0, hits = 0, blocked = 0;
  for (std::size_t i = 0; i < f.nearest_hit.size(); ++i) {
    const float* ray = &f.nearest[8 * i];
    ASSERT_TRUE(std::isinf(ray[7]));
    const Met m = brute_force(f, ray, std::numeric_limits<double>::infinity());
    if (m.unclear) continue;
    ++checked;
    hits += m.tri >= 0;
    // A tie in t between clear hits is the hit order's (ids): same distance.
    if (f.nearest_hit[i] != m.tri) {
      ASSERT_GE(f.nearest_hit[i], 0) << "ray " << i << " misses, triangle " << m.tri << " is met at " << m.t;
      double inside;
      const double t = hit_t(&f.triangles[9 * std::size_t(f.nearest_hit[i])], ray, &inside);
      EXPECT_NEAR(t, m.t, 1e-6 * (1 + m.t)) << "ray " << i;
    }
  }
  for (std::size_t i = 0; i < f.any_blocked.size(); ++i) {
    const float* ray = &f.any[8 * i];
    const Met m = brute_force(f, ray, ray[7]);
    if (m.unclear) continue;
    ++checked;
    blocked += m.tri >= 0;
    EXPECT_EQ(f.any_blocked[i], m.tri >= 0 ? 1 : 0) << "shadow ray " << i;
  }
  // Most rays decide clearly, and the scene both hits and blocks.
  EXPECT_GT(checked, int(0.9 * double(f.nearest_hit.size() + f.any_blocked.size())));
  EXPECT_GT(hits, 0);
  EXPECT_GT(blocked, 0);
}

TEST(BenchRaysOut, RefusedForAnInstancedSceneAndAWrongName) {
  test::TempDir dir;
  const std::string rays = dir.file("f.rays");
  test::RunResult r = test::run_opsila({"bench", std::string(OPSILA_SOURCE_DIR) + "/scenes/forest.json", "--size",
                                        "8x8", "--quick", "--rays-out", rays});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--rays-out"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("instances"), std::string::npos) << r.err;
  EXPECT_FALSE(test::file_exists(rays));
  r = test::run_opsila({"bench", "scene.json", "--rays-out", dir.file("f.bin")});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("must end in .rays"), std::string::npos) << r.err;
}

TEST(BenchRaysOut, AShortOrForeignFileIsRefusedByName) {
  RayFile f;
  f.triangles.assign(9, 1.0f);
  f.nearest.assign(8, 0.5f);
  f.nearest_hit = {0};
  const std::string bytes = ray_file_bytes(f);
  EXPECT_EQ(parse_ray_file(bytes, "x.rays").nearest_hit, f.nearest_hit);
  EXPECT_THROW(parse_ray_file(bytes.substr(0, bytes.size() - 4), "x.rays"), InputError);
  EXPECT_THROW(parse_ray_file("PNG" + bytes, "x.rays"), InputError);
}

}  // namespace
}  // namespace opsila
