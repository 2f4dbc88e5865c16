// The descriptor exchange between ranks (frame/rank_exchange.h) on 1..4
// simulated ranks (tests/sim_ranks.h), each with a device runtime of its
// own, without a launcher: every record bound for another rank's PEs
// arrives there exactly once, whole, in (source rank, source order), ahead
// of the rank's own waiting records; the per-round figures count what went
// where, and rounds past the cap add into the last kept one.
#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include "device/device_buffers.h"
#include "exchange_check.h"
#include "frame/rank_exchange.h"
#include "sim_ranks.h"
#include "test_device.h"

namespace opsila {
namespace {

constexpr int kPes = 7, kDepth = 3;

// Rank r's records of round `round`, each named by its pixel, its
// destination drawn at random (some for every rank's PEs, more for PE 0's).
std::vector<HostDescriptor> records_of_rank(int r, int round) {
  std::vector<HostDescriptor> v;
  const int n = 40 + 37 * r + 11 * round;
  for (int k = 0; k < n; ++k) {
    const unsigned h = unsigned(k) * 2654435761u + unsigned(r) * 40503u + unsigned(round) * 977u;
    v.push_back(test::exchange_entry(100000 * r + 1000 * round + k, (h >> 7) % 3 == 0 ? 0 : int((h >> 9) % kPes)));
  }
  // The exchange leaves them grouped by destination PE, each PE's in order.
  std::stable_sort(v.begin(), v.end(), [](const auto& a, const auto& b) { return desc_dest(a) < desc_dest(b); });
  return v;
}

bool in_group(const HostDescriptor& d, const PeGroup& g) { return desc_dest(d) >= g.begin && desc_dest(d) < g.end; }

// What rank r's pool must hold after the exchange: every other rank's
// records for its PEs, by source rank, then its own that stay.
std::vector<HostDescriptor> expected_pool(int r, int R, int round) {
  const PeGroup g = pe_group(kPes, R, r);
  std::vector<HostDescriptor> pool;
  for (int q = 0; q <= R; ++q) {
    if (q == r) continue;
    const int source = q == R ? r : q;
    for (const HostDescriptor& d : records_of_rank(source, round))
      if (in_group(d, g)) pool.push_back(d);
  }
  return pool;
}

// One rank's rounds of the exchange, each pool checked (every record lies
// in one rank's expected pool: together they hold each once).
void exchange_rounds(Ranks& ranks, ClRuntime& rt, int rounds, std::size_t round_cap) {
  const int r = ranks.rank(), R = ranks.size();
  const PeGroup g = pe_group(kPes, R, r);
  RankExchange ex(rt, ranks, g, kPes, kDepth, round_cap);
  std::vector<std::vector<std::uint64_t>> sent, received;
  for (int round = 0; round < rounds; ++round) {
    SCOPED_TRACE("rank " + std::to_string(r) + ", round " + std::to_string(round));
    const std::vector<HostDescriptor> mine = records_of_rank(r, round);
    std::vector<cl_int> totals(kPes, 0);
    for (const HostDescriptor& d : mine) ++totals[std::size_t(desc_dest(d))];
    const cl::Buffer pe_total = upload(rt, totals, "test PE totals");
    DescriptorSet next, into;
    next.allocate(rt, mine.size(), "test next pool");
    next.write(rt, mine, 0, kDepth);
    ex.start(pe_total, next, mine.size());
    ex.exchange();
    const std::size_t len = ex.finish(next, into, 5);
    EXPECT_GE(into.capacity, len + 5);
    const std::vector<HostDescriptor> expected = expected_pool(r, R, round);
    ASSERT_EQ(len, expected.size());
    const std::vector<HostDescriptor> got = into.read(rt, len);
    const std::vector<cl_int> keys = test::from_device<cl_int>(rt, into.dests, len);
    for (std::size_t i = 0; i < len; ++i) {
      EXPECT_TRUE(test::same_record(got[i], expected[i]))
          << "entry " << i << ": pixel " << desc_pixel(got[i]) << ", expected " << desc_pixel(expected[i]);
      EXPECT_EQ(keys[i], desc_key(expected[i], kDepth)) << "entry " << i << "'s sort key";
    }
    std::uint64_t own = 0;
    std::vector<std::uint64_t> to(std::size_t(R), 0), from(std::size_t(R), 0);
    for (const HostDescriptor& d : mine)
      (in_group(d, g) ? own : to[std::size_t(rank_of_pe(kPes, R, desc_dest(d)))]) += 1;
    for (int q = 0; q < R; ++q)
      for (const HostDescriptor& d : q == r ? std::vector<HostDescriptor>() : records_of_rank(q, round))
        from[std::size_t(q)] += in_group(d, g);
    EXPECT_EQ(ex.waiting(), own);
    keep_round(sent, to, round_cap);
    keep_round(received, from, round_cap);
  }
  EXPECT_EQ(ex.sent, sent) << "[round][rank] sent, the rounds past the cap added into the last";
  EXPECT_EQ(ex.received, received);
  EXPECT_EQ(ex.sent.size(), std::min<std::size_t>(std::size_t(rounds), round_cap));
  EXPECT_EQ(ex.mpi_seconds.size(), ex.sent.size());
}

TEST(RankExchange, RecordsArriveOnceInSourceRankOrder) {
  std::vector<std::unique_ptr<ClRuntime>> runtimes;  // one device context per rank, as each MPI rank has
  for (int r = 0; r < 4; ++r) runtimes.push_back(std::make_unique<ClRuntime>(test::test_device()));
  for (int R = 1; R <= 4; ++R) {
    SCOPED_TRACE(std::to_string(R) + " ranks");
    test::run_ranks(R, [&](Ranks& ranks) { exchange_rounds(ranks, *runtimes[std::size_t(ranks.rank())], 3, 2); });
  }
}

}  // namespace
}  // namespace opsila
