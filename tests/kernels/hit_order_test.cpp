// kernels/hit_order.h, the one nearest-hit order (docs/CONTRACT.md "Nearest
// hit"): a strict total order on near ties, exact ties, fans and coincident
// facets, whose least hit is the same in every order the hits are found in,
// on the host and on the device.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <set>
#include <tuple>
#include <vector>

#include "batch.h"
#include "hit_order.h"

namespace opsila {
namespace {

struct Hit {
  float t;
  int facet, fan;
};
using HitSet = std::vector<Hit>;

float ulps_after(float t, int ulps) { return hit_bits_float(hit_float_bits(t) + static_cast<hit_bits_t>(ulps)); }

// Hit sets of one ray where a pairwise tolerance goes wrong: chains of
// distances a few ulps apart (each near the next, not the last), exact
// ties, several triangles of one facet (a non-planar fan on its shared
// edges), equal distances on two facets (coincident facets of two objects),
// and distances astride a grid cell's end. Each (facet, fan) once.
std::vector<HitSet> hit_sets(unsigned seed, int count, int n) {
  std::mt19937 gen(seed);
  std::uniform_real_distribution<float> base(0.01f, 100.0f);
  std::uniform_int_distribution<int> step(0, 12), facet(0, 5), fan(0, 3), kind(0, 2);
  std::vector<HitSet> sets;
  while (static_cast<int>(sets.size()) < count) {
    float t = base(gen);
    if (kind(gen) == 0)  // the last ulp of a cell: the chain crosses into the next
      t = hit_bits_float(hit_float_bits(t) | OPSILA_HIT_GRID_MASK);
    std::set<std::pair<int, int>> used;
    HitSet s;
    while (static_cast<int>(s.size()) < n) {
      const std::pair<int, int> ids{facet(gen), fan(gen)};
      if (!used.insert(ids).second) continue;
      s.push_back({t, ids.first, ids.second});
      if (kind(gen) != 0) t = ulps_after(t, step(gen));  // else an exact tie with the next
    }
    sets.push_back(s);
  }
  return sets;
}

// The contract's order written out: (the distance's cell, facet, fan).
std::tuple<hit_bits_t, int, int> order_key(const Hit& h) {
  return {hit_float_bits(h.t) >> OPSILA_HIT_GRID_BITS, h.facet, h.fan};
}
int expected_winner(const HitSet& s) {
  return static_cast<int>(std::min_element(s.begin(), s.end(), [](const Hit& a, const Hit& b) {
                            return order_key(a) < order_key(b);
                          }) - s.begin());
}

// Folds the hits in `order` as a walk does: keep a hit that comes first.
template <typename Before>
int fold(const HitSet& s, const std::vector<int>& order, Before before) {
  int won = -1;
  for (int h : order)
    if (won < 0 || before(s[std::size_t(h)], s[std::size_t(won)])) won = h;
  return won;
}
bool order_before(const Hit& a, const Hit& b) { return hit_before(a.t, -1, a.facet, a.fan, hit_key(b.t, -1, b.facet, b.fan)); }

TEST(HitOrder, IsAStrictTotalOrderOnNearAndExactTies) {
  for (const HitSet& s : hit_sets(1, 300, 8)) {
    for (const Hit& a : s) {
      EXPECT_FALSE(order_before(a, a));
      for (const Hit& b : s) {
        if (&a == &b) continue;
        EXPECT_NE(order_before(a, b), order_before(b, a)) << "two hits of distinct triangles are always ordered";
        for (const Hit& c : s)
          if (order_before(a, b) && order_before(b, c)) EXPECT_TRUE(order_before(a, c)) << "not transitive";
      }
    }
  }
}

TEST(HitOrder, TheLeastHitIsTheSameInEveryOrder) {
  std::mt19937 gen(7);
  for (const HitSet& s : hit_sets(2, 500, 10)) {
    const int want = expected_winner(s);
    std::vector<int> order(s.size());
    std::iota(order.begin(), order.end(), 0);
    for (int k = 0; k < 40; ++k) {
      std::shuffle(order.begin(), order.end(), gen);
      ASSERT_EQ(fold(s, order, order_before), want);
    }
  }
}

// The rule the order replaced, a relative tolerance compared pair by pair
// (then the lower facet), gives two winners for one hit set in two orders
// on these sets: what the test above would catch.
TEST(HitOrder, APairwiseToleranceIsNotAnOrder) {
  const auto tolerance_before = [](const Hit& a, const Hit& b) {
    const float tol = 1e-6f * b.t;
    return a.t < b.t - tol || (a.t <= b.t + tol && a.facet < b.facet);
  };
  std::mt19937 gen(7);
  int unstable = 0;
  for (HitSet s : hit_sets(3, 500, 10)) {
    for (Hit& h : s) h.t = ulps_after(h.t, 4 * h.facet);  // chains long enough to span the tolerance
    std::vector<int> order(s.size());
    std::iota(order.begin(), order.end(), 0);
    std::set<int> winners;
    for (int k = 0; k < 40; ++k) {
      std::shuffle(order.begin(), order.end(), gen);
      winners.insert(fold(s, order, tolerance_before));
    }
    unstable += winners.size() > 1;
  }
  EXPECT_GT(unstable, 0);
}

// hit_limit: every distance below it can win against the best (its cell is
// not after the best's), none at or beyond it; culling widens, never narrows.
TEST(HitOrder, TheLimitBoundsTheHitsThatCanWin) {
  std::mt19937 gen(11);
  std::uniform_real_distribution<float> t(1e-6f, 1e6f);
  for (int i = 0; i < 100000; ++i) {
    const float best = t(gen), limit = hit_limit(best);
    ASSERT_GT(limit, best);
    ASSERT_LE(hit_grid(std::nextafter(limit, 0.0f)), hit_grid(best));
    ASSERT_GT(hit_grid(limit), hit_grid(best));
    ASSERT_GE(cull_exit(limit, 0.0f), limit);
    ASSERT_GE(cull_exit(-limit, 0.0f), -limit);
  }
  EXPECT_EQ(hit_limit(OPSILA_HIT_INF), OPSILA_HIT_INF);
  EXPECT_TRUE(hit_before(1e30f, -1, 0x7ffffffe, 0, hit_none()));
}

// The device folds the same sets, each in many random orders, to the host's
// winner (hit_order.h compiled as OpenCL C).
TEST(HitOrderKernel, EveryOrderOnTheDeviceGivesTheHostsWinner) {
  constexpr int kSets = 400, kOrders = 16, kHits = 10;
  const std::vector<HitSet> sets = hit_sets(4, kSets, kHits);
  std::vector<float> t;
  std::vector<cl_int2> ids;
  for (const HitSet& s : sets)
    for (const Hit& h : s) t.push_back(h.t), ids.push_back({{h.facet, h.fan}});
  std::mt19937 gen(5);
  std::vector<cl_int> set_of, order;
  for (int s = 0; s < kSets; ++s) {
    std::vector<int> o(kHits);
    std::iota(o.begin(), o.end(), 0);
    for (int k = 0; k < kOrders; ++k) {
      std::shuffle(o.begin(), o.end(), gen);
      set_of.push_back(s);
      order.insert(order.end(), o.begin(), o.end());
    }
  }
  ClRuntime& rt = test::batch_runtime();
  const std::size_t count = set_of.size();
  cl::Buffer bt = test::to_device(rt, t), bids = test::to_device(rt, ids), bset = test::to_device(rt, set_of),
             border = test::to_device(rt, order), out = test::to_device(rt, std::vector<cl_int>(count));
  cl::Kernel k = rt.kernel("least_hit_batch");
  int a = 0;
  for (const cl::Buffer* b : {&bt, &bids, &bset, &border}) k.setArg(a++, *b);
  k.setArg(a++, cl_int(kHits));
  k.setArg(a++, cl_int(count));
  k.setArg(a++, out);
  test::run_batch(rt, k, count);
  const std::vector<cl_int> won = test::from_device<cl_int>(rt, out, count);
  for (std::size_t i = 0; i < count; ++i)
    ASSERT_EQ(won[i], expected_winner(sets[std::size_t(set_of[i])])) << "set " << set_of[i] << ", order " << i;
}

}  // namespace
}  // namespace opsila
