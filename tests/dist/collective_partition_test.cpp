// The collective partition (dist/collective_partition.h) on 1..4 simulated
// ranks (tests/sim_ranks.h), without a launcher: each rank reads its share
// of a scene (whole objects dealt to it, its window of a terrain spread
// over the ranks) and the ranks together build exactly the banks one
// process builds from the whole scene for each rank's group of PEs, byte
// for byte, by facets, by measured work and by the sampled rays' work
// (dist/collective_balance.h), with routing on spheres and on boxes; and
// over an exchange of several rounds.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "dist/collective_balance.h"
#include "dist/collective_partition.h"
#include "formats/json/scene_file.h"
#include "partition/banks.h"
#include "partition/instance_banks.h"
#include "prepare/prepare.h"
#include "reference/reference.h"
#include "sim_ranks.h"
#include "test_util.h"

namespace opsila {
namespace {

// A terrain spread over the ranks (rotated, so its cuts are not along its
// grid; of an odd number of facets at its first cuts), and objects a rank
// holds whole: a sphere, a grid of small spheres, a small terrain. Smooth:
// every facet carries vertex normals, exchanged too.
const char* const kScene = R"({"smooth": true, "objects": [
  {"type": "sphere", "center": [0, 4, 0], "radius": 1, "subdivisions": 2},
  {"type": "terrain", "size": [20, 20], "quads": [39, 41], "height": 3, "transform": {"rotate": [0, 30, 0]}},
  {"type": "grid", "counts": [4, 3, 2], "min": [-8, 5, -2], "max": [-4, 7, 2], "radius": 0.3, "subdivisions": 1,
   "seed": 3},
  {"type": "terrain", "size": [6, 6], "quads": [9, 7], "height": 0, "center": [0, 6, 0]}]})";

struct Case {
  Balance balance;
  int num_pes, routing;
  const char* scene = kScene;
  std::string dir;               // where its files are
  std::vector<int> spread = {1};  // the objects made in windows
  std::vector<int> ranks = {1, 2, 3, 4};
  bool pilot = true;  // the facets' clusters too (expect_same_banks); instances have none
};

Scene read(const Case& c, const SceneShare& share = SceneShare()) {
  return load_scene_from_string(c.scene, "scene.json", c.dir, kMaxTriangles, share);
}

template <class V>
bool same_bytes(const V& a, const V& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(a[0])) == 0);
}

// Everything a renderer reads of the banks: the group's banks and the
// tables every PE knows. (`source`, the scene triangle of each facet, is
// an index into the share the rank read, not into the whole scene.)
void expect_same_banks(const PreparedBanks& one, const PreparedBanks& ranks) {
  const BankedScene &a = one.scene, &b = ranks.scene;
  EXPECT_EQ(one.tri_base, ranks.tri_base);
  EXPECT_EQ(one.balance, ranks.balance);
  EXPECT_EQ(a.num_pes, b.num_pes);
  EXPECT_TRUE(same_bytes(a.triangles, b.triangles)) << "bank facets";
  EXPECT_TRUE(same_bytes(a.nodes, b.nodes)) << "bank BVH nodes";
  EXPECT_TRUE(same_bytes(a.clusters, b.clusters)) << "clusters";
  EXPECT_TRUE(same_bytes(a.instances, b.instances)) << "instances";
  EXPECT_TRUE(same_bytes(a.route_nodes, b.route_nodes)) << "routing nodes";
  EXPECT_TRUE(same_bytes(a.pes, b.pes)) << "PE table";
  EXPECT_TRUE(same_bytes(a.materials, b.materials)) << "materials";
  EXPECT_TRUE(same_bytes(a.lights, b.lights)) << "lights";
  EXPECT_TRUE(same_bytes(a.attributes, b.attributes)) << "vertex attributes";
  EXPECT_TRUE(same_bytes(a.textures, b.textures)) << "texture copies";
  EXPECT_TRUE(same_bytes(a.texels, b.texels)) << "texels";
  EXPECT_EQ(a.bank_bytes, b.bank_bytes);
  EXPECT_EQ(a.texture_bytes, b.texture_bytes);
  EXPECT_EQ(a.texture_replicated_bytes, b.texture_replicated_bytes);
  EXPECT_EQ(a.global_bytes, b.global_bytes);
  EXPECT_EQ(a.replicated_bytes, b.replicated_bytes);
  EXPECT_EQ(a.tri_cluster, b.tri_cluster);
  EXPECT_EQ(a.node_cluster, b.node_cluster);
}

