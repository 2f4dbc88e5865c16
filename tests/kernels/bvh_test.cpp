// kernels/lib/bvh.cl alone: the bank BVH walks (nearest hit, any hit) on
// many random rays, each answer held against a brute-force search of the
// bank's facets on the host, so that a walk that loses a facet fails here
// and not only as a wrong pixel.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "batch.h"
#include "partition/bank_qnode.h"
#include "partition/partition.h"
#include "hit_order.h"
#include "opsila_shared.h"

namespace opsila {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

// The watertight ray-facet test of kernels/lib/geometry.cl, expression for
// expression, in float: the oracle's facet test.
struct HostRay {
  float org[3], dir[3];
  int kx, ky, kz;
  float sx, sy, sz;
};

HostRay host_ray(const cl_float4& o, const cl_float4& d) {
  HostRay r{{o.s[0], o.s[1], o.s[2]}, {d.s[0], d.s[1], d.s[2]}, 0, 0, 0, 0, 0, 0};
  const float a[3] = {std::fabs(d.s[0]), std::fabs(d.s[1]), std::fabs(d.s[2])};
  r.kz = (a[0] > a[1]) ? (a[0] > a[2] ? 0 : 2) : (a[1] > a[2] ? 1 : 2);
  r.kx = r.kz + 1 == 3 ? 0 : r.kz + 1;
  r.ky = r.kx + 1 == 3 ? 0 : r.kx + 1;
  if (r.dir[r.kz] < 0.0f) std::swap(r.kx, r.ky);
  const float dz = r.dir[r.kz];
  r.sx = r.dir[r.kx] / dz;
  r.sy = r.dir[r.ky] / dz;
  r.sz = 1.0f / dz;
  return r;
}

float host_intersect(const HostRay& r, const BankTriangle& tri, float tmin, float tmax) {
  const float* v[3] = {tri.v0, tri.v1, tri.v2};
  float x[3], y[3], z[3];
  for (int i = 0; i < 3; ++i) {
    const float p[3] = {v[i][0] - r.org[0], v[i][1] - r.org[1], v[i][2] - r.org[2]};
    z[i] = p[r.kz];
    x[i] = p[r.kx] - r.sx * z[i];
    y[i] = p[r.ky] - r.sy * z[i];
  }
  const float u = x[2] * y[1] - y[2] * x[1], v_ = x[0] * y[2] - y[0] * x[2], w = x[1] * y[0] - y[1] * x[0];
  if ((u < 0.0f || v_ < 0.0f || w < 0.0f) && (u > 0.0f || v_ > 0.0f || w > 0.0f)) return kInf;
  const float det = u + v_ + w;
  if (det == 0.0f) return kInf;
  const float inv_det = 1.0f / det;
  const float t = (u * inv_det) * (r.sz * z[0]) + (v_ * inv_det) * (r.sz * z[1]) + (w * inv_det) * (r.sz * z[2]);
  return (t > tmin && t < tmax) ? t : kInf;
}

struct Bank {
  Scene scene;
  BankedScene bs;
  float slack = 0;
  bool quantised = false;  // the walks read BankQNode (test::batch_runtime)
};

Bank make_bank(int pes) {
  Bank b;
  b.scene = test::batch_scene(1987);
  b.bs = partition_scene(b.scene, pes);
  b.slack = frame_params(b.scene, b.bs, 1).box_slack;
  return b;
}

struct Walks {
  std::vector<int> tri, blocked;
  std::vector<float> t;
  std::vector<cl_uint2> tests;
};

// Runs `kernel` (nearest_batch or any_batch) from PE p's bank root.
Walks run_walk(const Bank& b, int p, const test::RayBatch& rays, const char* kernel) {
  ClRuntime& rt = test::batch_runtime(b.quantised);
  const std::size_t n = rays.size();
  cl::Buffer nodes = rt.quantised_nodes() ? test::to_device(rt, quantise_nodes(b.bs.nodes))
                                          : test::to_device(rt, b.bs.nodes);
  cl::Buffer tris = test::to_device(rt, b.bs.triangles);
  cl::Buffer org = test::to_device(rt, rays.org), dir = test::to_device(rt, rays.dir);
  cl::Buffer out_a = test::to_device(rt, std::vector<cl_int>(n)), out_t = test::to_device(rt, std::vector<float>(n));
  cl::Buffer tests = test::to_device(rt, std::vector<cl_uint2>(n));
  cl::Kernel k = rt.kernel(kernel);
  const bool nearest = std::string(kernel) == "nearest_batch";
  int a = 0;
  for (const cl::Buffer* buf : {&nodes, &tris}) k.setArg(a++, *buf);
  k.setArg(a++, cl_int(b.bs.pes[p].node_begin));
  k.setArg(a++, b.slack);
  k.setArg(a++, org);
  k.setArg(a++, dir);
  k.setArg(a++, cl_int(n));
  k.setArg(a++, out_a);
  if (nearest) k.setArg(a++, out_t);
  k.setArg(a++, tests);
  test::run_batch(rt, k, n);
  Walks w;
  (nearest ? w.tri : w.blocked) = test::from_device<cl_int>(rt, out_a, n);
  if (nearest) w.t = test::from_device<float>(rt, out_t, n);
  w.tests = test::from_device<cl_uint2>(rt, tests, n);
  return w;
}

// Runs `kernel` from the root of every bank that holds facets and hands
// each ray's answer to check(pe, walks, i, host ray); stops at the first
// failure (one message, not thousands).
template <typename Check>
void for_each_bank(const Bank& b, const test::RayBatch& rays, const char* kernel, Check check) {
  for (int p = 0; p < b.bs.num_pes; ++p) {
    const PeInfo& pe = b.bs.pes[p];
    if (pe.node_begin == pe.node_end) continue;
    const Walks w = run_walk(b, p, rays, kernel);
    for (std::size_t i = 0; i < rays.size() && !::testing::Test::HasFailure(); ++i)
      check(pe, w, i, host_ray(rays.org[i], rays.dir[i]));
  }
}

// Every PE's bank (and the whole scene as one bank): the walk's nearest hit
// is the brute-force search's under the one hit order, facet for facet;
// and the walk tests far fewer facets than the search.
TEST(BankBvhWalk, NearestHitIsTheBruteForceNearestOnRandomRays) {
  for (int pes : {1, 16, -16}) {  // -16: 16 PEs, quantised nodes
    Bank b = make_bank(std::abs(pes));
    b.quantised = pes < 0;
    const test::RayBatch rays = test::random_rays(2000, 17 + pes, 0.0f, kInf, kInf);
    std::size_t hits = 0, walk_tests = 0, brute_tests = 0;
    for_each_bank(b, rays, "nearest_batch", [&](const PeInfo& pe, const Walks& w, std::size_t i, const HostRay& r) {
      HitKey key = hit_none();
      int best = -1;
      for (int f = pe.tri_begin; f < pe.tri_end; ++f) {
        const BankTriangle& tri = b.bs.triangles[f];
        const float t = host_intersect(r, tri, rays.org[i].s[3], kInf);
        if (t < kInf && hit_before(t, -1, tri.facet_id, OPSILA_TRI_FAN(tri), key)) {
          key = hit_key(t, -1, tri.facet_id, OPSILA_TRI_FAN(tri));
          best = f;
        }
      }
      const float best_t = key.t;
      const std::string at = std::to_string(std::abs(pes)) + (b.quantised ? " PEs, quantised" : " PEs") +
                             ", facets from " + std::to_string(pe.tri_begin) + ", ray " + std::to_string(i);
      EXPECT_EQ(w.tri[i] >= 0, best >= 0) << at;
      walk_tests += w.tests[i].s[0];
      brute_tests += static_cast<std::size_t>(pe.tri_end - pe.tri_begin);
      if (best < 0 || w.tri[i] < 0) return;
      ++hits;
      // The rounding of t follows the coordinates (origin to vertices, up
      // to about 14 here), not t: NVIDIA's kernel was 4.8e-7 off the host's
      // at t = 0.036.
      EXPECT_NEAR(w.t[i], best_t, 1e-5f * std::max(best_t, 1.0f)) << at;
      // One order (hit_order.h): the same facet, unless the device's
      // rounding put the distance in another grid cell than the host's.
      if (w.tri[i] != best)
        EXPECT_NE(hit_grid(w.t[i]), hit_grid(best_t)) << at << ": facet " << w.tri[i] << ", brute force " << best;
    });
    EXPECT_GT(hits, rays.size() / 4) << "too few rays hit anything to test the walk";
    EXPECT_LT(walk_tests * 5, brute_tests) << "the walk culls too little";
  }
}

// Shadow segments: the any-hit walk is blocked exactly when some facet of
// the bank is hit inside the segment.
TEST(BankBvhWalk, AnyHitMatchesTheBruteForceOnRandomSegments) {
  for (bool quantised : {false, true}) {
    Bank b = make_bank(8);
    b.quantised = quantised;
    const test::RayBatch rays = test::random_rays(2000, 5, 1e-3f, 0.5f, 12.0f);
    std::size_t blocked = 0;
    for_each_bank(b, rays, "any_batch", [&](const PeInfo& pe, const Walks& w, std::size_t i, const HostRay& r) {
      bool hit = false;
      for (int f = pe.tri_begin; f < pe.tri_end && !hit; ++f)
        hit = host_intersect(r, b.bs.triangles[f], rays.org[i].s[3], rays.dir[i].s[3]) < kInf;
      EXPECT_EQ(w.blocked[i] != 0, hit) << (quantised ? "quantised, " : "") << "facets from " << pe.tri_begin
                                        << ", ray " << i;
      blocked += hit;
    });
    EXPECT_GT(blocked, 100u) << "too few segments blocked to test the walk";
  }
}

// A ray from a random point above facet t to the point at w along its edge
// v0-v1: open, or (ends_there) a segment that ends at that point.
void push_edge_ray(test::RayBatch& b, const Triangle& t, float w, std::mt19937& gen, bool ends_there) {
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  const Vec3 p{t.v0[0] + w * (t.v1[0] - t.v0[0]), t.v0[1] + w * (t.v1[1] - t.v0[1]),
               t.v0[2] + w * (t.v1[2] - t.v0[2])};
  const Vec3 o{p[0] + 3 * u(gen), p[1] + 4 + 2 * u(gen), p[2] + 3 + 3 * u(gen)};
  const Vec3 d{p[0] - o[0], p[1] - o[1], p[2] - o[2]};
  const float l = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  b.org.push_back({{o[0], o[1], o[2], 0.0f}});
  b.dir.push_back({{d[0] / l, d[1] / l, d[2] / l, ends_there ? l : kInf}});
}

// Rays aimed at the points where the hit order's ids decide: the midpoints
// and corners of shared fan edges (both triangles of a crease are hit), and
// points of coincident facets of two objects (test::tie_scene).
test::RayBatch rays_at_ties(const Scene& s, unsigned seed) {
  test::RayBatch b;
  std::mt19937 gen(seed);
  for (const Triangle& t : s.triangles) {
    if (t.fan == 0) continue;  // a later fan triangle: its edge v0-v1 is shared with the one before
    for (float w : {0.5f, 0.0f, 0.25f}) push_edge_ray(b, t, w, gen, false);
  }
  return b;
}

// The least hit of a ray over every bank, the banks taken in `order`.
std::vector<std::pair<int, int>> winners(const Bank& b, const test::RayBatch& rays, const std::vector<int>& order) {
  std::vector<HitKey> best(rays.size(), hit_none());
  for (int p : order) {
    const PeInfo& pe = b.bs.pes[std::size_t(p)];
    if (pe.node_begin == pe.node_end) continue;
    const Walks w = run_walk(b, p, rays, "nearest_batch");
    for (std::size_t i = 0; i < rays.size(); ++i) {
      if (w.tri[i] < 0) continue;
      const BankTriangle& t = b.bs.triangles[std::size_t(w.tri[i])];
      if (hit_before(w.t[i], -1, t.facet_id, OPSILA_TRI_FAN(t), best[i])) best[i] = hit_key(w.t[i], -1, t.facet_id, OPSILA_TRI_FAN(t));
    }
  }
  std::vector<std::pair<int, int>> ids;
  for (const HitKey& k : best) ids.push_back({k.facet, k.fan});
  return ids;
}

// One winner, whatever holds the facets and whatever order they are met
// in: the scene's triangles shuffled (other clusters, BVHs and leaf
// orders), cut into 1, 3 or 16 banks, the banks joined in random orders.
TEST(BankBvhWalk, OneWinnerWhateverTheBanksAndTheVisitOrder) {
  const Scene tie = test::tie_scene(64, 12);
  const test::RayBatch rays = rays_at_ties(tie, 3);
  std::mt19937 gen(9);
  std::vector<std::pair<int, int>> first;
  std::size_t fan_wins = 0;
  for (int shuffle = 0; shuffle < 3; ++shuffle) {
    Bank b;
    b.scene = tie;
    if (shuffle > 0) std::shuffle(b.scene.triangles.begin(), b.scene.triangles.end(), gen);
    for (int pes : {1, 3, 16}) {
      b.quantised = pes == 3;  // another layout: other boxes, another visit order
      b.bs = partition_scene(b.scene, pes);
      b.slack = frame_params(b.scene, b.bs, 1).box_slack;
      std::vector<int> order(std::size_t(b.bs.num_pes));
      std::iota(order.begin(), order.end(), 0);
      std::shuffle(order.begin(), order.end(), gen);
      const std::vector<std::pair<int, int>> got = winners(b, rays, order);
      if (first.empty()) {
        first = got;
        for (const auto& w : got) fan_wins += w.second > 0;
        continue;
      }
      for (std::size_t i = 0; i < rays.size(); ++i)
        ASSERT_EQ(got[i], first[i]) << "shuffle " << shuffle << ", " << pes << " PEs, ray " << i;
    }
  }
  EXPECT_GT(fan_wins, rays.size() / 10) << "too few rays decided on a fan's later triangle to test the order";
}

// A leaf's facets are tested two or four at a time (intersect_triangle2,
// intersect_triangle4): each lane must give the single test's bits, or a
// leaf's winner would change with how its facets fall into leaves (the PE
// count). Facets side by side as a leaf holds them: the tie scene's fans
// (shared edges, creases), coincident facets, and degenerate ones (a
// sliver, a point, a segment); rays aimed at their edges and corners, and
// random ones through the batch scene.
TEST(BankBvhWalk, FacetTestsInLanesGiveTheSingleTestsBits) {
  Scene s = test::tie_scene(64, 12);
  const Scene more = test::batch_scene(7);
  s.triangles.insert(s.triangles.end(), more.triangles.begin(), more.triangles.end());
  const Vec3 p{0.5f, 0.25f, -0.125f};
  s.triangles.push_back({p, p, p, 1, 0, 0, -1, 0});                                                  // a point
  s.triangles.push_back({p, {p[0] + 1, p[1], p[2]}, {p[0] + 2, p[1], p[2]}, 2, 0, 0, -1, 0});         // a segment
  s.triangles.push_back({p, {p[0] + 1, p[1], p[2]}, {p[0] + 1, p[1] + 1e-7f, p[2]}, 3, 0, 0, -1, 0});  // a sliver
  while (s.triangles.size() % 4 != 0) s.triangles.push_back(s.triangles.back());
  std::vector<BankTriangle> tris;
  for (const Triangle& t : s.triangles) {
    BankTriangle b{};
    for (int a = 0; a < 3; ++a) b.v0[a] = t.v0[a], b.v1[a] = t.v1[a], b.v2[a] = t.v2[a];
    b.facet_id = t.facet_id;
    tris.push_back(b);
  }
  const int num_groups = static_cast<int>(tris.size() / 4), groups = 6;
  // Rays at each facet's edges and corners, each tried on the groups around
  // its facet; then random rays on random groups.
  test::RayBatch rays;
  std::vector<cl_int> first;
  std::mt19937 gen(11);
  for (std::size_t j = 0; j < s.triangles.size(); ++j) {
    for (float w : {0.5f, 0.0f, 1.0f / 3.0f}) {
      push_edge_ray(rays, s.triangles[j], w, gen, w == 0.0f);  // a corner: the segment ends there
      first.push_back(std::max(0, static_cast<int>(j / 4) - groups / 2));
    }
  }
  const test::RayBatch random = test::random_rays(4000, 3, 1e-3f, 2.0f, 20.0f);
  std::uniform_int_distribution<int> g(0, num_groups - 1);
  for (std::size_t i = 0; i < random.size(); ++i) {
    rays.org.push_back(random.org[i]);
    rays.dir.push_back(random.dir[i]);
    first.push_back(g(gen));
  }
  ClRuntime& rt = test::batch_runtime();
  const std::size_t n = rays.size();
  cl::Buffer tri_buf = test::to_device(rt, tris), org = test::to_device(rt, rays.org), dir = test::to_device(rt, rays.dir);
  cl::Buffer first_buf = test::to_device(rt, first), out = test::to_device(rt, std::vector<cl_uint2>(n));
  cl::Kernel k = rt.kernel("facet_lanes_batch");
  int a = 0;
  k.setArg(a++, tri_buf);
  k.setArg(a++, cl_int(num_groups));
  k.setArg(a++, org);
  k.setArg(a++, dir);
  k.setArg(a++, first_buf);
  k.setArg(a++, cl_int(groups));
  k.setArg(a++, cl_int(n));
  k.setArg(a++, out);
  test::run_batch(rt, k, n);
  const std::vector<cl_uint2> res = test::from_device<cl_uint2>(rt, out, n);
  std::size_t hits = 0;
  for (std::size_t i = 0; i < n; ++i) {
    ASSERT_EQ(res[i].s[0], 0u) << "ray " << i << ": a lane's distance differs from the single test's";
    hits += res[i].s[1];
  }
  EXPECT_GT(hits, n / 2) << "too few facets hit to compare the lanes";
}

}  // namespace
}  // namespace opsila
