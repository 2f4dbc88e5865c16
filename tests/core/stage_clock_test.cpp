// The preparation's stage clocks (host/core/stage_clock.h) and host thread
// pool (host/core/parallel.h): time goes to the innermost stage, the pilot
// frames absorb what runs inside them, progress lines appear past the mark
// (OPSILA_PROGRESS_AFTER) unless -q, and --stats has a "prepare" section.
#include <gtest/gtest.h>

#include <chrono>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/parallel.h"
#include "core/stage_clock.h"
#include "test_util.h"

namespace opsila {
namespace {

void sleep_ms(int ms) { std::this_thread::sleep_for(std::chrono::milliseconds(ms)); }

TEST(StageClock, TimeGoesToTheInnermostStage) {
  reset_prepare_times();
  const auto t0 = std::chrono::steady_clock::now();
  {
    StageClock parse(PrepareStage::parse);
    sleep_ms(20);
    {
      StageClock read(PrepareStage::read);
      sleep_ms(60);
    }
    sleep_ms(20);
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const PrepareTimes t = prepare_times();
  EXPECT_GE(t[PrepareStage::read], 0.06);
  EXPECT_GE(t[PrepareStage::parse], 0.04);
  // Nothing counted twice, nothing lost (but the clock reads themselves).
  EXPECT_LE(t[PrepareStage::read] + t[PrepareStage::parse], wall);
  EXPECT_GE(t[PrepareStage::read] + t[PrepareStage::parse], wall - 0.005);
  EXPECT_EQ(t[PrepareStage::partition], 0.0);
  EXPECT_GT(t.peak_host_bytes, 0u);
}

TEST(StageClock, PilotFramesAbsorbTheStagesInsideThem) {
  reset_prepare_times();
  const PrepareTimes start = prepare_times();
  {
    StageClock pilots(PrepareStage::pilots);
    StageClock partition(PrepareStage::partition);  // a pilot renderer's own
    sleep_ms(30);
  }
  {
    StageClock partition(PrepareStage::partition);
    sleep_ms(10);
  }
  const PrepareTimes t = stages_since(start);
  EXPECT_GE(t[PrepareStage::pilots], 0.03);
  EXPECT_GE(t[PrepareStage::partition], 0.01);
  EXPECT_LT(t[PrepareStage::partition], 0.03) << "the pilots' partition counted as partitioning";
}

TEST(ParallelFor, RunsEveryTaskOnceAndRethrowsTheLowestFailure) {
  std::vector<int> runs(1000, 0);
  parallel_for(runs.size(), [&](std::size_t i) { ++runs[i]; }, 4);
  for (int r : runs) ASSERT_EQ(r, 1);
  for (int threads : {1, 2, 4}) {
    try {
      parallel_for(
          64,
          [&](std::size_t i) {
            if (i == 40) throw std::runtime_error("task 40");
            if (i == 7) {
              sleep_ms(20);  // fails after task 40 has (most likely) failed
              throw std::runtime_error("task 7");
            }
          },
          threads);
      FAIL() << "no exception";
    } catch (const std::runtime_error& e) {
      EXPECT_EQ(std::string(e.what()), "task 7") << threads << " threads";
    }
  }
}

// A scene big enough to be split over banks, quick to prepare.
struct PrepareRun : ::testing::Test {
  test::TempDir dir;
  std::string scene;
  void SetUp() override {
    scene = dir.write("t.json",
                      "{\"image\": {\"width\": 32, \"height\": 24}, \"camera\": {\"eye\": [0, 30, 40], \"look_at\": [0, "
                      "0, 0]}, \"lights\": [{\"position\": [0, 50, 0], \"intensity\": 1}], \"objects\": [{\"type\": "
                      "\"terrain\", \"size\": [40, 40], \"quads\": 40, \"height\": 4}]}");
  }
};

TEST_F(PrepareRun, EveryStageShowsProgressPastTheMarkUnlessQuiet) {
  const test::EnvChanges now{{"OPSILA_PROGRESS_AFTER", "0"}};
  test::RunResult r = test::run_program(OPSILA_BINARY, {"render", scene, "-o", dir.file("a.png"), "--pes", "4",
                                                   "--balance", "measured"}, now);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* stage : {"reading", "parsing", "partitioning", "building bank BVHs", "uploading", "pilot frames"})
    EXPECT_NE(r.err.find(std::string("opsila: ") + stage + ": 100.0% done, "), std::string::npos)
        << stage << "\n" << r.err;
  std::istringstream lines(r.err);
  for (std::string line; std::getline(lines, line);)
    if (line.find("opsila: render: ") == std::string::npos)
      EXPECT_EQ(line.find("rays/s"), std::string::npos) << "a preparation stage casts no rays: " << line;
  r = test::run_program(OPSILA_BINARY, {"render", scene, "-o", dir.file("b.png"), "--pes", "4", "-q"}, now);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");
  // Below the mark (the default two seconds), a quick preparation says nothing.
  r = test::run_program(OPSILA_BINARY, {"render", scene, "-o", dir.file("c.png"), "--pes", "4"},
                        {{"OPSILA_PROGRESS_AFTER", std::nullopt}});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("% done"), std::string::npos) << r.err;
}

TEST_F(PrepareRun, StatsHaveAPrepareSection) {
  const test::RunResult r = test::run_opsila({"render", scene, "-o", dir.file("a.png"), "--pes", "4", "--balance",
                                        "measured", "--stats", dir.file("s.json"), "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(test::read_file(dir.file("s.json")));
  ASSERT_TRUE(j.contains("prepare")) << j.dump(2);
  const nlohmann::json& p = j["prepare"];
  for (const char* key : {"read_seconds", "parse_seconds", "partition_seconds", "bank_build_seconds",
                          "upload_seconds", "pilot_seconds"}) {
    ASSERT_TRUE(p.contains(key)) << key;
    EXPECT_GE(p[key].get<double>(), 0.0) << key;
  }
  EXPECT_GT(p["partition_seconds"].get<double>(), 0.0);
  EXPECT_GT(p["pilot_seconds"].get<double>(), 0.0);
  EXPECT_GT(p["peak_host_bytes"].get<std::uint64_t>(), 1u << 20);
}

}  // namespace
}  // namespace opsila
