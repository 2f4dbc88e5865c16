// One harness for the exchange (kernels/scatter.cl) on its own, shared by the
// PoCL tests and the Oclgrind run: SPMD output places (only the first
// out_item_count[t] of each work-item's S places hold records; the rest hold
// stale records that must be ignored) followed by a waiting pool with NIL
// holes. Checks Vd(I'(i)) = Vs(i): every valid entry arrives once, whole
// (every lane); within its destination PE, the rays that end their tree
// (OPSILA_STREAM_KEY) first, each kind in source order, the outputs before
// the pool; banks follow the plan's rules
// (demand, cap, slots, water-filling levels, work-group alignment, and
// throttled only the rays that end their tree); what does not fit waits in
// the next pool, grouped by PE.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <random>
#include <vector>

#include "device/descriptors.h"
#include "frame/renderer.h"
#include "test_device.h"

namespace opsila::test {

struct ExchangeCase {
  int pes = 4, slots = 8, cap = 0, group_size = 4, spawn_slots = 3;
  int move_by_block = -1;  // -1: as the device chooses; 0: by entry (GPU path); 1: by block (CPU path)
  int pool_len = 10, out_groups = 2;
  double hole_rate = 0.25, hot_share = 0.3;  // hot_share: entries bound for PE 0 (a hot bank)
  unsigned seed = 1;
  // Entries are radiance rays of levels 0 to 4 (k % 5): at depth 3, those of
  // levels 2 to 4 end their tree. throttle: ScatterPass::Args::throttle.
  int depth = 3;
  bool throttle = false;
};

// A case of `pes` PEs and `slots` bank slots, over a pool of `pool_len`
// behind `out_groups` SPMD work-groups' outputs (0: the pool alone).
inline ExchangeCase exchange_case(int pes, int slots, int pool_len, int out_groups) {
  ExchangeCase c;
  c.pes = pes;
  c.slots = slots;
  c.pool_len = pool_len;
  c.out_groups = out_groups;
  return c;
}

inline HostDescriptor exchange_entry(int k, int dest) {
  HostDescriptor d{};
  d.org = {{float(k), 1.5f * k, -2.0f, 0.25f * k}};
  d.dir = {{0.5f, float(-k), 3.0f, 1.0f}};
  d.wgt = {{0.125f * k, 0.5f, 0.75f, 0.0f}};
  d.ids = {{k, OPSILA_META(OPSILA_KIND_TRACE, k % 5), k % 7 - 1, dest}};
  return d;
}

inline bool same_record(const HostDescriptor& a, const HostDescriptor& b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}

// One exchange pass (plan, then move), to its end on the device.
inline void run_exchange_pass(ClRuntime& rt, ScatterPass& scatter, const ScatterPass::Args& a) {
  std::vector<LaunchRecord> records;
  Launcher launch(rt, records);
  scatter.plan(launch, a, 0);
  scatter.move(launch, a, 0);
  launch.check(rt.queue().finish(), "clFinish(test exchange)");
  launch.harvest();
}

// Runs one exchange and checks it; returns the counts {waiting, placed, groups}.
inline std::vector<cl_int> check_exchange(ClRuntime& rt, const ExchangeCase& c) {
  std::mt19937 rng(c.seed);
  std::uniform_real_distribution<double> coin(0, 1);
  auto draw = [&] { return coin(rng) < c.hole_rate ? -1 : coin(rng) < c.hot_share ? 0 : int(rng() % c.pes); };
  const int S = c.spawn_slots, items = c.out_groups * c.group_size;
  std::vector<HostDescriptor> pool(c.pool_len), out(std::size_t(std::max(items, 1)) * S);
  std::vector<cl_int> out_count(std::max(items, 1), 0);
  // Per PE and sort key (what ends its tree, the rest), in source order.
  std::vector<std::vector<HostDescriptor>> ends(c.pes), more(c.pes);
  auto expect_entry = [&](const HostDescriptor& d) {
    const int key = desc_key(d, c.depth);
    (key % 2 == 0 ? ends : more)[key / 2].push_back(d);
  };
  for (int k = 0; k < c.pool_len; ++k) pool[k] = exchange_entry(k, draw());
  for (int t = 0; t < items; ++t) {
    out_count[t] = static_cast<int>(rng() % (S + 1));
    for (int j = 0; j < S; ++j) {
      const int k = c.pool_len + t * S + j;
      const bool used = j < out_count[t];
      out[std::size_t(t) * S + j] = exchange_entry(k, int(rng() % c.pes));  // unused places: stale records
      if (used) expect_entry(out[std::size_t(t) * S + j]);
    }
  }
  for (const HostDescriptor& d : pool)
    if (desc_dest(d) >= 0) expect_entry(d);
  std::vector<std::vector<HostDescriptor>> expected(c.pes);  // per PE, in the exchange's order
  bool any_ends = false;
  std::size_t valid = 0;
  for (int q = 0; q < c.pes; ++q) {
    expected[q] = ends[q];
    expected[q].insert(expected[q].end(), more[q].begin(), more[q].end());
    any_ends |= !ends[q].empty();
    valid += expected[q].size();
  }
  const bool ends_only = c.throttle && any_ends;

  DescriptorSet d_pool, d_out, banks, next;
  d_pool.allocate(rt, pool.size(), "test pool");
  d_out.allocate(rt, out.size(), "test outputs");
  banks.allocate(rt, std::size_t(c.slots) + std::size_t(c.pes) * c.group_size, "test banks");
  next.allocate(rt, valid + 1, "test next pool");
  d_pool.write(rt, pool, 0, c.depth);
  d_out.write(rt, out, 0, c.depth);
  OutputCounts counts_in;
  counts_in.buffer = upload(rt, out_count, "test output counts");
  ScatterPass scatter(rt, c.pes);
  if (c.move_by_block >= 0) scatter.set_move_by_block(c.move_by_block == 1);
  ScatterPass::Args a;
  a.pool_len = c.pool_len;
  a.pool = &d_pool;
  a.out_groups = c.out_groups;
  a.group_size = c.group_size;
  a.spawn_slots = S;
  a.outputs = &d_out;
  a.out_item_count = &counts_in;
  a.slots = c.slots;
  a.cap = c.cap;
  a.banks = &banks;
  a.next_pool = &next;
  a.throttle = c.throttle;
  run_exchange_pass(rt, scatter, a);

  auto read_ints = [&](const cl::Buffer& b, std::size_t n) { return from_device<cl_int>(rt, b, n); };
  const auto counts = read_ints(scatter.counts, 3);
  const auto begin = read_ints(scatter.bank_ranges.begin, c.pes), fill = read_ints(scatter.bank_ranges.count, c.pes);
  const auto group_pe = read_ints(scatter.group_pe.buffer, counts[2]),
             group_first = read_ints(scatter.group_first.buffer, counts[2]);
  const auto bank = banks.read(rt, banks.capacity), waiting = next.read(rt, counts[0]);

  // The plan: demand, cap, budget, water-filling levels within one, alignment.
  const int cap = c.cap > 0 ? c.cap : c.slots;
  long placed = 0;
  int at = 0, groups = 0;
  for (int q = 0; q < c.pes; ++q) placed += fill[q];
  EXPECT_LE(placed, c.slots);
  for (int q = 0; q < c.pes; ++q) {
    const int demand = static_cast<int>(ends_only ? ends[q].size() : expected[q].size());
    EXPECT_LE(fill[q], std::min(demand, cap)) << "PE " << q;
    if (fill[q] < std::min(demand, cap)) {
      EXPECT_EQ(placed, c.slots) << "PE " << q << " waits while slots are free";
      for (int r = 0; r < c.pes; ++r) EXPECT_LE(fill[r], fill[q] + 1) << "PE " << r << " got more than its level";
    }
    EXPECT_EQ(begin[q], at) << "PE " << q;
    EXPECT_EQ(begin[q] % c.group_size, 0);
    for (int g = 0; g < (fill[q] + c.group_size - 1) / c.group_size; ++g, ++groups) {
      EXPECT_EQ(group_pe[groups], q);
      EXPECT_EQ(group_first[groups], begin[q] + g * c.group_size);
    }
    at += (fill[q] + c.group_size - 1) / c.group_size * c.group_size;
  }
  EXPECT_EQ(counts[1], placed);
  EXPECT_EQ(counts[2], groups);
  EXPECT_EQ(std::size_t(counts[0]) + std::size_t(counts[1]), valid);

  // The moves: banks, then the next pool grouped by PE, in the exchange's order.
  int w = 0;
  for (int q = 0; q < c.pes; ++q)
    for (std::size_t r = 0; r < expected[q].size(); ++r) {
      const bool in_bank = r < std::size_t(fill[q]);
      if (!in_bank) EXPECT_LT(w, counts[0]);
      if (!in_bank && w >= counts[0]) return counts;
      const HostDescriptor& got = in_bank ? bank[begin[q] + r] : waiting[w++];
      EXPECT_TRUE(same_record(got, expected[q][r]))
          << "PE " << q << " entry " << r << ": source " << desc_pixel(expected[q][r]) << ", got "
          << desc_pixel(got) << (in_bank ? " in the bank" : " waiting");
    }
  EXPECT_EQ(w, counts[0]);
  return counts;
}

}  // namespace opsila::test
