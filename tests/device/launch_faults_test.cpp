// Launch faults and launch records (docs/RELIABILITY.md): a failed enqueue
// or kernel names the kernel; records past their caps are folded, not lost.
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

// ------------------------------------------------------------- launch faults

// scatter_plan with tiny buffers: a kernel to launch, and its counts to read.
struct PlanKernel {
  cl::Kernel kernel;
  cl::Buffer block_counts, key_totals, ticket, pe_total, bank_begin, bank_count, key_begin, key_count, key_base,
      group_pe, group_first, counts;
  explicit PlanKernel(ClRuntime& rt) {
    kernel = rt.kernel("scatter_plan");
    block_counts = upload(rt, std::vector<cl_int>{0, 3}, "block counts");  // one PE: 3 rays that spawn more
    key_totals = upload(rt, std::vector<cl_int>{0, 0}, "key totals");
    ticket = upload(rt, std::vector<cl_int>{0}, "plan ticket");
    pe_total = upload(rt, std::vector<cl_int>{0}, "PE totals");
    bank_begin = upload(rt, std::vector<cl_int>{0}, "bank begin");
    bank_count = upload(rt, std::vector<cl_int>{0}, "bank count");
    key_begin = upload(rt, std::vector<cl_int>{0, 0}, "key begin");
    key_count = upload(rt, std::vector<cl_int>{0, 0}, "key count");
    key_base = upload(rt, std::vector<cl_int>{0, 0}, "key base");
    group_pe = upload(rt, std::vector<cl_int>{0, 0}, "group PEs");
    group_first = upload(rt, std::vector<cl_int>{0, 0}, "group slots");
    counts = upload(rt, std::vector<cl_int>{-1, -1, -1}, "counts");
    int a = 0;
    kernel.setArg(a++, 1);  // one block
    kernel.setArg(a++, 2);  // two sort keys
    for (cl::Buffer* b : {&block_counts, &key_totals, &ticket}) kernel.setArg(a++, *b);
    kernel.setArg(a++, 1);  // PEs
    kernel.setArg(a++, 0);  // this device's PEs: [0, 1)
    kernel.setArg(a++, 1);
    kernel.setArg(a++, 2);  // slots
    kernel.setArg(a++, 2);  // cap
    kernel.setArg(a++, 1);  // work-group size
    kernel.setArg(a++, 0);  // not throttled
    for (cl::Buffer* b :
         {&pe_total, &bank_begin, &bank_count, &key_begin, &key_count, &key_base, &group_pe, &group_first, &counts})
      kernel.setArg(a++, *b);
  }
};

TEST(LaunchFaults, CleanLaunchesPassAndErrorsNameTheLastKernel) {
  ClRuntime rt(test_device(), plain_options());
  PlanKernel plan(rt);
  std::vector<LaunchRecord> records;
  Launcher launch(rt, records);
  launch.run(plan.kernel, "scatter_plan", 1, 1, 4);
  cl_int counts[3] = {0, 0, 0};
  EXPECT_NO_THROW(
      launch.check(rt.queue().enqueueReadBuffer(plan.counts, CL_TRUE, 0, sizeof counts, counts), "read"));
  EXPECT_EQ(counts[0], 1);  // 3 entries for one PE of 2 slots: one waits
  EXPECT_EQ(counts[1], 2);
  try {
    launch.check(CL_OUT_OF_RESOURCES, "clFinish");
    FAIL() << "an error code passed";
  } catch (const ClError& e) {
    EXPECT_STREQ(e.what(), "clFinish: CL_OUT_OF_RESOURCES (-5) after kernel scatter_plan (round 4)");
  }
  launch.harvest();
  ASSERT_EQ(records.size(), 1u);
  EXPECT_EQ(records[0].name, "scatter_plan");
}

