// Determinism: the same inputs give the same bytes run after run, whatever
// the bank capacity or the item buffer's tiles.
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

// ---------------------------------------------------------------- determinism

TEST(Determinism, SameInputsGiveTheSameBytesRunToRun) {
  TempDir dir;
  RunResult a = opsila(render_args(dir.file("a.pfm"), {"--item-buffer", dir.file("a.npy")}));
  RunResult b = opsila(render_args(dir.file("b.pfm"), {"--item-buffer", dir.file("b.npy")}));
  ASSERT_EQ(a.exit_code, 0) << a.err;
  ASSERT_EQ(b.exit_code, 0) << b.err;
  const std::string pa = test::read_file(dir.file("a.pfm")), pb = test::read_file(dir.file("b.pfm"));
  ASSERT_GT(pa.size(), 40u * 30u * 12u);
  EXPECT_TRUE(pa == pb) << "two runs of the same render differ";
  EXPECT_TRUE(test::read_file(dir.file("a.npy")) == test::read_file(dir.file("b.npy")));
}

TEST(Determinism, BankCapacityDownToOneGivesTheSameImage) {
  TempDir dir;
  RunResult base = opsila(render_args(dir.file("auto.pfm")));
  ASSERT_EQ(base.exit_code, 0) << base.err;
  const FloatImage reference = read_pfm(dir.file("auto.pfm"));
  for (const char* capacity : {"1", "2", "5", "64"}) {
    const std::string out = dir.file(std::string("n") + capacity + ".pfm");
    RunResult r = opsila(render_args(out, {"--bank-capacity", capacity}));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const FloatImage img = read_pfm(out);
    EXPECT_GE(test::clamped_psnr(img.rgb, reference.rgb), 60.0) << "--bank-capacity " << capacity;
  }
}

// The item buffer is launched in tiles (bounded work per launch): the tile
// size changes the launches, never the image.
TEST(Determinism, ItemBufferTilesDoNotChangeTheImage) {
  ClRuntime rt(test_device(), plain_options());
  Scene s = test::mirror_glass_scene(40, 3);  // 40x30
  RenderSettings settings;
  settings.num_pes = 4;
  RenderResult whole = render(s, settings, rt);
  settings.item_buffer_tile = 97;
  RenderResult tiled = render(s, settings, rt);
  ASSERT_EQ(whole.rgb.size(), tiled.rgb.size());
  EXPECT_EQ(0, std::memcmp(whole.rgb.data(), tiled.rgb.data(), whole.rgb.size() * sizeof(float)));
  EXPECT_EQ(whole.item_buffer, tiled.item_buffer);
  const auto item_launches = std::count_if(tiled.stats.launches.begin(), tiled.stats.launches.end(),
                                           [](const LaunchRecord& l) { return l.name == "item_buffer"; });
  // Bounded work: no launch covers more than item_buffer_tile pixels.
  EXPECT_GE(item_launches, (40 * 30 + 96) / 97);
}

// By default an item-buffer launch covers as many pixels as the SPMD launch
// has slots (P x n), at least 2^16: 192 Ki pixels take three launches with
// 16 PEs of 4096 slots, one with 64 PEs; the image is the tiles' anyway.
TEST(Determinism, ItemBufferLaunchesFollowTheSlotsInFlight) {
  ClRuntime rt(test_device(), plain_options());
  Scene s = test::mirror_glass_scene(512, 1);  // 512x384
  auto launches = [](const RenderResult& r) {
    return std::count_if(r.stats.launches.begin(), r.stats.launches.end(),
                         [](const LaunchRecord& l) { return l.name == "item_buffer"; });
  };
  RenderSettings rs;
  rs.bank_capacity = 4096;
  rs.num_pes = 16;
  const RenderResult sixteen = render(s, rs, rt);
  rs.num_pes = 64;
  const RenderResult sixty_four = render(s, rs, rt);
  EXPECT_EQ(launches(sixteen), 3);
  EXPECT_EQ(launches(sixty_four), 1);
  ASSERT_EQ(sixteen.rgb.size(), sixty_four.rgb.size());
  EXPECT_EQ(0, std::memcmp(sixteen.rgb.data(), sixty_four.rgb.data(), sixteen.rgb.size() * sizeof(float)));
  EXPECT_EQ(sixteen.item_buffer, sixty_four.item_buffer);
}

