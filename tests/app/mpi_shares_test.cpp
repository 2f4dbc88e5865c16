// Scenes read in shares under mpiexec: each rank reads only its share of a
// JSON scene (whole objects, its window of a terrain) and the ranks
// partition it together into one process's banks: the same image, item
// buffer and banks; one rank's triangle limit times R; texture maps
// decoded only where used. The fixture: tests/mpi_fixture.h.
#include <gtest/gtest.h>

#include <sstream>
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

// Under mpirun each rank reads only its share of a JSON scene and the ranks
// partition it together into the banks one process builds: the same image,
// item buffer and work per PE, the same banks (memory, clusters), and each
// rank read about 1/R of the facets and holds its group's banks only.
TEST_F(MpiFixture, ScenesReadInSharesAreTheSameAsOneProcess) {
  const std::string path = share_scene(dir, 6, 5);
  auto with = [&](const std::string& tag) {
    return std::vector<std::string>{path,    "--size", "64x48", "--pes", "12", "-q", "-o", dir.file(tag + ".pfm"),
                                    "--item-buffer", dir.file(tag + ".npy"), "--stats", dir.file(tag + ".json")};
  };
  const RunResult single = one(with("one"));
  ASSERT_EQ(single.exit_code, 0) << single.err;
  const nlohmann::json base = stats(dir.file("one.json"));
  const std::uint64_t N = base.at("scene").at("triangles");
  ASSERT_EQ(N, 6u * 72 * 80 + 5 * 4);
  for (int R : {2, 3, 4}) {
    SCOPED_TRACE(std::to_string(R) + " ranks");
    nlohmann::json s;
    expect_ranks_as_one(R, with, s);
    if (HasFatalFailure()) return;
    std::uint64_t read = 0, held = 0;
    for (const auto& rank : s.at("mpi").at("per_rank")) {
      const nlohmann::json& share = rank.at("share");
      const std::uint64_t pes = rank.at("pes").at(1).get<std::uint64_t>() - rank.at("pes").at(0).get<std::uint64_t>();
      // Whole objects are dealt: a share is 1/R of the facets, give or take one object.
      EXPECT_LE(share.at("facets_read").get<std::uint64_t>(), N / R + 80);
      // Banks of equal facet counts, within a cluster's size or so.
      EXPECT_LE(share.at("facets_held").get<std::uint64_t>(), N * pes / 12 + N / 12);
      for (const char* stage : {"read_seconds", "partition_seconds", "exchange_seconds", "bank_seconds"})
        EXPECT_GE(share.at(stage).get<double>(), 0.0) << stage;
      read += share.at("facets_read").get<std::uint64_t>();
      held += share.at("facets_held").get<std::uint64_t>();
    }
    EXPECT_EQ(read, N);
    EXPECT_EQ(held, N);
  }
}

// A terrain is made in windows: each rank makes only the triangles of its
// slice of the scene (so reads N / R of them, give or take the sphere), the
// ranks cut it into clusters together (collective median cuts), and the
// image, item buffer, clusters and banks are those of one process.
TEST_F(MpiFixture, ATerrainSpreadOverRanksIsTheSameAsOneProcess) {
  const std::string path = dir.write("terrain.json", R"({"objects": [
    {"type": "sphere", "center": [0, 4, 0], "radius": 1, "subdivisions": 2},
    {"type": "terrain", "size": [20, 20], "quads": [60, 60], "height": 3, "transform": {"rotate": [0, 30, 0]}},
    {"type": "terrain", "size": [6, 6], "quads": [9, 7], "height": 0, "center": [0, 6, 0]}]})");
  auto with = [&](const std::string& tag) {
    return std::vector<std::string>{path, "--size", "48x36", "--pes", "6", "-q", "-o", dir.file(tag + ".pfm"),
                                    "--item-buffer", dir.file(tag + ".npy"), "--stats", dir.file(tag + ".json")};
  };
  ASSERT_EQ(one(with("one")).exit_code, 0);
  const nlohmann::json base = stats(dir.file("one.json"));
  const std::uint64_t N = base.at("scene").at("triangles");
  ASSERT_EQ(N, 320u + 7200 + 126);
  for (int R : {3, 4}) {
    SCOPED_TRACE(std::to_string(R) + " ranks");
    nlohmann::json s;
    expect_ranks_as_one(R, with, s);
    if (HasFatalFailure()) return;
    EXPECT_EQ(facets_read(s, N / R + 320, "a slice of the terrain, and at most the sphere more"), N);
  }
  // One rank's limit: the terrain alone is over it, so one process refuses
  // the scene, naming the file, the key and the figures; two ranks render it.
  expect_two_ranks_past_the_limit("5000", with, {"terrain.json:", "objects[1]", "at most 5000"}, "one");
}

