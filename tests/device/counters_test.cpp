// The device's counters (kernels/lib/accum.cl count_add, read back by
// device/counters.h): 64 bits each, so that the largest frame opsila
// accepts cannot wrap them. A counter-only kernel adds, from many
// work-items at once, what the largest frame could put in one PE x PE
// traffic cell, and the host must read it back exactly.
#include <gtest/gtest.h>

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "scene/scene.h"
#include "device/counters.h"
#include "device/descriptors.h"
#include "prepare/prepare_banks.h"
#include "frame/renderer.h"
#include "opsila_shared.h"
#include "test_device.h"
#include "test_scenes.h"

namespace opsila {

const std::string& kernel_source();  // the embedded kernels (generated from kernels/*.cl)

namespace {

// Every work-item adds `amount` to counter (id % cells), through the
// function the SPMD phase flushes its statistics and traffic with.
const char* const kCountMany = R"(
__kernel void count_many(volatile __global uint *counters, int cells, uint amount) {
  count_add(counters, (long)(get_global_id(0) % (size_t)cells), amount);
}
)";

TEST(Counters, HoldTheLargestFrameAcceptedManyTimesOver) {
  // The largest frame: kMaxImageSide^2 pixels at kMaxSpp samples, 2^38
  // primary rays; if every one crossed the same PE pair at one level 64
  // times, one traffic cell would count 2^44.
  const std::uint64_t largest_frame = std::uint64_t(kMaxImageSide) * kMaxImageSide * kMaxSpp;
  ASSERT_EQ(largest_frame, std::uint64_t(1) << 38);
  ClRuntimeOptions o;
  o.read_environment = false;
  o.kernel_source = kernel_source() + kCountMany;
  o.kernel_source_origin = "counter test kernel";
  ClRuntime rt(test::test_device(), o);
  cl::Kernel k = rt.kernel("count_many");
  // A work-group flushes at most a 32-bit local count per counter: each
  // work-item adds the largest, 2^32 - 1, to one of three cells.
  const int cells = 3, items = 3 << 12, launches = 2;
  const cl_uint amount = 0xffffffffu;
  cl::Buffer counters = device_buffer(rt, counter_bytes(cells), "test counters");
  zero_buffer(rt, counters, counter_bytes(cells), "test counters");
  cl_check(k.setArg(0, counters), "setArg");
  cl_check(k.setArg(1, cells), "setArg");
  cl_check(k.setArg(2, amount), "setArg");
  for (int l = 0; l < launches; ++l)  // as rounds do, one after the other
    cl_check(rt.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(items), cl::NullRange), "count_many");
  const std::vector<std::uint64_t> got = read_counters(rt, counters, cells, "test counters");
  const std::uint64_t expected = std::uint64_t(items / cells) * launches * amount;
  ASSERT_GE(expected, largest_frame * 64);
  for (int c = 0; c < cells; ++c) EXPECT_EQ(got[std::size_t(c)], expected) << "cell " << c;
}

// The statistics' sums come from their one declaration: what each counter
// adds to (spawned, finished, neither).
TEST(Counters, SumsFollowTheCounterTable) {
  std::vector<std::uint64_t> one(OPSILA_STAT_COUNT, 0);
  for (int i = 0; i < OPSILA_STAT_COUNT; ++i) one[std::size_t(i)] = std::uint64_t(1) << i;
  const CounterSums s = counter_sums(one.data());
  EXPECT_EQ(s.spawned, one[OPSILA_STAT_SPAWN_RADIANCE] + one[OPSILA_STAT_SPAWN_SHADOW]);
  EXPECT_EQ(s.finished,
            one[OPSILA_STAT_RESOLVED] + one[OPSILA_STAT_MISS] + one[OPSILA_STAT_OCCLUDED] + one[OPSILA_STAT_LIT]);
  std::vector<std::uint64_t> two_pes = one;
  two_pes.insert(two_pes.end(), one.begin(), one.end());
  EXPECT_EQ(counter_sums(two_pes).spawned, 2 * s.spawned);
  EXPECT_EQ(std::string(stat_name(OPSILA_STAT_TRI_TESTS)), "triangle_tests");
  EXPECT_EQ(std::string(stat_name(OPSILA_STAT_LOCAL)), "local");
}

