// The collective median cut without MPI: the radix select run by 1..4
// simulated ranks in one process finds the key nth_element puts in the
// middle, so the halves are the same; a terrain spread over simulated
// ranks (tests/sim_ranks.h) is cut into one process's clusters; and a
// terrain made in windows is bit for bit the whole terrain's triangles.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <mutex>
#include <string>
#include <random>
#include <utility>
#include <vector>

#include "dist/collective_cut.h"
#include "formats/json/primitives.h"
#include "formats/json/scene_file.h"
#include "prepare/prepare.h"
#include "sim_ranks.h"

namespace opsila {
namespace {

// One process's lower half of a median cut: the indices nth_element puts
// below `mid` on (centroid, index), sorted; `median` gets the one at mid.
std::vector<int> one_process_lower(std::vector<std::pair<float, int>> sorted, std::size_t mid, int* median = nullptr) {
  std::nth_element(sorted.begin(), sorted.begin() + std::ptrdiff_t(mid), sorted.end(), [](const auto& a, const auto& b) {
    return a.first < b.first || (a.first == b.first && a.second < b.second);
  });
  std::vector<int> lower;
  for (std::size_t i = 0; i < mid; ++i) lower.push_back(sorted[i].second);
  std::sort(lower.begin(), lower.end());
  if (median) *median = sorted[mid].second;
  return lower;
}

// Each simulated rank's keys selected in step: each step every rank's
// histogram, summed, narrows every rank.
SelectedKey select_in_step(const std::vector<std::vector<std::uint64_t>>& dealt, std::uint64_t k) {
  std::vector<RadixSelect> ranks;
  for (auto& d : dealt) ranks.emplace_back(std::move(d), k);
  while (!ranks[0].done()) {
    std::vector<std::uint64_t> sum(RadixSelect::kBuckets, 0);
    for (const RadixSelect& r : ranks) {
      const std::vector<std::uint64_t> h = r.histogram();
      for (std::size_t b = 0; b < sum.size(); ++b) sum[b] += h[b];
    }
    for (RadixSelect& r : ranks) r.narrow(sum);
  }
  for (const RadixSelect& r : ranks) {
    EXPECT_EQ(r.key(), ranks[0].key()) << "every rank agrees";
    EXPECT_EQ(r.equal_below(), ranks[0].equal_below());
  }
  return {ranks[0].key(), ranks[0].equal_below()};
}

// Keys dealt at random to R simulated ranks.
std::uint64_t select_on_ranks(const std::vector<std::uint64_t>& keys, std::uint64_t k, int R, std::mt19937& rng) {
  std::vector<std::vector<std::uint64_t>> dealt(static_cast<std::size_t>(R));
  for (std::uint64_t key : keys) dealt[rng() % std::size_t(R)].push_back(key);
  const SelectedKey at = select_in_step(dealt, k);
  EXPECT_EQ(at.equal_below, 0u) << "keys with distinct facet ids never tie";
  return at.key;
}

TEST(CollectiveCut, RadixSelectMakesTheHalvesOfNthElement) {
  std::mt19937 rng(7);
  // Few distinct centroids (many ties, broken by index), both signs, -0 and +0.
  const float values[] = {-3.5f, -1.0f, -0.0f, 0.0f, 1e-30f, 0.25f, 2.0f, 7.75f, 1e20f};
  for (int trial = 0; trial < 40; ++trial) {
    const std::size_t n = 1 + rng() % 3000;
    std::vector<std::pair<float, int>> facets(n);
    std::vector<std::uint64_t> keys(n);
    for (std::size_t i = 0; i < n; ++i) {
      const float c = trial % 2 ? values[rng() % 9] : std::uniform_real_distribution<float>(-5, 5)(rng);
      facets[i] = {c, static_cast<int>(i * 3 + trial)};
      keys[i] = cut_key(c, static_cast<std::uint32_t>(facets[i].second));
    }
    const std::size_t mid = n / 2;
    int median_facet = 0;
    const std::vector<int> lower = one_process_lower(facets, mid, &median_facet);
    for (int R = 1; R <= 4; ++R) {
      SCOPED_TRACE("n " + std::to_string(n) + ", " + std::to_string(R) + " ranks");
      const std::uint64_t median = select_on_ranks(keys, mid, R, rng);
      std::vector<int> below;
      for (std::size_t i = 0; i < n; ++i)
        if (keys[i] < median) below.push_back(facets[i].second);
      EXPECT_EQ(below, lower);
      EXPECT_EQ(median & 0xffffffffu, std::uint64_t(median_facet)) << "the median facet itself";
    }
  }
}

TEST(CollectiveCut, SelectKeyAddsUpThroughItsCallback) {
  std::vector<std::uint64_t> keys = {9, 3, 7, 1, 5};
  int calls = 0;
  const auto sum = [&](std::vector<std::uint64_t>& h) {
    ++calls;
    EXPECT_EQ(h.size(), std::size_t(RadixSelect::kBuckets));
  };
  for (std::uint64_t k = 0; k < keys.size(); ++k) EXPECT_EQ(select_key(keys, k, sum).key, 2 * k + 1);
  EXPECT_EQ(calls, 5 * 64 / RadixSelect::kDigitBits);
}

// An OBJ polygon fans into triangles that share its facet id, and often
// its centroid on the cut axis (a flat quad's two halves): equal keys. The
// ranks hold whole polygons in windows, in file order; the halves must
// still be nth_element's on (centroid, index), the first of the tied
// triangles below the cut.
TEST(CollectiveCut, PolygonTiesSplitAsOneProcess) {
  std::mt19937 rng(11);
  const float values[] = {-2.0f, 0.0f, 0.5f, 3.0f};
  for (int trial = 0; trial < 60; ++trial) {
    std::vector<std::pair<float, int>> tris;  // centroid, one process's index
    std::vector<std::uint64_t> keys;
    std::vector<std::size_t> polygon_starts;
    for (std::uint32_t facet = 0; tris.size() < 20 + std::size_t(trial) * 40; ++facet) {
      polygon_starts.push_back(tris.size());
      const int fan = 1 + int(rng() % 5);
      const bool flat = rng() % 2;  // every triangle of the polygon at one centroid
      const float shared = values[rng() % 4];
      for (int k = 0; k < fan; ++k) {
        const float c = flat ? shared : values[rng() % 4];
        tris.push_back({c, static_cast<int>(tris.size())});
        keys.push_back(cut_key(c, facet));
      }
    }
    const std::size_t n = tris.size(), mid = n / 2;
    const std::vector<int> lower = one_process_lower(tris, mid);
    for (int R = 1; R <= 4; ++R) {
      SCOPED_TRACE("n " + std::to_string(n) + ", " + std::to_string(R) + " ranks");
      // Windows of whole polygons: cut points at polygon starts, maybe empty windows.
      std::vector<std::size_t> cuts = {0, n};
      for (int r = 1; r < R; ++r) cuts.push_back(polygon_starts[rng() % polygon_starts.size()]);
      std::sort(cuts.begin(), cuts.end());
      std::vector<std::vector<std::uint64_t>> dealt;
      for (int r = 0; r < R; ++r) dealt.emplace_back(keys.begin() + std::ptrdiff_t(cuts[r]), keys.begin() + std::ptrdiff_t(cuts[r + 1]));
      const SelectedKey at = select_in_step(dealt, mid);
      std::vector<int> below;
      for (int r = 0; r < R; ++r) {
        const std::vector<char> mine = lower_half(dealt[std::size_t(r)], at);
        for (std::size_t i = 0; i < mine.size(); ++i)
          if (mine[i]) below.push_back(static_cast<int>(cuts[std::size_t(r)] + i));
      }
      EXPECT_EQ(below, lower);
    }
  }
}

TEST(CollectiveCut, KeysOrderAsCentroidsThenIndex) {
  EXPECT_EQ(cut_key(-0.0f, 4), cut_key(0.0f, 4));
  EXPECT_LT(cut_key(-1.0f, 9), cut_key(-0.5f, 0));
  EXPECT_LT(cut_key(-1e-30f, 9), cut_key(0.0f, 0));
  EXPECT_LT(cut_key(0.0f, 9), cut_key(1e-30f, 0));
  EXPECT_LT(cut_key(2.0f, 3), cut_key(2.0f, 4));
  EXPECT_LT(cut_key(2.0f, 0xffffffffu), cut_key(std::nextafter(2.0f, 3.0f), 0));
}

// A facet's triangle by what names it in any share: (facet id, fan index).
std::vector<std::uint64_t> names_of(const Scene& scene, const std::vector<int>& tris) {
  std::vector<std::uint64_t> names;
  for (int t : tris) {
    const Triangle& tri = scene.triangles[std::size_t(t)];
    names.push_back(std::uint64_t(std::uint32_t(tri.facet_id)) << 32 | std::uint32_t(tri.fan));
  }
  std::sort(names.begin(), names.end());
  return names;
}

Box scene_box(const Scene& scene) {
  Vec3 lo, hi;
  scene.bounds(lo, hi);
  Box b;
  b.grow(lo);
  b.grow(hi);
  return b;
}

// split_share on 2..4 simulated ranks: the terrain spread over them is cut
// by every rank together (spread_bounds, cut_spread_at_median) into the
// clusters one process's split_object makes of it, in the same order, each
// cluster's facets spread over the ranks; the shares' figures add up to
// the whole scene's (combine_share).
TEST(CollectiveCut, ASpreadTerrainIsCutAsOneProcessCutsIt) {
  const std::string text = R"({"objects": [
    {"type": "sphere", "center": [0, 4, 0], "radius": 1, "subdivisions": 2},
    {"type": "terrain", "size": [20, 12], "quads": [37, 23], "height": 3, "transform": {"rotate": [0, 30, 0]}}]})";
  const Scene whole = load_scene_from_string(text, "terrain.json", "");
  const int pes = 9;
  using namespace partition_steps;
  const SplitLimits limits = split_limits(whole.triangles.size(), scene_box(whole), pes);
  std::vector<ClusterBuild> one;
  split_object(whole, triangles_by_object(whole)[1], limits.max_tris, limits.max_extent, false, one, split_threads());
  ASSERT_GT(one.size(), 4u);
  for (int R = 2; R <= 4; ++R) {
    SCOPED_TRACE(std::to_string(R) + " ranks");
    std::vector<std::vector<std::uint64_t>> clusters(one.size());  // every rank's facets of each
    std::mutex lock;
    test::run_ranks(R, [&](Ranks& ranks) {
      const Scene share = load_scene_from_string(text, "terrain.json", "", kMaxTriangles, scene_share_for(ranks));
      ASSERT_EQ(share.share.spread, std::vector<int>{1});
      EXPECT_EQ(share.total_triangles(), whole.triangles.size());
      const Box box = scene_box(share), whole_box = scene_box(whole);
      EXPECT_EQ(std::memcmp(&box, &whole_box, sizeof(Box)), 0) << "every rank's bounds";
      const ShareClusters split = split_share(share, box, pes, false, ranks, {});
      ASSERT_EQ(split.spread.size(), one.size());
      std::lock_guard<std::mutex> hold(lock);
      for (std::size_t k = 0; k < one.size(); ++k) {
        EXPECT_EQ(split.spread[k].facets, one[k].tris.size()) << "cluster " << k;
        const std::vector<int>& tris = split.clusters[std::size_t(split.spread[k].local)].tris;
        const std::vector<std::uint64_t> mine = names_of(share, tris);
        clusters[k].insert(clusters[k].end(), mine.begin(), mine.end());
      }
    });
    for (std::size_t k = 0; k < one.size(); ++k) {
      std::sort(clusters[k].begin(), clusters[k].end());
      EXPECT_EQ(clusters[k], names_of(whole, one[k].tris)) << "cluster " << k;
    }
  }
}