// Work "measured" per facet and level, a function of the facet alone (so
// the same for a share's copy of it): hot where the terrain rises to the
// sphere, cold elsewhere, with some spread so no two clusters tie.
MeasuredWork measured_work(const Scene& scene) {
  MeasuredWork m;
  m.levels = 2;
  for (const Triangle& t : scene.triangles) {
    const float hot = t.v0[0] < -2.0f ? 40.0f : 1.0f;
    const float spread = 1.0f + float((t.facet_id * 7 + t.fan * 3) % 11) / 8.0f;
    m.per_facet.push_back(hot * spread);
    m.per_facet.push_back(hot * spread * 0.25f + float(t.object_id));
  }
  return m;
}

RaySample traced_sample(const Scene& scene, const SampleJoin* join) {
  return ReferenceTracer(scene).sample_rays(1500, join);
}

void expect_shares_bank_as_one(const Case& c) {
  const Scene whole = read(c);
  MeasuredWork whole_work;
  RaySample whole_sample;
  BalancePolicy policy;
  policy.balance = c.balance;
  policy.pilot = c.pilot;
  if (c.balance == Balance::measured) whole_work = measured_work(whole), policy.measured = &whole_work;
  if (c.balance == Balance::work) whole_sample = traced_sample(whole, nullptr), policy.sample = &whole_sample;
  if (c.balance != Balance::facets) {  // the balance cuts hot clusters: more than by facets
    const PeGroup all = pe_group(c.num_pes, 1, 0);
    EXPECT_GT(bank_scene(whole, c.num_pes, c.routing, policy, all).scene.clusters.size(),
              bank_scene(whole, c.num_pes, c.routing, BalancePolicy(), all).scene.clusters.size());
  }
  for (int R : c.ranks) {
    SCOPED_TRACE(std::to_string(R) + " ranks");
    std::vector<PreparedBanks> got(static_cast<std::size_t>(R));
    test::run_ranks(R, [&](Ranks& ranks) {
      Scene share = read(c, scene_share_for(ranks));
      ASSERT_EQ(share.total_triangles(), whole.triangles.size());
      if (ranks.size() > 1) {
        EXPECT_EQ(share.share.spread, c.spread) << "the large objects, made in windows";
        EXPECT_LT(share.triangles.size(), whole.triangles.size() / 2 + 400) << "a share, not the scene";
      }
      MeasuredWork work;
      RaySample sample;
      ShareBalance how;
      how.pilot = c.pilot;
      if (c.balance == Balance::measured) work = measured_work(share), how.measured = &work;
      if (c.balance == Balance::work) {
        sample = balance_sample(share, traced_sample, ranks);  // traced by the ranks together
        EXPECT_TRUE(same_bytes(sample.rays, whole_sample.rays)) << "the sample is one process's";
        how.sample = &sample;
      }
      got[std::size_t(ranks.rank())] =
          bank_share(share, c.num_pes, c.routing, pe_group(c.num_pes, ranks.size(), ranks.rank()), ranks, how);
    });
    std::size_t held = 0;
    for (int r = 0; r < R; ++r) {
      SCOPED_TRACE("rank " + std::to_string(r));
      const PeGroup group = pe_group(c.num_pes, R, r);
      expect_same_banks(bank_scene(whole, c.num_pes, c.routing, policy, group), got[std::size_t(r)]);
      held += got[std::size_t(r)].scene.triangles.size();
    }
    std::size_t copies = 0;  // the models' facets, once in each bank that places them
    if (!whole.instances.empty())
      for (int f : instance_shares(whole, deal_instances(whole, c.num_pes), c.num_pes, R).facets) copies += std::size_t(f);
    EXPECT_EQ(held, whole.triangles.size() + copies) << "every facet in one bank";
  }
}

