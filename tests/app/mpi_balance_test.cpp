// --balance measured and work across MPI ranks: the ranks trace the ray
// sample or run the pilot frames together, on whole scenes and on shares,
// and build one process's partition, byte for byte. The fixture:
// tests/mpi_fixture.h.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "mpi_fixture.h"
#include "test_util.h"

namespace opsila {
namespace {

using namespace test_mpi;
using test::RunResult;
using test::TempDir;

// A terrain spread over the ranks (rotated), a second one and a sphere
// (a mirror, with `mirror`) above them: the balance tests' scene.
std::string balance_terrain(TempDir& dir, bool mirror) {
  return dir.write("terrain.json", std::string(R"({"objects": [
    {"type": "sphere", "center": [0, 4, 0], "radius": 1, "subdivisions": 2)") +
                                       (mirror ? R"(, "material": "mirror")" : "") + R"(},
    {"type": "terrain", "size": [20, 20], "quads": [60, 60], "height": 3, "transform": {"rotate": [0, 30, 0]}},
    {"type": "terrain", "size": [6, 6], "quads": [9, 7], "height": 0, "center": [0, 6, 0]}],
    "materials": {"mirror": {"kd": 0.2, "kr": 0.7}}})");
}

// --balance work: the ranks trace the ray sample together, each through
// its share; --balance measured: the ranks run the pilot frames together
// and share each cluster's counts. Either way they build one process's
// partition and agree with it, byte for byte.
TEST_F(MpiFixture, BalancedPartitionsAreTheSameOnThreeRanks) {
  for (const std::string mode : {"work", "measured"}) {
    const std::vector<std::string> common = {scene("hundreds.json"), "--size", "64x48", "--pes", "16", "--balance",
                                             mode, "-q"};
    auto with = [&](const std::string& tag) {
      std::vector<std::string> a = common;
      a.insert(a.end(), {"-o", dir.file(tag + ".pfm"), "--item-buffer", dir.file(tag + ".npy"), "--stats",
                         dir.file(tag + ".json")});
      return a;
    };
    const RunResult single = one(with(mode + "-one"));
    ASSERT_EQ(single.exit_code, 0) << single.err;
    const RunResult three = ranks(3, with(mode + "-three"));
    ASSERT_EQ(three.exit_code, 0) << three.err;
    EXPECT_TRUE(test::read_file(dir.file(mode + "-three.pfm")) == test::read_file(dir.file(mode + "-one.pfm"))) << mode;
    EXPECT_TRUE(test::read_file(dir.file(mode + "-three.npy")) == test::read_file(dir.file(mode + "-one.npy"))) << mode;
    const nlohmann::json a = stats(dir.file(mode + "-one.json")), b = stats(dir.file(mode + "-three.json"));
    EXPECT_EQ(a.at("balance"), mode);
    EXPECT_EQ(a.at("levels"), b.at("levels")) << mode << ": the ranks partitioned differently from one process";
    EXPECT_TRUE(b.at("mpi").at("exchange_balanced").get<bool>()) << mode;
  }
}

// --balance measured on shares: the pilot frames run on the ranks' shares,
// each pilot's partition made collectively from them (the share kept beside
// the pilot's banks until the last), and the frame's partition is one
// process's: the same image, item buffer, work per level and PE, and banks,
// on a scene of many objects and files and on a terrain spread over the
// ranks. No rank reads the whole scene (and no note says one does).
TEST_F(MpiFixture, MeasuredBalanceOnSharesIsTheSameAsOneProcess) {
  const std::string terrain = balance_terrain(dir, false);
  const std::string many = share_scene(dir, 6, 5);
  for (const std::string& path : {many, terrain}) {
    SCOPED_TRACE(path);
    expect_balance_on_shares(path, "measured", [](std::uint64_t N, int R, const nlohmann::json& s,
                                                  const nlohmann::json& base) {
      EXPECT_EQ(s.at("pilot").at("frames"), base.at("pilot").at("frames"));
      for (const auto& rank : s.at("mpi").at("per_rank")) {
        const nlohmann::json& share = rank.at("share");
        // While the pilots ran: its share, and a pilot's banks beside it (about 2N/R, never the whole scene).
        EXPECT_GT(share.at("pilot_facets_held").get<std::uint64_t>(), share.at("facets_read").get<std::uint64_t>());
        EXPECT_LE(share.at("pilot_facets_held").get<std::uint64_t>(), 3 * N / R + 320);
      }
    });
    if (HasFatalFailure() || path != terrain) continue;
    // Over one rank's limit (OPSILA_RANK_TRIANGLE_LIMIT), under two ranks':
    // the pilots run on two ranks' shares, the same image.
    env["OPSILA_RANK_TRIANGLE_LIMIT"] = "5000";
    const RunResult two = ranks(2, balanced(path, "measured")("two"));
    env.erase("OPSILA_RANK_TRIANGLE_LIMIT");
    expect_image_as(two, "two", "one");
  }
  expect_no_whole_scene_note(many, "measured");
}

// --balance work on shares: each rank traces the ray sample through its own
// facets and the ranks join every level's nearest hits, so the sample, the
// clusters cut for being too hot and the partition are one process's: the
// same image, item buffer, work per level and PE, and banks, on a scene of
// many objects and files and on a terrain spread over the ranks (with a
// mirror: the sample follows reflected rays). No rank reads the whole scene.
TEST_F(MpiFixture, WorkBalanceOnSharesIsTheSameAsOneProcess) {
  const std::string terrain = balance_terrain(dir, true);
  const std::string many = share_scene(dir, 6, 5);
  for (const std::string& path : {many, terrain}) {
    SCOPED_TRACE(path);
    expect_balance_on_shares(path, "work", [](std::uint64_t, int, const nlohmann::json&, const nlohmann::json&) {});
  }
  expect_no_whole_scene_note(many, "work");
}

}  // namespace
}  // namespace opsila