bool same_bits(const Triangle& a, const Triangle& b) { return std::memcmp(&a, &b, sizeof a) == 0; }

TEST(TerrainWindow, WindowsMakeTheWholeTerrainBitForBit) {
  TerrainDesc d;
  d.quads_x = 13;
  d.quads_z = 7;
  d.height = 3;
  d.center = {1.5f, -2, 0.25f};
  std::vector<Triangle> whole;
  ASSERT_EQ(add_terrain(whole, d, 4, 1, 2, 100), 100 + int(terrain_triangles(d)));
  ASSERT_EQ(whole.size(), std::size_t(2 * 13 * 7));
  std::mt19937 rng(3);
  for (int trial = 0; trial < 50; ++trial) {
    // Cut points at random (odd ones split a quad's two triangles), and empty windows.
    std::vector<std::size_t> cuts = {0, whole.size()};
    for (int k = 0; k < trial % 6; ++k) cuts.push_back(rng() % (whole.size() + 1));
    std::sort(cuts.begin(), cuts.end());
    std::vector<Triangle> pieces;
    for (std::size_t k = 0; k + 1 < cuts.size(); ++k)
      add_terrain_window(pieces, d, 4, 1, 2, 100, cuts[k], cuts[k + 1]);
    ASSERT_EQ(pieces.size(), whole.size());
    for (std::size_t i = 0; i < whole.size(); ++i) ASSERT_TRUE(same_bits(pieces[i], whole[i])) << "triangle " << i;
  }
}


