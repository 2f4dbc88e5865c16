// The scatter on its own, small enough to run under Oclgrind
// (.ci/oclgrind.sh): output slots and the waiting queue, with overflow.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <map>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "prepare/prepare_banks.h"
#include "device/descriptors.h"
#include "partition/pe_group.h"
#include "frame/rank_exchange.h"
#include "mpi/ranks.h"
#include "formats/image/image_io.h"
#include "opsila_shared.h"
#include "frame/renderer.h"
#include "exchange_check.h"
#include "test_scenes.h"
#include "test_device.h"
#include "test_util.h"
#include "fault_checks.h"

namespace opsila {

const std::string& kernel_source();  // the embedded kernels (generated from kernels/*.cl)

namespace {

// -------------------------------------------- the scatter on its own (small)

// The exchange on its own, small enough for Oclgrind: a pool with holes,
// SPMD output places (used and stale), banks that overflow
// (tests/exchange_check.h checks every lane of every record).
void small_scatter(int pes, int slots, int S, int pool_len, unsigned seed) {
  test::ExchangeCase c = test::exchange_case(pes, slots, pool_len, 2);
  c.spawn_slots = S;
  c.group_size = 2;
  c.seed = seed;
  for (int by_block : {0, 1})  // both moves under Oclgrind, throttled or not
    for (bool throttle : {false, true}) {
      // A runtime each: with four exchanges on one runtime, Oclgrind 21.10's
      // uninitialized-value check reported reads of values that the
      // exchange's own kernels had just written (the scan's totals, the
      // count's ranks), in buffers made after an earlier exchange's were
      // released. The values read were the ones written, on PoCL and under
      // Oclgrind alike (printed from the kernels), and zero-filling one such
      // buffer only moved the report to the next.
      ClRuntime rt(test_device(), plain_options());
      c.move_by_block = by_block;
      c.throttle = throttle;
      test::check_exchange(rt, c);
    }
}

TEST(SmallScatter, OutputSlotsAndQueueWithOverflow) {
  small_scatter(3, 2, 3, 7, 11);    // most entries wait
  small_scatter(4, 24, 4, 5, 12);   // most entries fit
  small_scatter(1, 1, 2, 3, 13);    // one PE, one slot
}

}  // namespace
}  // namespace opsila
