// The SIMD scatter on its own: random destinations with NIL holes; every
// descriptor arrives exactly once, in source order within its destination,
// and what does not fit a bank waits in the next queue.
#include <gtest/gtest.h>

#include <cstdlib>
#include <memory>
#include <random>

#include "machine/descriptors.h"
#include "machine/renderer.h"
#include "test_device.h"

namespace opsila {
namespace {

ClRuntime& runtime() { return test::shared_runtime(); }

template <typename T>
std::vector<T> read(ClRuntime& rt, const cl::Buffer& b, std::size_t count) {
  std::vector<T> v(count);
  if (count) cl_check(rt.queue().enqueueReadBuffer(b, CL_TRUE, 0, count * sizeof(T), v.data()), "read");
  return v;
}

template <typename T>
void write(ClRuntime& rt, const cl::Buffer& b, const std::vector<T>& v) {
  if (!v.empty()) cl_check(rt.queue().enqueueWriteBuffer(b, CL_TRUE, 0, v.size() * sizeof(T), v.data()), "write");
}

// Source = queue segment only; ids.x carries the source index, org.x a
// payload derived from it so that every field is checked to move along.
void check_scatter(std::size_t length, int pes, int capacity, double hole_rate, unsigned seed) {
  ClRuntime& rt = runtime();
  std::mt19937 rng(seed);
  std::vector<cl_int> dest(length);
  std::vector<cl_float4> org(length);
  std::vector<cl_int4> ids(length);
  std::uniform_real_distribution<double> coin(0, 1);
  // Skewed destinations: PE 0 gets many more, as hot banks do in renders.
  for (std::size_t i = 0; i < length; ++i) {
    dest[i] = coin(rng) < hole_rate ? -1 : (coin(rng) < 0.3 ? 0 : static_cast<int>(rng() % pes));
    org[i] = {{float(i) * 0.5f, 1, 2, 3}};
    ids[i] = {{static_cast<int>(i), 7, -1, dest[i]}};
  }
  DescriptorSet queue, banks, next, outputs;
  queue.allocate(rt, length, "test queue");
  banks.allocate(rt, std::size_t(pes) * capacity, "test banks");
  next.allocate(rt, length, "test next queue");
  outputs.allocate(rt, 1, "test outputs");
  write(rt, queue.dest, dest);
  write(rt, queue.org, org);
  write(rt, queue.ids, ids);
  cl::Buffer processed = upload(rt, std::vector<cl_int>(pes, 0), "processed");

  std::vector<LaunchRecord> launches;
  Launcher launch(rt, launches);
  ScatterPass scatter(rt, pes);
  ScatterPass::Args a;
  a.out_len = 0;
  a.queue_len = static_cast<int>(length);
  a.n = capacity;
  a.processed = &processed;
  a.outputs = &outputs;
  a.queue = &queue;
  a.banks = &banks;
  a.next_queue = &next;
  scatter.enqueue(launch, a, 0);
  cl_check(rt.queue().finish(), "finish");

  auto counts = read<cl_int>(rt, scatter.counts, 2);
  auto bank_count = read<cl_int>(rt, scatter.bank_count, pes);
  auto bank_ids = read<cl_int4>(rt, banks.ids, std::size_t(pes) * capacity);
  auto bank_org = read<cl_float4>(rt, banks.org, std::size_t(pes) * capacity);
  auto next_ids = read<cl_int4>(rt, next.ids, counts[0]);
  auto next_dest = read<cl_int>(rt, next.dest, counts[0]);

  std::vector<std::vector<int>> expected(pes);
  std::size_t valid = 0;
  for (std::size_t i = 0; i < length; ++i)
    if (dest[i] >= 0) expected[dest[i]].push_back(static_cast<int>(i)), ++valid;

  std::vector<int> seen(length, 0);
  std::size_t placed = 0;
  for (int q = 0; q < pes; ++q) {
    ASSERT_EQ(bank_count[q], std::min<int>(capacity, expected[q].size())) << "PE " << q;
    for (int r = 0; r < bank_count[q]; ++r) {
      int src = bank_ids[std::size_t(q) * capacity + r].s[0];
      ASSERT_EQ(src, expected[q][r]) << "bank " << q << " slot " << r << ": order within a destination is stable";
      EXPECT_FLOAT_EQ(bank_org[std::size_t(q) * capacity + r].s[0], float(src) * 0.5f);
      ++seen[src];
      ++placed;
    }
  }
  // Overflow keeps destination and source order.
  std::vector<std::size_t> cursor(pes);
  for (int q = 0; q < pes; ++q) cursor[q] = std::min<std::size_t>(capacity, expected[q].size());
  for (int k = 0; k < counts[0]; ++k) {
    int q = next_dest[k];
    ASSERT_GE(q, 0);
    ASSERT_LT(q, pes);
    int src = next_ids[k].s[0];
    ASSERT_LT(cursor[q], expected[q].size());
    ASSERT_EQ(src, expected[q][cursor[q]++]);
    ++seen[src];
  }
  EXPECT_EQ(counts[1], static_cast<int>(placed));
  EXPECT_EQ(placed + counts[0], valid);
  for (std::size_t i = 0; i < length; ++i) ASSERT_EQ(seen[i], dest[i] >= 0 ? 1 : 0) << "entry " << i;
}

TEST(Scatter, EveryDescriptorArrivesOnceInOrder) {
  unsigned seed = 1;
  for (std::size_t length : {16u, 100u, 4096u, 32767u, 65536u, 1u << 20}) {
    int capacity = static_cast<int>(std::max<std::size_t>(1, length / 24));
    SCOPED_TRACE(length);
    check_scatter(length, 16, capacity, 0.2, seed++);
  }
}

TEST(Scatter, ManyPesAndCapacityOne) {
  check_scatter(5000, 256, 1, 0.1, 42);
  check_scatter(3000, 1, 1000, 0.5, 43);
}

TEST(Scatter, AllHoles) { check_scatter(1000, 16, 8, 1.0, 44); }

}  // namespace
}  // namespace opsila