// A terrain's zero-area triangles (a patch too small for float at its
// place) are dropped by the ranks whose windows hold them: the warning
// counts every rank's, as one process's does, and the image is the same.
TEST_F(MpiFixture, ATerrainsDroppedTrianglesAreCountedOverEveryRank) {
  const std::string path = dir.write("drop.json", R"({"objects": [
    {"type": "sphere", "center": [1000, 0.5, 1000], "radius": 0.3, "subdivisions": 1},
    {"type": "terrain", "center": [1000, 0, 1000], "size": [0.0004, 0.0004], "quads": [16, 30], "height": 0.2}]})");
  auto with = [&](const std::string& tag) {
    return std::vector<std::string>{path, "--size", "32x24", "--pes", "4", "-o", dir.file(tag + ".pfm")};
  };
  const auto warning = [](const RunResult& r) {
    const std::size_t at = r.err.find("zero-area");
    return at == std::string::npos ? std::string() : r.err.substr(r.err.rfind("objects[1]", at), 40);
  };
  const RunResult single = one(with("one"));
  ASSERT_EQ(single.exit_code, 0) << single.err;
  ASSERT_NE(warning(single), "") << single.err;
  const RunResult three = ranks(3, with("three"));
  expect_image_as(three, "three", "one");
  EXPECT_EQ(warning(three), warning(single)) << three.err;
}

// The whole scene's bounds (so epsilon) come from every facet read, the
// first one's included: a one-facet scene on four ranks, three of which
// read and hold nothing, is the same as on one process.
TEST_F(MpiFixture, AOneFacetSceneRendersOnFourRanks) {
  const std::string path =
      dir.write("one.json", R"({"objects": [{"type": "polygon", "vertices": [[0,0,0],[1,0,0],[0,1,0]]}]})");
  auto with = [&](const std::string& tag) {
    return std::vector<std::string>{path, "--size", "32x24", "--pes", "4", "-q", "-o", dir.file(tag + ".pfm")};
  };
  ASSERT_EQ(one(with("single")).exit_code, 0);
  expect_image_as(ranks(4, with("four")), "four", "single");
}

// One rank's triangle limit (lowered here by OPSILA_RANK_TRIANGLE_LIMIT):
// a scene over it is refused on one process, before anything is built,
// naming the file, the key and the figures; two ranks accept twice the
// limit and render the same image as one process without the limit.
TEST_F(MpiFixture, TwoRanksAcceptTwiceOneRanksTriangles) {
  const std::string path = share_scene(dir, 4);  // 4 x 5760 triangles
  auto with = [&](const std::string& tag) {
    return std::vector<std::string>{path, "--size", "48x36", "--pes", "4", "-q", "-o", dir.file(tag + ".pfm")};
  };
  ASSERT_EQ(one(with("unlimited")).exit_code, 0);
  const std::vector<std::string> on_five = {path, "--size", "48x36", "--pes", "5", "-q", "-o", dir.file("unlimited5.pfm")};
  ASSERT_EQ(one(on_five).exit_code, 0);
  expect_two_ranks_past_the_limit("15000", with, {"share.json:", "objects[2]", "at most 15000"}, "unlimited");
  // A generator's items are dealt as they are made: an entry may be over
  // one rank's limit (each grid here has 5760 triangles).
  env["OPSILA_RANK_TRIANGLE_LIMIT"] = "5000";
  expect_image_as(ranks(5, {path, "--size", "48x36", "--pes", "5", "-q", "-o", dir.file("five.pfm")}), "five",
                  "unlimited5");
  // Any other entry is built whole by every rank: it must fit one rank's limit.
  const std::string ball =
      dir.write("ball.json", R"({"objects": [{"type": "sphere", "center": [0,0,0], "radius": 1, "subdivisions": 4}]})");
  expect_refused(ranks(4, {ball, "--size", "32x24", "--pes", "4", "-q", "-o", dir.file("entry.pfm")}),
                 {"ball.json:1: objects[0]", "one entry of objects may have at most 5000"});
  EXPECT_FALSE(test::file_exists(dir.file("entry.pfm")));
}

// An uncompressed 24-bit TGA of w x h texels of one colour.
std::string tga(int w, int h, unsigned char r, unsigned char g, unsigned char b) {
  std::string t(18, '\0');
  t[2] = 2, t[12] = char(w & 255), t[13] = char(w >> 8), t[14] = char(h & 255), t[15] = char(h >> 8), t[16] = 24;
  for (int i = 0; i < w * h; ++i) t += {char(b), char(g), char(r)};
  return t;
}

