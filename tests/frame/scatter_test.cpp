// The SIMD exchange on its own (tests/exchange_check.h): pools with NIL
// holes and a hot PE, SPMD outputs, banks that follow demand, caps and
// overflow; every descriptor arrives once, whole, in the exchange's order
// within its destination (what ends its ray tree first, the outputs before
// the pool), and what does not fit waits in the next pool.
#include <gtest/gtest.h>

#include "exchange_check.h"
#include "test_device.h"

namespace opsila {
namespace {

ClRuntime& runtime() { return test::shared_runtime(); }

TEST(Scatter, EveryDescriptorArrivesOnceInOrder) {
  unsigned seed = 1;
  for (int length : {16, 100, 4096, 32767, 65536, 1 << 20}) {
    SCOPED_TRACE(length);
    test::ExchangeCase c = test::exchange_case(16, std::max(1, length / 2), length, 0);
    c.group_size = 64;
    c.hole_rate = 0.2;
    c.seed = seed++;
    c.move_by_block = length % 2;  // both moves, on any device
    test::check_exchange(runtime(), c);
  }
}

// A pool of 3000 behind 40 SPMD work-groups' outputs, over 16 PEs.
test::ExchangeCase outputs_and_pool(int by_block, int slots) {
  test::ExchangeCase c = test::exchange_case(16, slots, 3000, 40);
  c.group_size = 64;
  c.spawn_slots = 4;
  c.move_by_block = by_block;
  return c;
}

TEST(Scatter, SpmdOutputsAndPoolTogether) {
  for (int by_block : {0, 1}) {  // the GPU and the CPU move, on whatever device runs the tests
    SCOPED_TRACE(by_block ? "move by block" : "move by entry");
    const test::ExchangeCase c = outputs_and_pool(by_block, 4096);
    const auto counts = test::check_exchange(runtime(), c);
    EXPECT_GT(counts[0], 0) << "the case should overflow";
  }
}

// More wait than the frame planned for: the banks take only the rays that
// end their tree, and when none waits the round is not held back.
TEST(Scatter, ThrottledBanksTakeOnlyRaysThatEndTheirTree) {
  for (int by_block : {0, 1}) {
    SCOPED_TRACE(by_block ? "move by block" : "move by entry");
    // More slots than the ~4400 rays that end their tree, fewer than the ~7400 in all.
    test::ExchangeCase c = outputs_and_pool(by_block, 6000);
    c.throttle = true;
    const auto held = test::check_exchange(runtime(), c);
    EXPECT_GT(held[1], 0);
    EXPECT_LT(held[1], 6000) << "throttled, the radiance rays of levels 0 and 1 should wait";
    c.depth = 31;  // no ray ends its tree
    const auto full = test::check_exchange(runtime(), c);
    EXPECT_EQ(full[1], 6000);
  }
}

TEST(Scatter, BanksFollowDemand) {
  // A hot PE takes the slots the others do not need: the round is full.
  test::ExchangeCase c = test::exchange_case(8, 2000, 5000, 0);
  c.hot_share = 0.8;
  c.hole_rate = 0.0;
  const auto counts = test::check_exchange(runtime(), c);
  EXPECT_EQ(counts[1], 2000);
}

TEST(Scatter, CapPerPeAndManyPes) {
  test::ExchangeCase c = test::exchange_case(256, 4000, 5000, 3);
  c.group_size = 16;
  c.cap = 16;  // one work-group per PE
  test::check_exchange(runtime(), c);
  // One PE, one slot, no cap.
  c = test::exchange_case(1, 1, 5000, 3);
  c.group_size = 1;
  c.hole_rate = 0.5;
  test::check_exchange(runtime(), c);
}

TEST(Scatter, AllHoles) {
  test::ExchangeCase c = test::exchange_case(4, 8, 1000, 0);
  c.hole_rate = 1.0;
  const auto counts = test::check_exchange(runtime(), c);
  EXPECT_EQ(counts[1], 0);
  EXPECT_EQ(counts[2], 0);
}

}  // namespace
}  // namespace opsila
