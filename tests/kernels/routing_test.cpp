// kernels/lib/routing.cl alone: the destination choice on many random rays,
// with cluster boxes and with the paper's spheres, held against a
// brute-force search over every PE's clusters on the host. A radiance ray's
// forwarding visits, in increasing (entry, PE) order, exactly the PEs whose
// volumes it meets before tmax; a shadow ray visits, in PE order, exactly
// the PEs other than its home whose volumes meet its segment.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "batch.h"
#include "partition/partition.h"
#include "opsila_shared.h"

namespace opsila {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

// A PE's volume as the oracle sees it: the entry (clamped at 0) of the
// first of its cluster volumes the segment meets, or kInf; `marginal` when
// rounding could decide it (spheres only: the device's dot products may round
// otherwise than the host's).
struct Reach {
  float entry = kInf;
  bool marginal = false;
};

// Cluster boxes of PE q, as its routing BVH's leaves hold them.
void leaf_boxes(const BankedScene& bs, int node, std::vector<std::pair<int, int>>& out) {
  const BankNode& n = bs.route_nodes[node];
  for (int k = 0; k < OPSILA_BVH_WIDTH; ++k) {
    if (n.count[k] > 0) out.push_back({node, k});
    if (n.count[k] == 0) leaf_boxes(bs, n.child[k], out);
  }
}

// route_hits of kernels/lib/routing.cl for one box, expression for expression.
Reach box_reach(const BankNode& n, int k, const cl_float4& o, const cl_float4& d, float tmin, float tmax) {
  const float lo[3] = {n.lo_x[k], n.lo_y[k], n.lo_z[k]}, hi[3] = {n.hi_x[k], n.hi_y[k], n.hi_z[k]};
  float enter = -kInf, leave = kInf;
  for (int a = 0; a < 3; ++a) {
    const float inv = 1.0f / d.s[a];
    const bool neg = std::signbit(inv);
    const float tn = ((neg ? hi[a] : lo[a]) - o.s[a]) * inv, tf = ((neg ? lo[a] : hi[a]) - o.s[a]) * inv;
    enter = a == 0 ? tn : std::fmax(enter, tn);
    leave = a == 0 ? tf : std::fmin(leave, tf);
  }
  Reach r;
  if (enter <= leave && leave > tmin && enter < tmax) r.entry = std::fmax(enter, 0.0f);
  return r;
}

// sphere_entry of kernels/lib/geometry.cl, in double, with its margins.
Reach sphere_reach(const Cluster& c, const cl_float4& o, const cl_float4& d, float tmin, float tmax) {
  double oc[3], b = 0, cc = 0;
  for (int a = 0; a < 3; ++a) {
    oc[a] = double(o.s[a]) - c.center[a];
    b += oc[a] * d.s[a];
    cc += oc[a] * oc[a];
  }
  const double r2 = double(c.radius) * c.radius, disc = b * b - (cc - r2), scale = 1e-3 * (r2 + cc);
  Reach r;
  r.marginal = std::fabs(disc) < scale;
  if (disc < 0) return r;
  const double s = std::sqrt(disc), t_near = -b - s, t_far = -b + s, m = 1e-3 * (1 + std::fabs(t_far));
  r.marginal = r.marginal || std::fabs(t_far - tmin) < m || std::fabs(t_near - tmax) < m || std::fabs(t_near) < m;
  if (t_far <= tmin || t_near >= tmax) return r;
  r.entry = float(std::max(t_near, 0.0));
  return r;
}

// Per PE: the smallest entry over its cluster volumes that meet the segment.
std::vector<Reach> reach_of_pes(const BankedScene& bs, int mode, const cl_float4& o, const cl_float4& d) {
  const float tmin = o.s[3], tmax = d.s[3];
  std::vector<Reach> out(bs.pes.size());
  for (int q = 0; q < bs.num_pes; ++q) {
    Reach& pe = out[q];
    std::vector<Reach> parts;
    if (mode == OPSILA_ROUTING_BOXES) {
      std::vector<std::pair<int, int>> leaves;
      leaf_boxes(bs, q, leaves);
      for (auto [node, k] : leaves) parts.push_back(box_reach(bs.route_nodes[node], k, o, d, tmin, tmax));
    } else {
      for (int c = bs.pes[q].cluster_begin; c < bs.pes[q].cluster_end; ++c)
        parts.push_back(sphere_reach(bs.clusters[c], o, d, tmin, tmax));
    }
    for (const Reach& r : parts) {
      pe.entry = std::min(pe.entry, r.entry);
      pe.marginal = pe.marginal || r.marginal;
    }
  }
  return out;
}

struct Routed {
  BankedScene bs;
  test::RayBatch rays;
};

Routed routed(int pes, float tmin, float tmax_lo, float tmax_hi) {
  const Scene s = test::batch_scene(2024);
  return Routed{partition_scene(s, pes), test::random_rays(1500, 31 + pes, tmin, tmax_lo, tmax_hi)};
}

// The routing tables and rays of `r` on the device, bound as every batch
// kernel of routing_test.cl takes them: pes, clusters, route, num_pes, mode,
// [home,] org, dir, count; then the kernel's outputs from `next_arg` on.
struct RoutingArgs {
  cl::Buffer pes, clusters, route, org, dir;
  RoutingArgs(ClRuntime& rt, const Routed& r)
      : pes(test::to_device(rt, r.bs.pes)),
        clusters(test::to_device(rt, r.bs.clusters)),
        route(test::to_device(rt, r.bs.route_nodes)),
        org(test::to_device(rt, r.rays.org)),
        dir(test::to_device(rt, r.rays.dir)) {}
  int bind(cl::Kernel& k, const Routed& r, int mode, const int* home = nullptr) const {
    int a = 0;
    for (const cl::Buffer* b : {&pes, &clusters, &route}) k.setArg(a++, *b);
    k.setArg(a++, cl_int(r.bs.num_pes));
    k.setArg(a++, cl_int(mode));
    if (home) k.setArg(a++, cl_int(*home));
    k.setArg(a++, org);
    k.setArg(a++, dir);
    k.setArg(a++, cl_int(r.rays.size()));
    return a;
  }
};

// Runs destination_chain or shadow_chain; visits (and entries) per ray.
std::pair<std::vector<int>, std::vector<float>> run_chain(const Routed& r, int mode, const char* kernel, int home) {
  ClRuntime& rt = test::batch_runtime();
  const std::size_t n = r.rays.size(), cells = n * r.bs.pes.size();
  const RoutingArgs args(rt, r);
  cl::Buffer visits = test::to_device(rt, std::vector<cl_int>(cells));
  cl::Buffer entries = test::to_device(rt, std::vector<float>(cells));
  const bool shadow = std::string(kernel) == "shadow_chain";
  cl::Kernel k = rt.kernel(kernel);
  int a = args.bind(k, r, mode, shadow ? &home : nullptr);
  k.setArg(a++, visits);
  if (!shadow) k.setArg(a++, entries);
  test::run_batch(rt, k, n);
  return {test::from_device<cl_int>(rt, visits, cells), shadow ? std::vector<float>() : test::from_device<float>(rt, entries, cells)};
}

// A box entry is (plane - origin) * (1 / d) on host and device alike, but a
// device may round 1 / d its own way (OpenCL C 1.2 allows 2.5 ulp; NVIDIA's
// driver did until the runtime asked for correct rounding), so the entries
// are held to a few ulps, not to their bits.
float box_entry_tolerance(float entry) { return 1e-6f * (1.0f + std::fabs(entry)); }

const char* mode_name(int mode) { return mode == OPSILA_ROUTING_BOXES ? "boxes" : "spheres"; }

TEST(Routing, ForwardingVisitsTheMetPesInEntryOrderOnRandomRays) {
  for (int pes : {5, 16, 64}) {
    const Routed r = routed(pes, 1e-3f, 2.0f, 20.0f);
    for (int mode : {OPSILA_ROUTING_BOXES, OPSILA_ROUTING_SPHERES}) {
      const auto [visits, entries] = run_chain(r, mode, "destination_chain", -1);
      std::size_t checked = 0, ordered = 0;
      for (std::size_t i = 0; i < r.rays.size(); ++i) {
        const std::vector<Reach> reach = reach_of_pes(r.bs, mode, r.rays.org[i], r.rays.dir[i]);
        if (std::any_of(reach.begin(), reach.end(), [](const Reach& x) { return x.marginal; })) continue;
        std::vector<std::pair<float, int>> expect;
        for (int q = 0; q < pes; ++q)
          if (reach[q].entry < r.rays.dir[i].s[3]) expect.push_back({reach[q].entry, q});
        std::sort(expect.begin(), expect.end());
        const std::string at = std::string(mode_name(mode)) + ", " + std::to_string(pes) + " PEs, ray " +
                               std::to_string(i);
        for (int j = 0; j < pes; ++j) {
          const int got = visits[i * pes + j];
          if (j >= int(expect.size())) {
            ASSERT_EQ(got, -1) << at << ": visit " << j << " is past the last PE the ray meets";
            break;
          }
          ASSERT_EQ(got, expect[j].second) << at << ": visit " << j;
          if (mode == OPSILA_ROUTING_BOXES)
            ASSERT_NEAR(entries[i * pes + j], expect[j].first, box_entry_tolerance(expect[j].first))
                << at << ": entry of visit " << j;
          else
            ASSERT_NEAR(entries[i * pes + j], expect[j].first, 1e-4f * (1 + expect[j].first)) << at;
        }
        ++checked;
        ordered += expect.size() >= 2;
      }
      EXPECT_GT(checked, r.rays.size() * 3 / 4) << mode_name(mode) << ": too many rays left out as marginal";
      EXPECT_GT(ordered, checked / 10) << mode_name(mode) << ": too few rays meet two PEs to test the order";
    }
  }
}

TEST(Routing, ShadowRaysVisitTheMetPesInPeOrderOnRandomSegments) {
  const int pes = 16;
  const Routed r = routed(pes, 1e-3f, 0.5f, 12.0f);
  for (int mode : {OPSILA_ROUTING_BOXES, OPSILA_ROUTING_SPHERES}) {
    for (int home : {-1, 0, 7, pes - 1}) {
      const auto visits = run_chain(r, mode, "shadow_chain", home).first;
      std::size_t checked = 0;
      for (std::size_t i = 0; i < r.rays.size(); ++i) {
        const std::vector<Reach> reach = reach_of_pes(r.bs, mode, r.rays.org[i], r.rays.dir[i]);
        if (std::any_of(reach.begin(), reach.end(), [](const Reach& x) { return x.marginal; })) continue;
        std::vector<int> expect;
        for (int q = 0; q < pes; ++q)
          if (q != home && reach[q].entry < kInf) expect.push_back(q);
        expect.resize(pes, -1);
        const std::vector<int> got(visits.begin() + i * pes, visits.begin() + (i + 1) * pes);
        ASSERT_EQ(got, expect) << mode_name(mode) << ", home " << home << ", ray " << i;
        ++checked;
      }
      EXPECT_GT(checked, r.rays.size() * 3 / 4) << mode_name(mode) << ": too many rays left out as marginal";
    }
  }
}

// A new ray's first destination choice also names the runner-up, so that
// the ray's first visit (made at once when the first PE is the spawning one)
// needs no second walk: the runner-up, when entered below the visit's limit,
// must be what next_destination chooses from the first PE's cursor, entry
// bits included; otherwise it must choose none. The oracle checks the pair.
TEST(Routing, TheFirstChoiceNamesTheVisitsNextChoice) {
  for (int pes : {5, 16, 64}) {
    const Routed r = routed(pes, 1e-3f, 0.5f, 12.0f);
    ClRuntime& rt = test::batch_runtime();
    const std::size_t n = r.rays.size();
    const RoutingArgs args(rt, r);
    for (int mode : {OPSILA_ROUTING_BOXES, OPSILA_ROUTING_SPHERES}) {
      cl::Buffer out = test::to_device(rt, std::vector<cl_int4>(n));
      cl::Buffer out_entries = test::to_device(rt, std::vector<cl_float4>(n));
      cl::Kernel k = rt.kernel("first_two");
      int a = args.bind(k, r, mode);
      k.setArg(a++, out);
      k.setArg(a++, out_entries);
      test::run_batch(rt, k, n);
      const std::vector<cl_int4> got = test::from_device<cl_int4>(rt, out, n);
      const std::vector<cl_float4> got_t = test::from_device<cl_float4>(rt, out_entries, n);
      std::size_t checked = 0, decided = 0, cut = 0;
      for (std::size_t i = 0; i < n; ++i) {
        const std::string at = std::string(mode_name(mode)) + ", " + std::to_string(pes) + " PEs, ray " +
                               std::to_string(i);
        const cl_int4& g = got[i];
        const cl_float4& t = got_t[i];
        if (mode != OPSILA_ROUTING_BOXES) {  // spheres: no runner-up, each visit chooses
          ASSERT_EQ(g.s[2], 0) << at;
          continue;
        }
        ASSERT_EQ(g.s[2], 1) << at;
        const float limit = r.rays.dir[i].s[3];
        if (g.s[0] >= 0) {  // the visit's choice, from the pair
          const bool below = g.s[1] >= 0 && t.s[1] < limit;
          ASSERT_EQ(g.s[3], below ? g.s[1] : -1) << at;
          if (below) ASSERT_EQ(t.s[2], t.s[1]) << at << ": the same entry bits";
          decided += below;
          cut += g.s[1] >= 0 && !below;
        }
        // The pair against the oracle: the two least (entry, PE) of an open ray.
        cl_float4 open_dir = r.rays.dir[i];
        open_dir.s[3] = kInf;
        const std::vector<Reach> reach = reach_of_pes(r.bs, mode, r.rays.org[i], open_dir);
        std::vector<std::pair<float, int>> expect;
        for (int q = 0; q < pes; ++q)
          if (reach[q].entry < kInf) expect.push_back({reach[q].entry, q});
        std::sort(expect.begin(), expect.end());
        expect.resize(std::max<std::size_t>(expect.size(), 2), {kInf, -1});
        ASSERT_EQ(g.s[0], expect[0].second) << at;
        ASSERT_EQ(g.s[1], expect[1].second) << at;
        if (g.s[0] >= 0) ASSERT_NEAR(t.s[0], expect[0].first, box_entry_tolerance(expect[0].first)) << at;
        if (g.s[1] >= 0) ASSERT_NEAR(t.s[1], expect[1].first, box_entry_tolerance(expect[1].first)) << at;
        ++checked;
      }
      if (mode == OPSILA_ROUTING_BOXES) {
        EXPECT_GT(decided, checked / 10) << pes << " PEs: too few runner-ups below the limit";
        EXPECT_GT(cut, checked / 50) << pes << " PEs: too few runner-ups cut by the limit";
      }
    }
  }
}

}  // namespace
}  // namespace opsila