// A scene of `n` textured squares side by side, each an OBJ file whose
// material maps an image of its own (of a size of its own); then one whose
// map is not an image and one whose map is missing.
std::string textured_scene(TempDir& dir, int n) {
  std::string objects;
  for (int k = 0; k < n + 2; ++k) {
    const std::string name = "sq" + std::to_string(k);
    const std::string image = k < n ? name + ".tga" : k == n ? "broken.tga" : "missing.png";
    if (k < n) dir.write(image, tga(8 + 4 * k, 8, (unsigned char)(40 * k), 200, (unsigned char)(255 - 40 * k)));
    if (k == n) dir.write(image, "not an image");
    dir.write(name + ".mtl", "newmtl m\nKd 1 1 1\nKa 0.2 0.2 0.2\nmap_Kd " + image + "\n");
    dir.write(name + ".obj", "mtllib " + name + ".mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                             "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl m\nf 1/1 2/2 3/3 4/4\n");
    objects += std::string(k ? ",\n" : "") + R"({"type": "obj", "file": ")" + name + R"(.obj", "transform": {"translate": [)" +
               std::to_string(1.5 * k) + ", 0, 0]}}";
  }
  return dir.write("maps.json", R"({"camera": {"eye": [5, 0.5, 9], "look_at": [5, 0.5, 0]}, "objects": [
)" + objects + "]}\n");
}

// Textures are decoded only by the ranks whose banks use them: each rank
// holds no more texel bytes than its banks copy (and the ranks together
// hold each map about once, not R times); every image is checked once
// over the ranks, so the warnings for an image that is not one, and for a
// missing one, are those of one process, as are the image and item buffer.
TEST_F(MpiFixture, TexturesAreDecodedOnlyWhereUsed) {
  const int n = 4;
  const std::string path = textured_scene(dir, n);
  auto with = [&](const std::string& tag) {
    return std::vector<std::string>{path, "--size", "64x32", "--pes", "6", "-o", dir.file(tag + ".pfm"),
                                    "--item-buffer", dir.file(tag + ".npy"), "--stats", dir.file(tag + ".json")};
  };
  const auto warnings = [](const RunResult& r) {
    std::vector<std::string> lines;
    std::istringstream s(r.err);
    for (std::string line; std::getline(s, line);)
      if (line.find("warning:") != std::string::npos) lines.push_back(line);
    return lines;
  };
  const RunResult single = one(with("one"));
  ASSERT_EQ(single.exit_code, 0) << single.err;
  ASSERT_EQ(warnings(single).size(), 2u) << single.err;
  EXPECT_NE(warnings(single)[0].find("broken.tga' ignored"), std::string::npos) << single.err;
  EXPECT_NE(warnings(single)[1].find("missing.png' ignored"), std::string::npos) << single.err;
  std::uint64_t all_maps = 0;
  for (int k = 0; k < n; ++k) all_maps += std::uint64_t(8 + 4 * k) * 8 * 4;
  for (int R : {2, 3, 6}) {
    SCOPED_TRACE(std::to_string(R) + " ranks");
    nlohmann::json s;
    expect_ranks_as_one(R, with, s);
    if (HasFatalFailure()) return;
    const RunResult again = ranks(R, with("again"));
    EXPECT_EQ(warnings(again), warnings(single)) << again.err;
    const auto bank_textures = s.at("memory").at("texture_bytes").get<std::vector<std::uint64_t>>();
    std::uint64_t held = 0;
    for (const auto& rank : s.at("mpi").at("per_rank")) {
      const std::uint64_t mine = rank.at("share").at("texture_bytes");
      std::uint64_t copied = 0;  // what its banks copy of the maps (texels and a record each)
      for (int p = rank.at("pes").at(0); p < rank.at("pes").at(1).get<int>(); ++p) copied += bank_textures[p];
      EXPECT_LE(mine, copied) << "rank " << rank.at("rank") << " decoded a map its banks do not use";
      held += mine;
    }
    EXPECT_GE(held, all_maps) << "a map used by some bank was decoded by no rank";
    EXPECT_LT(held, std::uint64_t(R) * all_maps) << "every rank decoded every map";
  }
  // A bare OBJ file is streamed by every rank, each keeping its window of
  // the facets: its maps are checked once over the ranks and decoded where
  // used, with one process's warning and image.
  for (const char* bare : {"sq2.obj", "sq4.obj"}) {
    const std::vector<std::string> args = {dir.file(bare), "--size", "32x32", "--pes", "4", "-o"};
    std::vector<std::string> a1 = args, a2 = args;
    a1.push_back(dir.file("bare1.pfm"));
    a2.push_back(dir.file("bare2.pfm"));
    const RunResult r1 = one(a1), r2 = ranks(2, a2);
    ASSERT_EQ(r1.exit_code, 0) << r1.err;
    ASSERT_EQ(r2.exit_code, 0) << r2.err;
    EXPECT_TRUE(test::read_file(dir.file("bare2.pfm")) == test::read_file(dir.file("bare1.pfm"))) << bare;
    EXPECT_EQ(warnings(r2), warnings(r1)) << bare << ": " << r2.err;
  }
}

}  // namespace
}  // namespace opsila
