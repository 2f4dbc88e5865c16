// The collective median cut without MPI: the radix select run by 1..4
// simulated ranks in one process finds the key nth_element puts in the
// middle, so the halves are the same; and a terrain made in windows is
// bit for bit the whole terrain's triangles.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <random>
#include <utility>
#include <vector>

#include "input/primitives.h"
#include "machine/collective_cut.h"

namespace opsila {
namespace {

// Keys dealt at random to R simulated ranks, selected in step: each step
// every rank's histogram, summed, narrows every rank.
std::uint64_t select_on_ranks(const std::vector<std::uint64_t>& keys, std::uint64_t k, int R, std::mt19937& rng) {
  std::vector<std::vector<std::uint64_t>> dealt(static_cast<std::size_t>(R));
  for (std::uint64_t key : keys) dealt[rng() % std::size_t(R)].push_back(key);
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
  for (const RadixSelect& r : ranks) EXPECT_EQ(r.key(), ranks[0].key()) << "every rank agrees";
  return ranks[0].key();
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
    std::vector<std::pair<float, int>> sorted = facets;
    std::nth_element(sorted.begin(), sorted.begin() + std::ptrdiff_t(mid), sorted.end(), [](const auto& a, const auto& b) {
      return a.first < b.first || (a.first == b.first && a.second < b.second);
    });
    std::vector<int> lower;
    for (std::size_t i = 0; i < mid; ++i) lower.push_back(sorted[i].second);
    std::sort(lower.begin(), lower.end());
    for (int R = 1; R <= 4; ++R) {
      SCOPED_TRACE("n " + std::to_string(n) + ", " + std::to_string(R) + " ranks");
      const std::uint64_t median = select_on_ranks(keys, mid, R, rng);
      std::vector<int> below;
      for (std::size_t i = 0; i < n; ++i)
        if (keys[i] < median) below.push_back(facets[i].second);
      EXPECT_EQ(below, lower);
      EXPECT_EQ(median & 0xffffffffu, std::uint64_t(sorted[mid].second)) << "the median facet itself";
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
  for (std::uint64_t k = 0; k < keys.size(); ++k) EXPECT_EQ(select_key(keys, k, sum), 2 * k + 1);
  EXPECT_EQ(calls, 5 * 64 / RadixSelect::kDigitBits);
}

TEST(CollectiveCut, KeysOrderAsCentroidsThenIndex) {
  EXPECT_EQ(cut_key(-0.0f, 4), cut_key(0.0f, 4));
  EXPECT_LT(cut_key(-1.0f, 9), cut_key(-0.5f, 0));
  EXPECT_LT(cut_key(-1e-30f, 9), cut_key(0.0f, 0));
  EXPECT_LT(cut_key(0.0f, 9), cut_key(1e-30f, 0));
  EXPECT_LT(cut_key(2.0f, 3), cut_key(2.0f, 4));
  EXPECT_LT(cut_key(2.0f, 0xffffffffu), cut_key(std::nextafter(2.0f, 3.0f), 0));
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

}  // namespace
}  // namespace opsila