// Sparse (Launcher::set_sparse): a launch goes without an event unless it is
// watched. Both are recorded in launch order, only the watched one with a
// time, and an error still names the last kernel launched.
TEST(LaunchRecords, SparseLaunchesKeepOnlyTheWatchedEvents) {
  ClRuntime rt(test_device(), plain_options());
  PlanKernel plan(rt);
  std::vector<LaunchRecord> records;
  Launcher launch(rt, records);
  launch.set_sparse(true);
  launch.run(plan.kernel, "scatter_plan", 1, 1, 2);
  launch.run(plan.kernel, "watched_plan", 1, 1, 3, nullptr, Launcher::Watch::always);
  launch.run(plan.kernel, "last_plan", 1, 1, 4);
  cl_int counts[3] = {0, 0, 0};
  EXPECT_NO_THROW(
      launch.check(rt.queue().enqueueReadBuffer(plan.counts, CL_TRUE, 0, sizeof counts, counts), "read"));
  try {
    launch.check(CL_OUT_OF_RESOURCES, "clFinish");
    FAIL() << "an error code passed";
  } catch (const ClError& e) {
    EXPECT_STREQ(e.what(), "clFinish: CL_OUT_OF_RESOURCES (-5) after kernel last_plan (round 4)");
  }
  launch.harvest();
  ASSERT_EQ(records.size(), 3u);
  EXPECT_EQ(std::tie(records[0].name, records[0].round, records[0].seconds, records[0].started),
            std::make_tuple(std::string("scatter_plan"), 2, 0.0, -1.0));
  EXPECT_EQ(records[1].name, "watched_plan");
  EXPECT_GE(records[1].started, 0) << "the watched launch has its profiled times";
  EXPECT_EQ(std::tie(records[2].name, records[2].started), std::make_tuple(std::string("last_plan"), -1.0));
}

// An endless render launches without end: past its cap the launcher folds
// each kernel's later launches into one record, their count and seconds.
TEST(LaunchRecords, PastTheCapEachKernelsLaunchesAreFolded) {
  ClRuntime rt(test_device(), plain_options());
  PlanKernel plan(rt);
  std::vector<LaunchRecord> records;
  Launcher launch(rt, records, 3);
  for (int i = 0; i < 10; ++i) launch.run(plan.kernel, i % 2 ? "odd" : "even", 1, 1, i);
  launch.check(rt.queue().finish(), "clFinish");
  launch.harvest();
  ASSERT_EQ(records.size(), 5u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(records[i].round, i);
    EXPECT_EQ(records[i].launches, 1u);
  }
  EXPECT_EQ(records[3].name, "odd");  // rounds 3, 5, 7, 9
  EXPECT_EQ(records[3].round, LaunchRecord::kFoldedRound);
  EXPECT_EQ(records[3].launches, 4u);
  EXPECT_EQ(records[4].name, "even");  // rounds 4, 6, 8
  EXPECT_EQ(records[4].round, LaunchRecord::kFoldedRound);
  EXPECT_EQ(records[4].launches, 3u);
  EXPECT_GE(records[3].seconds, 0.0);
}

// The rank exchange's per-round figures: kept one by one up to the cap,
// then added into the last row, so every sum over the rounds stays exact.
TEST(ExchangeRecords, PastTheCapRoundsAreAddedIntoTheLastRow) {
  std::vector<std::vector<std::uint64_t>> rows;
  std::vector<double> seconds;
  std::vector<std::uint64_t> total(3, 0);
  double total_seconds = 0;
  for (std::uint64_t k = 0; k < 10; ++k) {
    const std::vector<std::uint64_t> row = {k, 10 * k, 100 * k};
    keep_round(rows, row, 3);
    keep_round(seconds, 0.5 * double(k), 3);
    for (int i = 0; i < 3; ++i) total[i] += row[i];
    total_seconds += 0.5 * double(k);
  }
  ASSERT_EQ(rows.size(), 3u);
  ASSERT_EQ(seconds.size(), 3u);
  EXPECT_EQ(rows[0], (std::vector<std::uint64_t>{0, 0, 0}));
  EXPECT_EQ(rows[1], (std::vector<std::uint64_t>{1, 10, 100}));
  EXPECT_EQ(rows[2], (std::vector<std::uint64_t>{44, 440, 4400}));  // rounds 2 .. 9
  std::vector<std::uint64_t> sum(3, 0);
  for (const auto& r : rows)
    for (int i = 0; i < 3; ++i) sum[i] += r[i];
  EXPECT_EQ(sum, total);
  EXPECT_DOUBLE_EQ(seconds[0] + seconds[1] + seconds[2], total_seconds);
}

