// Several MPI ranks render as one process (mpiexec -np R opsila render
// ...): the same image and item buffer, the same work per level and PE,
// every descriptor sent received; with or without the item buffer, with
// textures and smooth shading, where the hit order decides a pixel, and a
// scene too big for one device on four. The fixture: tests/mpi_fixture.h.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/fixed_point.h"
#include "formats/image/image_io.h"
#include "mpi_fixture.h"
#include "test_util.h"

namespace opsila {
namespace {

using namespace test_mpi;
using test::RunResult;
using test::TempDir;

// Renders `name` on one process and on R = 1..4 ranks: same PFM, same item
// buffer, the same work per level and PE, every descriptor sent received.
void expect_same_as_one_process(MpiFixture& f, const std::string& name, const std::string& size,
                                const std::string& pes) {
  const std::vector<std::string> common = {f.scene(name), "--size", size, "--pes", pes, "-q"};
  auto args = [&](const std::string& tag) {
    std::vector<std::string> a = common;
    a.insert(a.end(), {"-o", f.dir.file(tag + ".pfm"), "--item-buffer", f.dir.file(tag + ".npy"), "--stats",
                       f.dir.file(tag + ".json")});
    return a;
  };
  const RunResult single = f.one(args("one"));
  ASSERT_EQ(single.exit_code, 0) << single.err;
  const std::string pfm = test::read_file(f.dir.file("one.pfm")), npy = test::read_file(f.dir.file("one.npy"));
  const nlohmann::json base = MpiFixture::stats(f.dir.file("one.json"));
  ASSERT_FALSE(pfm.empty());
  for (int R : {1, 2, 3, 4}) {
    SCOPED_TRACE(name + " on " + std::to_string(R) + " ranks");
    const std::string tag = "r" + std::to_string(R);
    const RunResult r = f.ranks(R, args(tag));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_TRUE(test::read_file(f.dir.file(tag + ".pfm")) == pfm) << "PFM differs from one process";
    EXPECT_TRUE(test::read_file(f.dir.file(tag + ".npy")) == npy) << "item buffer differs from one process";
    const nlohmann::json s = MpiFixture::stats(f.dir.file(tag + ".json"));
    EXPECT_TRUE(s.at("balanced").get<bool>());
    EXPECT_EQ(s.at("rays"), base.at("rays"));
    EXPECT_EQ(s.at("descriptors").at("spawned"), base.at("descriptors").at("spawned"));
    // Each descriptor is traced by the same PE whatever rank holds it.
    EXPECT_EQ(s.at("levels"), base.at("levels")) << "per-level, per-PE work differs from one process";
    if (R == 1) {
      EXPECT_FALSE(s.contains("mpi"));
      continue;
    }
    const nlohmann::json& mpi = s.at("mpi");
    EXPECT_EQ(mpi.at("ranks"), R);
    EXPECT_TRUE(mpi.at("exchange_balanced").get<bool>());
    EXPECT_EQ(mpi.at("descriptors_sent"), mpi.at("descriptors_received"));
    EXPECT_GT(mpi.at("descriptors_sent").get<std::uint64_t>(), 0u);
    // What each rank received, as it counted it, is what the others sent it.
    const auto total = mpi.at("traffic_total").get<std::vector<std::vector<std::uint64_t>>>();
    ASSERT_EQ(total.size(), std::size_t(R));
    for (int d = 0; d < R; ++d) {
      std::uint64_t to_d = 0;
      for (int src = 0; src < R; ++src)
        if (src != d) to_d += total[src][d];
      EXPECT_EQ(mpi.at("per_rank").at(d).at("received"), to_d) << "rank " << d;
      EXPECT_EQ(total[d][d], 0u);
    }
    // The PE groups cover the PEs once, in order.
    int next = 0;
    for (const auto& rank : mpi.at("per_rank")) {
      EXPECT_EQ(rank.at("pes").at(0), next);
      next = rank.at("pes").at(1);
    }
    EXPECT_EQ(next, std::stoi(pes));
  }
}

TEST_F(MpiFixture, WhittedIsTheSameOnOneToFourRanks) { expect_same_as_one_process(*this, "whitted.json", "96x72", "16"); }
TEST_F(MpiFixture, CornellIsTheSameOnOneToFourRanks) { expect_same_as_one_process(*this, "cornell.json", "80x80", "4"); }
TEST_F(MpiFixture, HundredsIsTheSameOnOneToFourRanks) {
  expect_same_as_one_process(*this, "hundreds.json", "96x72", "16");
}

// Without --item-buffer the frame writes no (object, facet) output: no
// centre pass for an even sample grid, and the ranks relay only the hits.
// The image is the same, on one process or three ranks, as with it.
TEST_F(MpiFixture, WithoutTheItemBufferOutputRanksGiveTheSameImage) {
  const std::string path = scene("hundreds.json");
  auto args = [&](const std::string& tag, bool items) {
    std::vector<std::string> a{path, "--size", "48x36", "--pes", "16", "--spp", "4", "-q", "-o", dir.file(tag + ".pfm")};
    if (items) a.insert(a.end(), {"--item-buffer", dir.file(tag + ".npy")});
    return a;
  };
  ASSERT_EQ(one(args("items", true)).exit_code, 0);
  ASSERT_EQ(one(args("one", false)).exit_code, 0);
  const RunResult r = ranks(3, args("r3", false));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string pfm = test::read_file(dir.file("items.pfm"));
  EXPECT_TRUE(test::read_file(dir.file("one.pfm")) == pfm);
  EXPECT_TRUE(test::read_file(dir.file("r3.pfm")) == pfm);
}

TEST_F(MpiFixture, TexturedAndSmoothAreTheSameOnThreeRanks) {
  expect_same_as_one_process(*this, "textured.json", "64x48", "8");
  expect_same_as_one_process(*this, "smooth.json", "64x48", "8");
}

// Non-planar quads (a crease between their two fan triangles) and
// coincident facets of two objects, where the hit order's ids decide a
// pixel (kernels/hit_order.h): one process's bytes on 2, 3 and 4 ranks at
// 64 PEs, by facets and by the sampled work.
std::string tie_obj(TempDir& dir, int n) {
  std::string t;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      t += "v " + std::to_string(i * 0.1) + " " + std::to_string(0.05 * ((i * 5 + j * 3) % 7) + 0.02 * (i % 2)) +
           " " + std::to_string(j * 0.1) + "\n";
  t += "v 0.5 0.2 0.5\nv 0.5 0.9 0.5\nv 1.5 0.9 0.5\nv 1.5 0.2 0.5\n";
  const int c = (n + 1) * (n + 1);
  t += "o terrain\n";
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i + 1;
      t += "f " + std::to_string(a) + " " + std::to_string(a + n + 1) + " " + std::to_string(a + n + 2) + " " +
           std::to_string(a + 1) + "\n";
    }
  for (const char* o : {"o lower\n", "o upper\n"})
    t += std::string(o) + "f " + std::to_string(c + 1) + " " + std::to_string(c + 2) + " " + std::to_string(c + 3) +
         " " + std::to_string(c + 4) + "\n";
  return dir.write("ties.obj", t);
}

TEST_F(MpiFixture, HitOrderAcrossRanks) {
  const std::string path = tie_obj(dir, 30);
  for (const char* balance : {"facets", "work"}) {
    SCOPED_TRACE(std::string("balance ") + balance);
    const auto with = [&](const std::string& tag) {
      return std::vector<std::string>{path, "--size", "128x96", "--eye", "1.2,1.6,4.2", "--look-at", "1.5,0.2,1.5",
                                      "--pes", "64", "--balance", balance, "-q", "-o", dir.file(tag + ".pfm"),
                                      "--item-buffer", dir.file(tag + ".npy"), "--stats", dir.file(tag + ".json")};
    };
    const RunResult single = one(with("one"));
    ASSERT_EQ(single.exit_code, 0) << single.err;
    for (int R : {2, 3, 4}) {
      SCOPED_TRACE(std::to_string(R) + " ranks");
      nlohmann::json s;
      expect_ranks_as_one(R, with, s);
    }
  }
}

// A light so bright that pixel sums pass 2^63 on some ranks' devices, or
// only once the ranks' sums are added: they saturate as on one process
// (core/fixed_point.h, add_sums), never wrap to a small value.
TEST_F(MpiFixture, SaturatedSumsAreTheSameOnRanks) {
  const std::string path = scene("whitted.json");
  const auto with = [&](const std::string& tag) {
    return std::vector<std::string>{path, "--size", "64x48", "--spp", "4", "--pes", "7", "--light",
                                    "2,6,4,3e12,3e12,3e12", "--ambient", "0.5,0.5,0.5", "-q", "-o",
                                    dir.file(tag + ".pfm"), "--item-buffer", dir.file(tag + ".npy"), "--stats",
                                    dir.file(tag + ".json")};
  };
  const RunResult single = one(with("one"));
  ASSERT_EQ(single.exit_code, 0) << single.err;
  const FloatImage img = read_pfm(dir.file("one.pfm"));
  int top = 0;  // pixels at the largest value a 4-sample pixel holds
  for (float v : img.rgb) top += v == kMaxPixelValue / 4;
  ASSERT_GT(top, 0) << "no sum saturated: the test would show nothing";
  for (int R : {2, 3}) {
    SCOPED_TRACE(std::to_string(R) + " ranks");
    nlohmann::json s;
    expect_ranks_as_one(R, with, s);
  }
}

TEST_F(MpiFixture, SceneTooBigForOneDeviceRendersOnFour) {
  // hundreds at 40x30 holds ~6.2 MB of banks: over a 4.5 MB device alone,
  // ~1.6 MB of banks per device on four ranks.
  const std::vector<std::string> args = {scene("hundreds.json"), "--size", "40x30", "-q"};
  auto with = [&](const std::string& out) {
    std::vector<std::string> a = args;
    a.insert(a.end(), {"-o", dir.file(out)});
    return a;
  };
  const RunResult full = one(with("unlimited.pfm"));
  ASSERT_EQ(full.exit_code, 0) << full.err;
  env["OPSILA_DEVICE_MEMORY_LIMIT"] = "4500000";
  const RunResult alone = ranks(1, with("alone.pfm"));
  const RunResult four = ranks(4, with("four.pfm"));
  EXPECT_EQ(alone.exit_code, 3) << alone.err;
  ASSERT_EQ(alone.error_lines().size(), 1u) << alone.err;
  EXPECT_NE(alone.error_lines()[0].find("OPSILA_DEVICE_MEMORY_LIMIT"), std::string::npos) << alone.err;
  EXPECT_FALSE(test::file_exists(dir.file("alone.pfm")));
  expect_image_as(four, "four", "unlimited");
}

}  // namespace
}  // namespace opsila