TEST(CollectivePartition, SharesBankAsOneProcessByFacets) {
  expect_shares_bank_as_one({Balance::facets, 12, OPSILA_ROUTING_SPHERES});
  expect_shares_bank_as_one({Balance::facets, 7, OPSILA_ROUTING_BOXES});
}

// At 64 PEs the hot clusters are cut again (collective_balance.cpp): the
// terrain's by every rank together, the small objects' by their own rank.
TEST(CollectivePartition, SharesBankAsOneProcessByMeasuredWork) {
  expect_shares_bank_as_one({Balance::measured, 64, OPSILA_ROUTING_SPHERES});
}

TEST(CollectivePartition, SharesBankAsOneProcessBySampledWork) {
  expect_shares_bank_as_one({Balance::work, 64, OPSILA_ROUTING_BOXES});
}

// An OBJ grid of n x n quads over a gentle slope: each quad fans into two
// triangles that share its facet id.
std::string quad_grid(int n) {
  std::string obj;
  for (int z = 0; z <= n; ++z)
    for (int x = 0; x <= n; ++x)
      obj += "v " + std::to_string(x * 0.05) + " " + std::to_string((x % 7 + z % 5) * 0.01) + " " +
             std::to_string(z * 0.05) + "\n";
  for (int z = 0; z < n; ++z)
    for (int x = 0; x < n; ++x) {
      const int a = z * (n + 1) + x + 1;  // OBJ counts from 1
      obj += "f " + std::to_string(a) + " " + std::to_string(a + n + 1) + " " + std::to_string(a + n + 2) + " " +
             std::to_string(a + 1) + "\n";
    }
  return obj;
}

// Instances (every rank holds them all and banks its own PEs'): the model
// copies, the instance BVHs and clusters and the instance table as one
// process's, beside a terrain spread over the ranks and smooth models.
TEST(CollectivePartition, SharesBankInstancesAsOneProcess) {
  Case c{Balance::facets, 12, OPSILA_ROUTING_BOXES};
  c.scene = R"({"smooth": true, "objects": [
    {"type": "terrain", "size": [20, 20], "quads": [39, 41], "height": 3, "transform": {"rotate": [0, 30, 0]}},
    {"type": "instances", "model": {"type": "sphere", "center": [0, 0, 0], "radius": 0.5, "subdivisions": 2},
     "grid": {"counts": [7, 2, 5], "min": [-8, 4, -8], "max": [8, 6, 8], "jitter": 0.5, "scale": [0.5, 2],
              "rotate_y": [0, 90], "seed": 9}},
    {"type": "instances", "model": {"type": "box", "center": [0, 0, 0], "size": [1, 2, 1]},
     "transforms": [{"translate": [0, 8, 0]}, {"rotate": [10, 20, 30], "translate": [3, 8, 1]}]},
    {"type": "sphere", "center": [0, 4, 0], "radius": 1, "subdivisions": 2}]})";
  c.pilot = false;
  c.spread = {0};
  expect_shares_bank_as_one(c);
  c.balance = Balance::work;
  c.num_pes = 16;
  expect_shares_bank_as_one(c);
}

// More than 2^16 facets a rank: the exchange takes several rounds, every
// rank sending to every rank in each, a cluster's facets over several of
// them. The spread OBJ's quads give facets that share an id, which a rank
// receives from several ranks.
TEST(CollectivePartition, SharesBankAsOneProcessOverSeveralRounds) {
  test::TempDir dir;
  dir.write("quads.obj", quad_grid(300));
  Case c{Balance::facets, 8, OPSILA_ROUTING_SPHERES};
  c.scene = R"({"objects": [{"type": "obj", "file": "quads.obj"},
    {"type": "terrain", "size": [20, 20], "quads": [300, 300], "height": 3, "center": [0, -2, 0]}]})";
  c.dir = dir.path();
  c.spread = {0, 1};
  c.ranks = {3, 4};  // both objects spread over the ranks
  expect_shares_bank_as_one(c);
}

}  // namespace
}  // namespace opsila