// A rank exchange run for more rounds than its cap holds that many rows,
// its four per-round tables alike.
TEST(ExchangeRecords, AnExchangeKeepsAtMostItsCapOfRounds) {
  ClRuntime rt(test_device(), plain_options());
  const int pes = 4;
  PeGroup one;
  one.begin = 0;
  one.end = pes;
  RankExchange x(rt, Ranks::world(), one, pes, 5, 3);
  cl::Buffer totals = device_buffer(rt, pes * sizeof(cl_int), "test totals");
  const std::vector<cl_int> none(pes, 0);
  cl_check(rt.queue().enqueueWriteBuffer(totals, CL_TRUE, 0, pes * sizeof(cl_int), none.data()), "write totals");
  DescriptorSet next, into;
  next.allocate(rt, 16, "test next");
  for (int round = 0; round < 10; ++round) {
    x.start(totals, next, 0);
    x.exchange();
    x.finish(next, into, 1);
  }
  EXPECT_EQ(x.sent.size(), 3u);
  EXPECT_EQ(x.received.size(), 3u);
  EXPECT_EQ(x.staging_seconds.size(), 3u);
  EXPECT_EQ(x.mpi_seconds.size(), 3u);
  x.reset();
  EXPECT_TRUE(x.sent.empty());
}

TEST(LaunchFaults, AnEnqueueThatFailsNamesTheKernel) {
  ClRuntime rt(test_device(), plain_options());
  cl::Kernel k = rt.kernel("scatter_plan");  // no arguments set
  std::vector<LaunchRecord> records;
  Launcher launch(rt, records);
  try {
    launch.run(k, "scatter_plan", 1, 1, 0);
    FAIL() << "a kernel without arguments was enqueued";
  } catch (const ClError& e) {
    EXPECT_TRUE(contains(e.what(), "clEnqueueNDRangeKernel(scatter_plan)")) << e.what();
  }
}

// A command can fail on the device after its enqueue succeeded (what a GPU
// reports as CL_OUT_OF_RESOURCES, or a watchdog reset). A user event set to
// an error stands in for the fault: the kernel waiting on it fails. Some
// drivers then answer a blocking read with CL_SUCCESS, so check() must look
// at the launches' own status.
TEST(LaunchFaults, AKernelThatFailsOnTheDeviceIsNamed) {
  ClRuntime rt(test_device(), plain_options());
  PlanKernel plan(rt);
  std::vector<LaunchRecord> records;
  Launcher launch(rt, records);
  cl_int err = CL_SUCCESS;
  cl::UserEvent fault(rt.context(), &err);
  cl_check(err, "clCreateUserEvent");
  const std::vector<cl::Event> wait = {fault};
  launch.run(plan.kernel, "scatter_plan", 1, 1, 7, &wait);
  cl_check(fault.setStatus(CL_OUT_OF_RESOURCES), "clSetUserEventStatus");
  cl_int counts[3] = {0, 0, 0};
  const cl_int read = rt.queue().enqueueReadBuffer(plan.counts, CL_TRUE, 0, sizeof counts, counts);
  if (read == CL_SUCCESS && counts[0] == 1 && counts[1] == 2)
    GTEST_SKIP() << rt.device().device_name << " ran a command whose wait list failed";
  try {
    launch.check(read, "clEnqueueReadBuffer(counts)");
    FAIL() << "a failed launch went unnoticed (the read returned " << read << ")";
  } catch (const ClError& e) {
    const std::string m = e.what();
    EXPECT_TRUE(contains(m, "scatter_plan (round 7)")) << m;
  }
}

}  // namespace
}  // namespace opsila
