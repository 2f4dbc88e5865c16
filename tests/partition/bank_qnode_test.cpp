// The quantised node layout (BankQNode, host/partition/bank_qnode.cpp): every
// child box decodes exactly to a grid box that holds its float box, not much
// larger; and the walks that read it (a GPU's layout, forced here) give the
// float layout's frames byte for byte, at any PE count.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>

#include "core/errors.h"
#include "frame/renderer.h"
#include "prepare/prepare_banks.h"
#include "partition/bank_bvh.h"
#include "partition/bank_qnode.h"
#include "partition/partition.h"
#include "instance_scenes.h"
#include "test_device.h"
#include "test_scenes.h"

namespace opsila {
namespace {

constexpr int kWidth = OPSILA_BVH_WIDTH;

// Child k's float box holds nothing the decoded box does not, and the
// decoded box is at most two grid steps wider per side than needed; the
// step is no finer than a float near the box can tell (2^-23 of it).
void expect_holds(const BankNode& n, const BankQNode& q, const std::string& what) {
  const float* flo[3] = {n.lo_x, n.lo_y, n.lo_z};
  const float* fhi[3] = {n.hi_x, n.hi_y, n.hi_z};
  for (int k = 0; k < kWidth; ++k) {
    EXPECT_EQ(q.child[k], n.child[k]) << what;
    EXPECT_EQ(q.count[k], n.count[k]) << what;
    float lo[3], hi[3];
    quantised_box(q, k, lo, hi);
    for (int a = 0; a < 3; ++a) {
      if (n.count[k] < 0) {
        EXPECT_GT(lo[a], hi[a]) << what << ": empty slot " << k << " not inverted";
        continue;
      }
      const double step = std::ldexp(1.0, int(q.exponent[a]) - 127);
      // Exact: the float decoding equals the decoding in doubles.
      const opsila_u8 qlo = (a == 0 ? q.lo_x : a == 1 ? q.lo_y : q.lo_z)[k];
      EXPECT_EQ(double(lo[a]), qlo * step + double(q.origin[a])) << what << ": child " << k << " axis " << a;
      ASSERT_LE(lo[a], flo[a][k]) << what << ": child " << k << " axis " << a;
      ASSERT_GE(hi[a], fhi[a][k]) << what << ": child " << k << " axis " << a;
      EXPECT_LT(double(flo[a][k]) - lo[a], step) << what;
      EXPECT_LT(double(hi[a]) - fhi[a][k], step) << what;
    }
  }
}

BankNode random_node(std::mt19937& rng, double centre, double size, int used) {
  BankNode n = empty_node();
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int k = 0; k < used; ++k) {
    float* lo[3] = {n.lo_x, n.lo_y, n.lo_z};
    float* hi[3] = {n.hi_x, n.hi_y, n.hi_z};
    for (int a = 0; a < 3; ++a) {
      float x = float(centre + size * u(rng)), y = float(centre + size * u(rng));
      if (k == 1) y = x;  // a flat box
      lo[a][k] = std::min(x, y), hi[a][k] = std::max(x, y);
    }
    n.child[k] = 7 * k, n.count[k] = k % 3;
  }
  return n;
}

TEST(QuantisedNodes, HoldEveryFloatBoxOnAnExactGrid) {
  std::mt19937 rng(1987);
  // Boxes of every size, near and far from the origin: tiny boxes far out
  // are where the grid must coarsen to stay exact.
  for (double centre : {0.0, 1.0, -3.5, 1e3, -7e5, 3e7, 1e-20})
    for (double size : {1e-30, 1e-6, 0.01, 1.0, 250.0, 1e6})
      for (int used : {1, 2, 5, kWidth}) {
        const std::string what = "centre " + std::to_string(centre) + ", size " + std::to_string(size) + ", " +
                                 std::to_string(used) + " children";
        const BankNode n = random_node(rng, centre, size, used);
        expect_holds(n, quantise_node(n), what);
        if (::testing::Test::HasFatalFailure()) return;
      }
  expect_holds(empty_node(), quantise_node(empty_node()), "a node with no child");
}

// A node's grid is as fine as its box allows: 255 steps over its extent.
TEST(QuantisedNodes, TheGridIsTheFinestThatCoversTheNode) {
  BankNode n = empty_node();
  n.lo_x[0] = n.lo_y[0] = n.lo_z[0] = 1.0f;
  n.hi_x[0] = n.hi_y[0] = 3.0f, n.hi_z[0] = 1.0f + 255.0f / 64;
  n.count[0] = 1;
  const BankQNode q = quantise_node(n);
  EXPECT_EQ(int(q.exponent[0]) - 127, -6) << "255 steps of 2^-7 fall short of 2";
  EXPECT_EQ(int(q.exponent[2]) - 127, -6) << "255 steps of 2^-6 exactly";
  float lo[3], hi[3];
  quantised_box(q, 0, lo, hi);
  EXPECT_EQ(lo[0], 1.0f);
  EXPECT_EQ(hi[0], 3.0f);
  EXPECT_EQ(hi[2], 1.0f + 255.0f / 64);
}

TEST(QuantisedNodes, EveryBankNodeOfAScene) {
  const Scene s = test::tie_scene(64, 6);
  for (int pes : {1, 16}) {
    const BankedScene bs = partition_scene(s, pes);
    const BankArray<BankQNode> q = quantise_nodes(bs.nodes);
    ASSERT_EQ(q.size(), bs.nodes.size());
    for (std::size_t i = 0; i < q.size(); ++i) {
      expect_holds(bs.nodes[i], q[i], std::to_string(pes) + " PEs, node " + std::to_string(i));
      if (::testing::Test::HasFatalFailure()) return;
    }
  }
}

// --stats' bank bytes count the nodes the walks read: each bank's shrink by
// 128 bytes a node (none in an empty bank), and without instances (whose
// models a device holds once for several banks) by as much in all as the
// device's bytes.
void expect_half_node_bytes(const RenderStats& floats, const RenderStats& quantised, bool no_instances) {
  ASSERT_EQ(floats.bank_bytes.size(), quantised.bank_bytes.size());
  std::uint64_t saved = 0;
  for (std::size_t p = 0; p < floats.bank_bytes.size(); ++p) {
    ASSERT_GE(floats.bank_bytes[p], quantised.bank_bytes[p]) << "bank " << p;
    const std::uint64_t d = floats.bank_bytes[p] - quantised.bank_bytes[p];
    EXPECT_EQ(d % (sizeof(BankNode) - sizeof(BankQNode)), 0u) << "bank " << p;
    saved += d;
  }
  EXPECT_GT(saved, 0u);
  if (no_instances) EXPECT_EQ(saved, floats.device_bytes - quantised.device_bytes);
}

// The image and the item buffer do not depend on the layout: the hit order
// decides, whatever boxes the walks visit (kernels/hit_order.h).
TEST(QuantisedNodes, GiveTheFloatLayoutsFrames) {
  ClRuntime& floats = test::shared_runtime();
  if (floats.quantised_nodes()) GTEST_SKIP() << "the test device reads quantised nodes already";
  ClRuntimeOptions o;
  o.node_layout = ClRuntimeOptions::NodeLayout::quantised;
  ClRuntime quantised(test::test_device(), o);
  ASSERT_TRUE(quantised.quantised_nodes());
  const Scene scenes[] = {test::tie_scene(40, 5), test::mirror_glass_scene(40, 4),
                          test::textured_smooth_scene(32, true), test::instanced_scene(40)};
  for (const Scene& s : scenes)
    for (int pes : {1, 16, 64}) {
      SCOPED_TRACE(std::to_string(pes) + " PEs, " + std::to_string(s.triangles.size()) + " triangles");
      RenderSettings rs;
      rs.num_pes = pes;
      rs.item_buffer_output = true;
      const RenderResult a = render(s, rs, floats), b = render(s, rs, quantised);
      ASSERT_EQ(a.rgb.size(), b.rgb.size());
      EXPECT_EQ(0, std::memcmp(a.rgb.data(), b.rgb.data(), a.rgb.size() * sizeof(float)));
      EXPECT_EQ(a.item_buffer, b.item_buffer);
      EXPECT_FALSE(a.stats.quantised_nodes);
      EXPECT_TRUE(b.stats.quantised_nodes) << "--stats names the layout the walks read";
      expect_half_node_bytes(a.stats, b.stats, s.instances.empty());
    }
}

TEST(QuantisedNodes, ABadSwitchIsAnInputError) {
  ::setenv("OPSILA_QUANT_NODES", "yes", 1);
  try {
    ClRuntime rt(test::test_device());
    ::unsetenv("OPSILA_QUANT_NODES");
    FAIL() << "OPSILA_QUANT_NODES=yes was taken";
  } catch (const InputError& e) {
    ::unsetenv("OPSILA_QUANT_NODES");
    EXPECT_STREQ(e.what(), "OPSILA_QUANT_NODES=yes: expected 0 or 1");
  }
}

}  // namespace
}  // namespace opsila