// The SPMD launch builds the next round's primary descriptors
// (RenderSettings::primary_ahead): the frame a launch of their own gives, to
// the byte and to the counter, with one build_primary launch a round fewer.
// Only a round that starts a sample pass (its item buffer pass and hit list
// first) still launches its own; hits beyond one injection (1024) and
// small banks (64 slots: many rounds) make the difference show.
TEST(Determinism, PrimaryDescriptorsBuiltAheadGiveTheSameFrame) {
  ClRuntime rt(test_device(), plain_options());
  auto count = [](const RenderResult& r, const char* name) {
    return std::count_if(r.stats.launches.begin(), r.stats.launches.end(),
                         [&](const LaunchRecord& l) { return l.name == name; });
  };
  bool fewer = false;
  for (int spp : {1, 4})
    for (int pes : {1, 16})
      for (int capacity : {0, 64}) {
        SCOPED_TRACE("spp " + std::to_string(spp) + ", " + std::to_string(pes) + " PEs, capacity " +
                     std::to_string(capacity));
        Scene s = test::mirror_glass_scene(96, 3);
        s.spp = spp;
        RenderSettings rs;
        rs.num_pes = pes;
        rs.bank_capacity = capacity;
        rs.primary_ahead = false;
        const RenderResult own = render(s, rs, rt);
        rs.primary_ahead = true;
        const RenderResult ahead = render(s, rs, rt);
        ASSERT_EQ(own.rgb.size(), ahead.rgb.size());
        EXPECT_EQ(0, std::memcmp(own.rgb.data(), ahead.rgb.data(), own.rgb.size() * sizeof(float)));
        EXPECT_EQ(own.item_buffer, ahead.item_buffer);
        EXPECT_TRUE(own.rays.same_rays(ahead.rays));
        EXPECT_EQ(own.rays.primary_hits, ahead.rays.primary_hits);
        const RenderStats &a = own.stats, &b = ahead.stats;
        EXPECT_EQ(a.counters, b.counters);
        EXPECT_EQ(a.traffic, b.traffic);
        EXPECT_EQ(std::tie(a.rounds, a.descriptors_spawned, a.descriptors_finished, a.forwards),
                  std::tie(b.rounds, b.descriptors_spawned, b.descriptors_finished, b.forwards));
        EXPECT_EQ(std::tie(a.overflow_deferrals, a.waiting_peak, a.throttled_rounds),
                  std::tie(b.overflow_deferrals, b.waiting_peak, b.throttled_rounds));
        const auto own_builds = count(own, "build_primary"), builds = count(ahead, "build_primary");
        EXPECT_EQ(a.launches.size() - b.launches.size(), std::size_t(own_builds - builds));
        EXPECT_LE(builds, count(ahead, "count_hits")) << "one build a sample pass at most";
        EXPECT_EQ(count(own, "spmd_phase"), count(ahead, "spmd_phase"));
        fewer = fewer || builds < own_builds;
      }
  EXPECT_TRUE(fewer) << "no configuration built a round's descriptors ahead";
}

// Launches without events but the long ones (RenderSettings::launch_records,
// Launcher::set_sparse; a plain render's way on a GPU, forced here by
// OPSILA_LAUNCH_EVENTS=0): the frame every launch's event gives, to the byte,
// with the same launches recorded, the item buffer's and the SPMD phase's
// timed, the others counted with no time.
TEST(Determinism, LaunchesWithoutEventsGiveTheSameFrame) {
  struct Events {  // OPSILA_LAUNCH_EVENTS for one render
    explicit Events(const char* v) { ::setenv("OPSILA_LAUNCH_EVENTS", v, 1); }
    ~Events() { ::unsetenv("OPSILA_LAUNCH_EVENTS"); }
  };
  ClRuntime rt(test_device(), plain_options());
  for (int pes : {1, 16, 64}) {
    SCOPED_TRACE(std::to_string(pes) + " PEs");
    Scene s = test::mirror_glass_scene(96, 3);
    RenderSettings rs;
    rs.num_pes = pes;
    rs.bank_capacity = 64;  // many rounds
    rs.launch_records = false;  // a plain render's way: sparse on a GPU, every launch timed on a CPU
    std::optional<RenderResult> timed_hook, sparse;
    {
      Events on("1");
      timed_hook = render(s, rs, rt);
    }
    {
      Events off("0");
      sparse = render(s, rs, rt);
    }
    rs.launch_records = true;  // as --stats asks: every launch timed, on any device
    const RenderResult timed = render(s, rs, rt);
    EXPECT_EQ(0, std::memcmp(timed.rgb.data(), timed_hook->rgb.data(), timed.rgb.size() * sizeof(float)));
    for (const LaunchRecord& l : timed_hook->stats.launches) EXPECT_GE(l.started, 0) << l.name << " (hook 1)";
    ASSERT_EQ(timed.rgb.size(), sparse->rgb.size());
    EXPECT_EQ(0, std::memcmp(timed.rgb.data(), sparse->rgb.data(), timed.rgb.size() * sizeof(float)));
    EXPECT_EQ(timed.item_buffer, sparse->item_buffer);
    EXPECT_EQ(timed.stats.counters, sparse->stats.counters);
    ASSERT_EQ(timed.stats.launches.size(), sparse->stats.launches.size());
    int untimed = 0;
    for (std::size_t i = 0; i < timed.stats.launches.size(); ++i) {
      const LaunchRecord &a = timed.stats.launches[i], &b = sparse->stats.launches[i];
      EXPECT_EQ(std::tie(a.name, a.round), std::tie(b.name, b.round));
      EXPECT_GE(a.started, 0) << a.name << ": every launch timed";
      const bool watched = b.name == "item_buffer" || b.name == "spmd_phase";
      EXPECT_EQ(b.started >= 0, watched) << b.name;
      if (!watched) EXPECT_EQ(b.seconds, 0.0) << b.name;
      untimed += watched ? 0 : 1;
    }
    EXPECT_GT(untimed, 0);
  }
  Events bad("2");
  Scene s = test::mirror_glass_scene(16, 1);
  try {
    render(s, RenderSettings(), rt);
    FAIL() << "OPSILA_LAUNCH_EVENTS=2 was taken";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "OPSILA_LAUNCH_EVENTS=2: expected 0 or 1");
  }
}

}  // namespace
}  // namespace opsila