// --balance measured sums each cluster's measured work per level in fixed
// point: the sum over a cluster's facets is the same in any order and when
// its facets are dealt to 1..4 ranks and the parts added up, which is what
// lets ranks holding parts of a cluster find one process's figure. (Summed
// in double, as before, these figures depend on the order: checked first,
// so the test would catch a return to it.)
TEST(MeasuredWork, SumsAreTheSameInAnyOrderAndOverAnyRanks) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> exponent(-12.0f, 24.0f);
  MeasuredWork m;
  m.levels = 3;
  const int n = 5000;
  for (int i = 0; i < n * m.levels; ++i) m.per_facet.push_back(std::exp2(exponent(rng)) * 1.37f);
  std::vector<int> tris(n);
  for (int i = 0; i < n; ++i) tris[std::size_t(i)] = i;
  std::vector<int> shuffled = tris;
  std::shuffle(shuffled.begin(), shuffled.end(), rng);
  const auto in_double = [&](const std::vector<int>& order) {
    double w = 0;
    for (int t : order) w += m.per_facet[std::size_t(t) * 3];
    return w;
  };
  ASSERT_NE(in_double(tris), in_double(shuffled)) << "figures whose double sum depends on the order";
  const std::vector<std::int64_t> whole = partition_steps::measured_sums(m, tris);
  EXPECT_EQ(partition_steps::measured_sums(m, shuffled), whole);
  for (int R = 1; R <= 4; ++R) {
    std::vector<std::vector<int>> dealt(static_cast<std::size_t>(R));
    for (int t : shuffled) dealt[std::size_t(rng() % unsigned(R))].push_back(t);
    std::vector<std::int64_t> added(3, 0);
    for (const std::vector<int>& part : dealt) {
      const std::vector<std::int64_t> s = partition_steps::measured_sums(m, part);
      for (int l = 0; l < 3; ++l) added[std::size_t(l)] += s[std::size_t(l)];
    }
    EXPECT_EQ(added, whole) << R << " ranks";
  }
  // The fixed point keeps the figures: 2^-16 of a test per facet at most.
  for (int l = 0; l < 3; ++l) {
    double exact = 0;
    for (int t : tris) exact += m.per_facet[std::size_t(t) * 3 + std::size_t(l)];
    EXPECT_NEAR(std::ldexp(double(whole[std::size_t(l)]), -partition_steps::kWorkFractionBits), exact,
                exact * 1e-12 + n * std::ldexp(1.0, -partition_steps::kWorkFractionBits));
  }
}

}  // namespace
}  // namespace opsila