// A render that nobody reads the work counters of uses a program without
// them (OPSILA_COUNT_WORK=0): the same image, item buffer, ray counts and
// descriptors spawned and finished; the work counters and the traffic are
// left out, not merely unread.
// One frame rendered by a machine that counts the work (a) and by one that
// counts only rays (b, with its settings).
struct BothWays {
  RenderSettings plain;
  RenderResult a, b;
};
BothWays render_both_ways(const Scene& s, int pes) {
  BothWays w;
  RenderSettings counted;
  counted.num_pes = pes;
  w.plain = counted;
  w.plain.count_work = false;
  w.a = render(s, counted, test::shared_runtime());
  w.b = render(s, w.plain, test::shared_runtime());
  return w;
}

TEST(Counters, WorkCountersLeftOutChangeNothingElse) {
  const Scene s = test::mirror_glass_scene(64, 5);
  for (int pes : {1, 16, 64}) {
    const BothWays w = render_both_ways(s, pes);
    const RenderResult &a = w.a, &b = w.b;
    EXPECT_EQ(a.rgb, b.rgb) << pes;
    EXPECT_EQ(a.item_buffer, b.item_buffer) << pes;
    EXPECT_TRUE(a.rays.same_rays(b.rays)) << pes;
    EXPECT_EQ(a.rays.primary_hits, b.rays.primary_hits) << pes;
    EXPECT_EQ(a.stats.descriptors_spawned, b.stats.descriptors_spawned) << pes;
    EXPECT_EQ(a.stats.descriptors_finished, b.stats.descriptors_finished) << pes;
    std::uint64_t work_a = 0, work_b = 0;
    for (int l = 0; l < int(a.stats.counters.size()); ++l)
      for (int p = 0; p < pes; ++p)
        for (int c : {OPSILA_STAT_TRI_TESTS, OPSILA_STAT_BOX_TESTS, OPSILA_STAT_ROUTE_TESTS, OPSILA_STAT_TRACED,
                      OPSILA_STAT_FORWARD}) {
          work_a += a.stats.counters[l][p][c];
          work_b += b.stats.counters[l][p][c];
        }
    EXPECT_GT(work_a, 0u) << pes;
    EXPECT_EQ(work_b, 0u) << pes;
    EXPECT_FALSE(a.stats.traffic.empty()) << pes;
    EXPECT_TRUE(b.stats.traffic.empty()) << pes;
  }
}

// The bench's machine: prepared once with both programs, it switches
// between them frame by frame. Each frame is the frame a machine prepared
// for that program alone gives: counters and traffic included, the image
// and ray counts the same either way. A machine prepared for one program
// refuses to switch.
TEST(Counters, AMachineSwitchesBetweenCountingAndNot) {
  const Scene s = test::mirror_glass_scene(64, 5);
  for (int pes : {1, 16}) {
    const BothWays w = render_both_ways(s, pes);
    const RenderResult &a = w.a, &b = w.b;
    RenderSettings both = w.plain;
    both.switch_counting = true;
    Renderer machine(s, prepare_banks(s, both, test::shared_runtime()), both, test::shared_runtime());
    for (bool on : {false, true, false, true}) {
      machine.count_work(on);
      const RenderResult r = machine.render();
      const RenderResult& want = on ? a : b;
      EXPECT_EQ(r.rgb, want.rgb) << pes << " " << on;
      EXPECT_TRUE(r.rays.same_rays(want.rays)) << pes << " " << on;
      EXPECT_EQ(r.stats.counters, want.stats.counters) << pes << " " << on;
      EXPECT_EQ(r.stats.traffic, want.stats.traffic) << pes << " " << on;
      EXPECT_EQ(r.stats.forwards, want.stats.forwards) << pes << " " << on;
    }
  }
  Renderer fixed(s, prepare_banks(s, RenderSettings(), test::shared_runtime()), RenderSettings(),
                 test::shared_runtime());
  EXPECT_NO_THROW(fixed.count_work(true));
  EXPECT_THROW(fixed.count_work(false), std::logic_error);
}

}  // namespace
}  // namespace opsila
