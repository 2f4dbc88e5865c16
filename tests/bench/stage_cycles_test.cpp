// Stage cycles (kernels/lib/stage_cycles.cl): the bench's breakdown frames
// count every stage of the SPMD phase and of the megakernel where they can
// run (an x86 CPU device), and change nothing else: the same image, the
// same rays. Elsewhere the runtime says why they cannot run.
#include <gtest/gtest.h>

#include <stdexcept>

#include "bench/bench.h"
#include "bench/bench_kernels.h"
#include "bench/report.h"
#include "device/counters.h"
#include "frame/renderer.h"
#include "kernel_signature.h"
#include "prepare/prepare_banks.h"
#include "test_device.h"
#include "test_scenes.h"

namespace opsila {
namespace {

ClRuntime& runtime() { return test::shared_runtime(); }

// Skips the test, saying why, where the device cannot count the cycles.
#define SKIP_WITHOUT_STAGE_CYCLES()                                      \
  do {                                                                   \
    const std::string why = runtime().stage_cycles_unavailable();        \
    if (!why.empty()) GTEST_SKIP() << "no stage cycles here: " << why; \
  } while (0)

TEST(StageCycles, EveryStageHasAName) {
  for (int s = 0; s < OPSILA_STAGE_COUNT; ++s) EXPECT_STRNE(stage_name(s), "?") << s;
  EXPECT_STREQ(stage_name(OPSILA_STAGE_BANK_WALK), "bank_walk");
  EXPECT_STREQ(stage_name(OPSILA_STAGE_COUNT), "?");
}

TEST(StageCycles, TheMegakernelsStructFollowsItsKernel) {
  SKIP_WITHOUT_STAGE_CYCLES();
  test::expect_follow_signatures<MegaStagesArgs>(runtime(), KernelProgram::baselines_stages, {"megakernel_stages"});
}

// A machine prepared for them switches to the clocked program and back: the
// same image and rays every frame, and cycles in the stages the SPMD phase
// runs (walks, destination choice, shading, pixel sums), none in the
// megakernel's camera.
TEST(StageCycles, TheSpmdPhaseCountsItsStagesAndKeepsItsImage) {
  SKIP_WITHOUT_STAGE_CYCLES();
  const Scene s = test::mirror_glass_scene(64, 5);
  RenderSettings rs;
  rs.num_pes = 16;
  rs.count_work = false;
  rs.stage_cycles = true;
  Renderer machine(s, prepare_banks(s, rs, runtime()), rs, runtime());
  const RenderResult plain = machine.render();
  EXPECT_TRUE(machine.stage_cycles().empty());
  machine.count_stage_cycles(true);
  const RenderResult clocked = machine.render();
  EXPECT_EQ(clocked.rgb, plain.rgb);
  EXPECT_TRUE(clocked.rays.same_rays(plain.rays));
  const std::vector<std::uint64_t> cycles = machine.stage_cycles();
  ASSERT_EQ(cycles.size(), std::size_t(OPSILA_STAGE_COUNTERS));
  for (int st : {OPSILA_STAGE_BODY, OPSILA_STAGE_BANK_WALK, OPSILA_STAGE_DESTINATION, OPSILA_STAGE_SHADING,
                 OPSILA_STAGE_PIXEL_SUMS, OPSILA_STAGE_OUTPUTS, OPSILA_STAGE_STATISTICS}) {
    EXPECT_GT(cycles[std::size_t(st)], 0u) << stage_name(st);
    EXPECT_GT(cycles[std::size_t(OPSILA_STAGE_COUNT + st)], 0u) << stage_name(st) << ": clock readings";
  }
  EXPECT_EQ(cycles[OPSILA_STAGE_CAMERA], 0u);
  EXPECT_EQ(cycles[OPSILA_STAGE_COUNT + OPSILA_STAGE_CAMERA], 0u);
  EXPECT_EQ(machine.render().rgb, plain.rgb);
  machine.count_stage_cycles(false);
  EXPECT_EQ(machine.render().rgb, plain.rgb);
}

// The clock readings' cost comes out of the stages they entered: here the
// clocked frame took 1.25x the timed one, so a fifth of the 1000 counted
// cycles (200) were readings; 100 readings cost 2 cycles each. Stage A
// (500 cycles, 90 readings) keeps 320, B (500, 10) keeps 480.
TEST(StageCycles, TheReadingsCostIsTakenFromTheStagesTheyEntered) {
  std::vector<std::uint64_t> counters(OPSILA_STAGE_COUNTERS, 0);
  counters[OPSILA_STAGE_CAMERA] = 500, counters[OPSILA_STAGE_COUNT + OPSILA_STAGE_CAMERA] = 90;
  counters[OPSILA_STAGE_SHADING] = 500, counters[OPSILA_STAGE_COUNT + OPSILA_STAGE_SHADING] = 10;
  StageClockCost cost;
  const std::vector<StageTime> t = stage_times(counters, 0.8, 1.0, &cost);
  ASSERT_EQ(t.size(), 2u);
  EXPECT_NEAR(cost.cycles_per_entry, 2.0, 1e-9);
  EXPECT_NEAR(cost.share, 0.2, 1e-9);
  EXPECT_EQ(t[0].name, "camera");
  EXPECT_NEAR(t[0].raw_share, 0.5, 1e-12);
  EXPECT_NEAR(t[0].share, 320.0 / 800.0, 1e-12);
  EXPECT_NEAR(t[1].share, 480.0 / 800.0, 1e-12);
  EXPECT_NEAR(t[0].seconds + t[1].seconds, 0.8, 1e-12);
  // Counters without the readings, or no clocked time: the shares as counted.
  counters.resize(OPSILA_STAGE_COUNT);
  for (const StageTime& s : stage_times(counters, 0.8, 1.0)) EXPECT_EQ(s.share, s.raw_share);
}

TEST(StageCycles, AMachineNotPreparedForThemRefuses) {
  const Scene s = test::mirror_glass_scene(16, 2);
  Renderer machine(s, prepare_banks(s, RenderSettings(), runtime()), RenderSettings(), runtime());
  EXPECT_THROW(machine.count_stage_cycles(true), std::logic_error);
}

// The megakernel's stages: camera, walks, shading and pixel sums; it has
// no destination choice and no output records.
TEST(StageCycles, TheMegakernelCountsItsStages) {
  SKIP_WITHOUT_STAGE_CYCLES();
  const Scene s = test::mirror_glass_scene(48, 4);
  Megakernel mega(s, runtime(), 500);
  const BaselineImage before = mega.frame();
  double seconds = 0;
  const std::vector<std::uint64_t> cycles = mega.stage_cycles(seconds);
  EXPECT_GT(seconds, 0.0);
  ASSERT_EQ(cycles.size(), std::size_t(OPSILA_STAGE_COUNTERS));
  for (int st : {OPSILA_STAGE_CAMERA, OPSILA_STAGE_BANK_WALK, OPSILA_STAGE_SHADING, OPSILA_STAGE_PIXEL_SUMS}) {
    EXPECT_GT(cycles[std::size_t(st)], 0u) << stage_name(st);
    EXPECT_GT(cycles[std::size_t(OPSILA_STAGE_COUNT + st)], 0u) << stage_name(st) << ": clock readings";
  }
  // The pixel's clock starts in the camera stage, and every walk is entered
  // once a ray and left back to the stage around it.
  EXPECT_GE(cycles[OPSILA_STAGE_COUNT + OPSILA_STAGE_CAMERA], std::uint64_t(48 * 48));
  for (int st : {OPSILA_STAGE_DESTINATION, OPSILA_STAGE_OUTPUTS, OPSILA_STAGE_STATISTICS})
    EXPECT_EQ(cycles[std::size_t(st)], 0u) << stage_name(st);
  // The clocked frame wrote the same pixel sums: the next frame's image is unchanged.
  EXPECT_EQ(mega.frame().rgb, before.rgb);
}

}  // namespace
}  // namespace opsila
