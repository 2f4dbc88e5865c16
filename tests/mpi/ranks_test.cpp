// The ranks' transport (mpi/ranks.h) on simulated ranks (tests/sim_ranks.h):
// the collectives' results in rank order, the exchanges' and messages'
// order, the failure agreement; one simulated rank answers as the MPI
// transport on one process does; and what would hang under MPI (a
// deadlock, collectives that do not match, a rank that left) fails here.
#include <gtest/gtest.h>

#include <atomic>
#include <cstring>
#include <mutex>
#include <string>
#include <vector>

#include "core/fixed_point.h"
#include "mpi/ranks.h"
#include "sim_ranks.h"

namespace opsila {
namespace {

using test::run_ranks;

std::vector<unsigned char> text_bytes(const std::string& s) { return std::vector<unsigned char>(s.begin(), s.end()); }
unsigned char byte(std::uint64_t v) { return static_cast<unsigned char>(v); }

TEST(SimRanks, CollectivesGiveEveryRanksValuesInRankOrder) {
  for (int R = 1; R <= 4; ++R) {
    SCOPED_TRACE(std::to_string(R) + " ranks");
    run_ranks(R, [R](Ranks& ranks) {
      const int r = ranks.rank();
      EXPECT_EQ(ranks.size(), R);
      ranks.barrier();
      EXPECT_EQ(ranks.sum(std::uint64_t(r + 1)), std::uint64_t(R * (R + 1) / 2));
      std::vector<std::uint64_t> v = {std::uint64_t(r), std::uint64_t(10 - r), ~std::uint64_t(0)};
      std::vector<std::uint64_t> m = v;
      ranks.max(m);
      EXPECT_EQ(m, (std::vector<std::uint64_t>{std::uint64_t(R - 1), 10, ~std::uint64_t(0)}));
      ranks.sum(v);  // unsigned: wraps modulo 2^64 as the fixed-point sums do
      EXPECT_EQ(v[0], std::uint64_t(R * (R - 1) / 2));
      EXPECT_EQ(v[2], ~std::uint64_t(0) * std::uint64_t(R));
      std::string all;
      for (int q = 0; q < R; ++q) all += std::string(std::size_t(q), char('a' + q));
      EXPECT_EQ(ranks.all_gather(text_bytes(std::string(std::size_t(r), char('a' + r)))), text_bytes(all));
      const std::vector<std::string> gathered = ranks.gather("rank" + std::to_string(r), R - 1);
      ASSERT_EQ(gathered.size(), r == R - 1 ? std::size_t(R) : 0u);
      for (int q = 0; q < int(gathered.size()); ++q) EXPECT_EQ(gathered[std::size_t(q)], "rank" + std::to_string(q));
      double value = r == R - 1 ? 2.5 : -1.0;
      ranks.broadcast(&value, sizeof value, R - 1);
      EXPECT_EQ(value, 2.5);
      std::vector<std::uint64_t> root = {std::uint64_t(r + 1)};
      ranks.reduce_sum(root, 0);
      EXPECT_EQ(root[0], r == 0 ? std::uint64_t(R * (R + 1) / 2) : std::uint64_t(r + 1)) << "valid on the root";
      // Pixel sums saturate: one marked (bit 63) with others just below it
      // would wrap past 2^64 as plain sums; two unmarked reach 2^63 together.
      const std::uint64_t mark = std::uint64_t(1) << 63;
      std::vector<std::uint64_t> sums = {r == 0 ? mark | 1 : mark - 1, mark / 2 + 1};
      ranks.reduce_sum(sums, 0);
      if (r == 0 && R > 1) EXPECT_TRUE(saturated(sums[0]) && saturated(sums[1])) << sums[0] << " " << sums[1];
      // The lowest failing rank's code, on every rank.
      int code = r > 0 && r % 2 == 1 ? 10 + r : 0;
      EXPECT_EQ(ranks.agree(code), R > 1 ? 1 : -1);
      EXPECT_EQ(code, R > 1 ? 11 : 0);
    });
  }
}

// Records sent to each rank arrive in source-rank order, each source's in
// the order it laid them out.
TEST(SimRanks, AllToAllDeliversBySourceThenSourceOrder) {
  for (int R = 1; R <= 4; ++R) {
    SCOPED_TRACE(std::to_string(R) + " ranks");
    run_ranks(R, [R](Ranks& ranks) {
      const int r = ranks.rank();
      std::vector<unsigned char> send;
      std::vector<std::uint64_t> counts;
      for (int d = 0; d < R; ++d) {
        counts.push_back(std::uint64_t((r + 2 * d) % 3));
        for (std::uint64_t k = 0; k < counts.back(); ++k) send.insert(send.end(), {byte(r), byte(d), byte(k)});
      }
      std::vector<unsigned char> recv;
      const std::vector<std::uint64_t> got = ranks.all_to_all(send, counts, 3, recv);
      std::vector<unsigned char> expected;
      for (int s = 0; s < R; ++s) {
        EXPECT_EQ(got[std::size_t(s)], std::uint64_t((s + 2 * r) % 3)) << "from rank " << s;
        for (int k = 0; k < (s + 2 * r) % 3; ++k) expected.insert(expected.end(), {byte(s), byte(r), byte(k)});
      }
      EXPECT_EQ(recv, expected);
    });
  }
}

// Messages between two ranks arrive in the order sent, for each tag apart.
TEST(SimRanks, MessagesArriveInOrderPerTag) {
  run_ranks(3, [](Ranks& ranks) {
    const int r = ranks.rank(), next = (r + 1) % 3, prev = (r + 2) % 3;
    std::vector<int> out = {r * 100, r * 100 + 1, r * 100 + 2};
    for (int k = 0; k < 3; ++k) ranks.send(&out[std::size_t(k)], sizeof(int), next, k == 1 ? 8 : 7);
    int a = 0, b = 0, c = 0;
    ranks.receive(&a, sizeof a, prev, 8);
    ranks.receive(&b, sizeof b, prev, 7);
    ranks.receive(&c, sizeof c, prev, 7);
    ranks.wait_sends();
    EXPECT_EQ(a, prev * 100 + 1);
    EXPECT_EQ(b, prev * 100);
    EXPECT_EQ(c, prev * 100 + 2);
  });
}

// One simulated rank is one process: the same answers as the MPI
// transport gives when no launcher started this process, and as OneProcess.
TEST(SimRanks, OneRankAnswersAsTheMpiTransportOnOneProcess) {
  Ranks& world = Ranks::world();
  ASSERT_EQ(world.size(), 1) << "the test program runs on one process";
  const auto calls = [](Ranks& ranks) {
    std::vector<std::string> seen;
    std::vector<std::uint64_t> v = {3, 9};
    ranks.max(v);
    ranks.sum(v);
    ranks.reduce_sum(v, 0);
    seen.push_back(std::to_string(ranks.sum(std::uint64_t(5))) + " " + std::to_string(v[0]) + " " +
                   std::to_string(v[1]));
    std::vector<unsigned char> recv;
    const auto counts = ranks.all_to_all(text_bytes("abcd"), {2}, 2, recv);
    seen.push_back(std::string(recv.begin(), recv.end()) + " " + std::to_string(counts.at(0)));
    seen.push_back(ranks.gather("g", 0).at(0));
    const std::vector<unsigned char> all = ranks.all_gather(text_bytes("xy"));
    seen.push_back(std::string(all.begin(), all.end()));
    int fine = 0, failed = 4;
    seen.push_back(std::to_string(ranks.agree(fine)) + " " + std::to_string(ranks.agree(failed)) + " " +
                   std::to_string(failed));
    seen.push_back("[" + ranks.label() + "]");
    ranks.checkpoint();
    ranks.begin_collective();
    seen.push_back(ranks.in_collective() ? "collective" : "alone");
    ranks.end_collective();
    return seen;
  };
  std::vector<std::string> simulated;
  run_ranks(1, [&](Ranks& ranks) { simulated = calls(ranks); });
  EXPECT_EQ(simulated, calls(world));
  OneProcess solo;
  EXPECT_EQ(simulated, calls(solo));
  EXPECT_EQ(simulated.back(), "alone");
}

// A rank that failed before the collective part joins the agreement from
// its error handler; the others, at their checkpoint, learn who and stop.
TEST(SimRanks, ACheckpointLearnsWhichRankFailed) {
  run_ranks(3, [](Ranks& ranks) {
    if (ranks.rank() == 2) {
      int code = 2;
      EXPECT_EQ(ranks.agree(code), 2);
      return;
    }
    try {
      ranks.begin_collective();
      ADD_FAILURE() << "rank 2 failed";
    } catch (const OtherRankFailed& e) {
      EXPECT_EQ(e.rank, 2);
      EXPECT_EQ(e.code, 2);
      EXPECT_FALSE(ranks.in_collective());
    }
  });
}

// What would hang under MPI fails here, naming why.
void expect_broken(const std::function<void(Ranks&)>& body, const std::string& why) {
  try {
    run_ranks(3, body, std::chrono::milliseconds(300));
    ADD_FAILURE() << "the ranks went on";
  } catch (const test::SimRanksBroken& e) {
    EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
  }
}

TEST(SimRanks, WhatWouldHangFailsInstead) {
  // Each rank waits for a message the next never sends: only the timeout ends it.
  expect_broken([](Ranks& ranks) {
    int x = 0;
    ranks.receive(&x, sizeof x, (ranks.rank() + 1) % 3, 1);
  }, "ms in receive from rank");
  expect_broken([](Ranks& ranks) {
    std::vector<std::uint64_t> v = {1};
    if (ranks.rank() == 1) ranks.max(v); else ranks.sum(v);
  }, "rank 1 called max while rank 0 called sum");
  expect_broken([](Ranks& ranks) {
    if (ranks.rank() != 2) ranks.barrier();
  }, "rank 2 returned while rank");
}

TEST(SimRanks, AFailingRankEndsTheOthersWaits) {
  try {
    run_ranks(4, [](Ranks& ranks) {
      if (ranks.rank() == 3) throw std::runtime_error("rank 3's own failure");
      ranks.barrier();
    });
    ADD_FAILURE() << "the failure was lost";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "rank 3's own failure");
  }
}

// Ranks failing at once in the collective part: one reports, every rank ends.
TEST(SimRanks, AbortReportsOnceAndEndsEveryRank) {
  std::atomic<int> reports{0};
  try {
    run_ranks(3, [&](Ranks& ranks) {
      if (ranks.rank() > 0) ranks.abort(3, [&] { ++reports; });
      ranks.barrier();
    });
    ADD_FAILURE() << "the ranks went on";
  } catch (const test::SimRanksAborted& e) {
    EXPECT_GT(e.rank, 0);
    EXPECT_EQ(e.code, 3);
  }
  EXPECT_EQ(reports.load(), 1);
}

}  // namespace
}  // namespace opsila
