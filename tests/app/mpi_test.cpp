// Several MPI ranks (mpiexec -np R opsila render ...): the
// same bytes as one process, every descriptor sent is received, a scene too
// big for one device renders across four, and a failing rank ends the run
// cleanly. Skipped, with the reason, in a build without MPI or without mpirun.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "mpi_fixture.h"
#include "ply_file.h"
#include "stl_file.h"
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

// A scene of `entries` grids of small spheres (80 triangles, one object
// each), side by side, each grid one entry of "objects"; `files` adds that
// many included OBJ files (a box each), the one named `broken` (if any)
// with a face that names a missing vertex.
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

std::string share_scene(TempDir& dir, int entries, int files = 0, int broken = -1) {
  std::string objects;
  for (int e = 0; e < entries; ++e)
    objects += std::string(objects.empty() ? "" : ",\n") + R"({"type": "grid", "counts": [6, 6, 2], "min": [)" +
               std::to_string(4 * e) + R"(, 0, 0], "max": [)" + std::to_string(4 * e + 3) +
               R"(, 3, 1], "radius": 0.2, "subdivisions": 1, "seed": )" + std::to_string(e + 1) + "}";
  for (int k = 0; k < files; ++k) {
    const std::string name = "part" + std::to_string(k) + ".obj";
    dir.write(name, std::string("o part\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\n") +
                                         (k == broken ? "f 1 2 9\n" : "f 1 2 3 4\nf 1 2 5\nf 2 3 5\n"));
    objects += ",\n" R"({"type": "obj", "file": ")" + name + R"(", "transform": {"translate": [)" +
               std::to_string(2 * k) + ", -2, 0]}}";
  }
  dir.write("share.json", "{\"objects\": [\n" + objects + "\n]}\n");
  return dir.file("share.json");
}

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
  // One rank's limit (OPSILA_RANK_TRIANGLE_LIMIT): the terrain alone is over
  // it, so one process refuses the scene, naming the file, the key and the
  // figures, and leaves nothing; two ranks render it, the same image.
  env["OPSILA_RANK_TRIANGLE_LIMIT"] = "5000";
  expect_refused(one(with("alone")), {"terrain.json:", "objects[1]", "at most 5000"});
  EXPECT_FALSE(test::file_exists(dir.file("alone.pfm")));
  const RunResult two = ranks(2, with("two"));
  ASSERT_EQ(two.exit_code, 0) << two.err;
  EXPECT_TRUE(test::read_file(dir.file("two.pfm")) == test::read_file(dir.file("one.pfm")));
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
  ASSERT_EQ(three.exit_code, 0) << three.err;
  EXPECT_EQ(warning(three), warning(single)) << three.err;
  EXPECT_TRUE(test::read_file(dir.file("three.pfm")) == test::read_file(dir.file("one.pfm")));
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
  const RunResult r = ranks(4, with("four"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(test::read_file(dir.file("four.pfm")) == test::read_file(dir.file("single.pfm")));
}

// One rank's triangle limit (lowered here by OPSILA_RANK_TRIANGLE_LIMIT):
// a scene over it is refused on one process, before anything is built,
// naming the file, the key and the figures; two ranks accept twice the
// limit and render the same image as one process without the limit.
TEST_F(MpiFixture, TwoRanksAcceptTwiceOneRanksTriangles) {
  const std::string path = share_scene(dir, 4);  // 4 x 5760 triangles
  auto with = [&](const std::string& out) {
    return std::vector<std::string>{path, "--size", "48x36", "--pes", "4", "-q", "-o", dir.file(out)};
  };
  ASSERT_EQ(one(with("unlimited.pfm")).exit_code, 0);
  const std::vector<std::string> on_five = {path, "--size", "48x36", "--pes", "5", "-q", "-o", dir.file("unlimited5.pfm")};
  ASSERT_EQ(one(on_five).exit_code, 0);
  env["OPSILA_RANK_TRIANGLE_LIMIT"] = "15000";
  expect_refused(one(with("alone.pfm")), {"share.json:", "objects[2]", "at most 15000"});
  EXPECT_FALSE(test::file_exists(dir.file("alone.pfm")));
  const RunResult two = ranks(2, with("two.pfm"));
  ASSERT_EQ(two.exit_code, 0) << two.err;
  EXPECT_TRUE(test::read_file(dir.file("two.pfm")) == test::read_file(dir.file("unlimited.pfm")));
  // A generator's items are dealt as they are made: an entry may be over
  // one rank's limit (each grid here has 5760 triangles).
  env["OPSILA_RANK_TRIANGLE_LIMIT"] = "5000";
  const RunResult five = ranks(5, {path, "--size", "48x36", "--pes", "5", "-q", "-o", dir.file("five.pfm")});
  ASSERT_EQ(five.exit_code, 0) << five.err;
  EXPECT_TRUE(test::read_file(dir.file("five.pfm")) == test::read_file(dir.file("unlimited5.pfm")));
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

// A broken file among many, which one rank reads (its scene names it) and
// the others do not: one error line naming the file, every rank ended, no
// output left behind.
TEST_F(MpiFixture, ABrokenFileOnOneRankEndsEveryRank) {
  const std::string good = share_scene(dir, 2, 4);
  TempDir other;
  const std::string bad = share_scene(other, 2, 4, 3);
  const std::vector<std::string> args = {"--size", "32x24", "--pes", "6", "-o", dir.file("x.pfm")};
  std::vector<std::string> mine = {good}, theirs = {bad};
  mine.insert(mine.end(), args.begin(), args.end());
  theirs.insert(theirs.end(), args.begin(), args.end());
  const RunResult r = ranks(2, mine, {theirs});  // rank 2 reads the broken scene
  EXPECT_EQ(r.exit_code, 2) << r.err;
  const auto errors = r.error_lines();
  ASSERT_EQ(errors.size(), 1u) << r.err;
  EXPECT_EQ(errors[0].rfind("opsila: error: rank 2: ", 0), 0u) << errors[0];
  EXPECT_NE(errors[0].find("part3.obj"), std::string::npos) << errors[0];
  EXPECT_EQ(dir.entries().size(), 5u) << "an output file was left behind (the folder held the scene and 4 OBJ files)";
}

// A wavy grid of nx x nz hexagons as one OBJ file: `sections` 'o' sections
// of rows, two materials by usemtl, vt and vn on every corner, the second
// half of the rows by negative indices, one degenerate face; `bad_row` (if
// any) has a broken face at its end. Each hexagon fans from its left corner
// into two pairs of triangles mirrored across its row, so with the same
// centroid on x: polygon ties for the median cuts. Returns its path.
std::string grid_obj(TempDir& dir, const std::string& name, int nx, int nz, int sections, int bad_row = -1) {
  dir.write("grid.mtl", "newmtl red\nKd 0.8 0.2 0.2\nnewmtl green\nKd 0.2 0.8 0.3\nKs 0.3 0.3 0.3\nNs 20\n");
  std::string t = "mtllib grid.mtl\n";
  const int columns = 4 * nx + 1, rows = 2 * nz + 1, verts = columns * rows;
  for (int b = 0; b < rows; ++b)
    for (int a = 0; a < columns; ++a) {
      t += "v " + std::to_string(a * 0.0625) + " " + std::to_string(0.1 * ((a * 7 + b * 3) % 5)) + " " +
           std::to_string(b * 0.125) + "\n";
      t += "vt " + std::to_string(double(a) / (columns - 1)) + " " + std::to_string(double(b) / (rows - 1)) + "\n";
    }
  t += "vn 0 1 0\nf 1 1 2\n";
  const auto at = [&](int a, int b, bool negative) {
    const int k = b * columns + a + 1;
    const std::string n = std::to_string(negative ? k - verts - 1 : k);
    return " " + n + "/" + n + "/" + (negative ? "-1" : "1");
  };
  for (int j = 0; j < nz; ++j) {
    if (j * sections % nz < sections) t += "o rows" + std::to_string(j) + "\n";
    t += j % 2 ? "usemtl green\n" : "usemtl red\n";
    const bool neg = j >= nz / 2;
    for (int i = 0; i < nx; ++i)
      t += "f" + at(4 * i, 2 * j + 1, neg) + at(4 * i + 1, 2 * j, neg) + at(4 * i + 3, 2 * j, neg) +
           at(4 * i + 4, 2 * j + 1, neg) + at(4 * i + 3, 2 * j + 2, neg) + at(4 * i + 1, 2 * j + 2, neg) + "\n";
    if (j == bad_row) t += "f 1 2 x\n";
  }
  return dir.write(name, t);
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

// One big OBJ, bare: every rank streams the file and keeps only its window
// of the polygons; the ranks cut its sections together. The same image,
// item buffer and banks as one process; each rank read about 1/R of the
// facets.
TEST_F(MpiFixture, ABareObjReadInWindowsIsTheSameAsOneProcess) {
  expect_windows_as_one(grid_obj(dir, "grid.obj", 40, 20, 5), 4u * 40 * 20);
}

// A scene of several OBJ files, each streamed in windows: the same as one
// process on 3 and 4 ranks.
TEST_F(MpiFixture, ObjFilesReadInWindowsAreTheSameAsOneProcess) {
  std::string objects;
  for (int k = 0; k < 4; ++k) {
    grid_obj(dir, "g" + std::to_string(k) + ".obj", 8 + 5 * k, 4 + 3 * k, 1 + k);
    objects += std::string(k ? ",\n" : "") + R"({"type": "obj", "file": "g)" + std::to_string(k) +
               R"(.obj", "transform": {"translate": [)" + std::to_string(3 * k) + ", 0, " + std::to_string(k) + "]}}";
  }
  const std::string path = dir.write("files.json", "{\"objects\": [\n" + objects + "\n]}\n");
  expect_scene_as_one(path, 6, {3, 4}, [](int, const nlohmann::json&) {});
}

#ifdef OPSILA_HAVE_ASSIMP
// One big binary PLY, bare: every rank reads its vertices and streams its
// faces, keeping only its window (host/formats/ply/ply_window.cpp). The same
// image, item buffer and banks as one process (which reads it through the
// importer); each rank read about 1/R of the facets.
TEST_F(MpiFixture, ABarePlyReadInWindowsIsTheSameAsOneProcess) {
  test::PlyFile p = test::ply_grid(41, 21, 0);
  for (auto& v : p.vertices) v[2] *= 0.3;
  const std::string path = dir.file("grid.ply");
  test::write_ply(path, p);
  expect_windows_as_one(path, 2u * 40 * 20 + 4);  // the quads, a pentagon and a triangle
}

// A scene of PLY models (binary either way and ascii, with normals and uv),
// each streamed in windows: the same as one process (which reads them
// through the importer) on 2 and 3 ranks, each rank reading about 1/R of
// every file's facets.
TEST_F(MpiFixture, PlyModelsReadInWindowsAreTheSameAsOneProcess) {
  std::string objects;
  std::uint64_t all = 0;
  for (int k = 0; k < 3; ++k) {
    test::PlyFile p = test::ply_grid(12 + 6 * k, 8 + 3 * k, k == 0 ? 0 : 5);
    p.format = k == 0 ? "binary_little_endian" : k == 1 ? "binary_big_endian" : "ascii";
    if (k > 0)
      p.props = {{"float", "x"}, {"float", "y"}, {"float", "z"}, {"float", "nx"}, {"float", "ny"}, {"float", "nz"},
                 {"float", "u"}, {"float", "v"}};
    for (auto& v : p.vertices) std::swap(v[1], v[2]);  // a terrain: y up
    test::write_ply(dir.file("m" + std::to_string(k) + ".ply"), p);
    all += 2 * (p.faces.size() - 4) + 4;
    objects += std::string(k ? ",\n" : "") + R"({"type": "model", "file": "m)" + std::to_string(k) +
               R"(.ply", "transform": {"translate": [)" + std::to_string(3 * k) + ", 0, " + std::to_string(k) + "]}}";
  }
  const std::string path = dir.write("models.json", "{\"objects\": [\n" + objects + "\n]}\n");
  expect_scene_as_one(path, 6, {2, 3}, [&](int R, const nlohmann::json& s) {
    EXPECT_EQ(s.at("scene").at("triangles").get<std::uint64_t>(), all);
    EXPECT_EQ(facets_read(s, all / std::uint64_t(R) + 3 * 4, "its window of each file, give or take a face"), all);
  });
}

// A PLY whose last face names a vertex the file does not have: every rank
// reads every face, so every rank stops on it with one line naming the
// file, the element and the byte; nothing is written.
TEST_F(MpiFixture, ABrokenPlyEndsEveryRankWithOneLine) {
  test::PlyFile p = test::ply_grid(30, 20, 0);
  p.faces.push_back({0, 1, 700});
  const std::string path = dir.file("broken.ply");
  test::write_ply(path, p);
  auto with = [&](const std::string& tag) {
    return std::vector<std::string>{path, "--size", "32x24", "--pes", "4", "-o", dir.file(tag + ".pfm")};
  };
  EXPECT_EQ(one(with("one")).exit_code, 2) << "one process refuses it too";
  const std::string face = "'face' element " + std::to_string(p.faces.size()) + " of " + std::to_string(p.faces.size());
  for (int R : {3, 4}) {
    const RunResult r = ranks(R, with("r" + std::to_string(R)));
    expect_refused(r, {"broken.ply: PLY " + face + " at byte ", "vertex index 700 out of range (the file has 600 vertices)"});
    EXPECT_FALSE(test::file_exists(dir.file("r" + std::to_string(R) + ".pfm")));
  }
}

// One big binary STL, bare: every rank streams its records, keeping only
// its window (host/formats/stl/stl_window.cpp). The same image, item buffer and
// banks as one process (which reads it through the importer); each rank
// read about 1/R of the facets.
TEST_F(MpiFixture, ABareStlReadInWindowsIsTheSameAsOneProcess) {
  test::StlFile s = test::stl_grid(41, 21);
  for (auto& f : s.facets)
    for (auto& c : f.corner) c[2] *= 0.3f;
  const std::string path = dir.file("grid.stl");
  test::write_stl(path, s);
  expect_windows_as_one(path, 2u * 40 * 20 + 2);  // the grid's facets and two more (one has no area)
}

// A scene of binary STL models, each streamed in windows: the same as one
// process on 2, 3 and 4 ranks, each rank reading about 1/R of every file's
// facets.
TEST_F(MpiFixture, StlModelsReadInWindowsAreTheSameAsOneProcess) {
  std::string objects;
  std::uint64_t all = 0;
  for (int k = 0; k < 3; ++k) {
    test::StlFile s = test::stl_grid(14 + 6 * k, 8 + 3 * k);
    for (auto& f : s.facets) {
      for (auto& c : f.corner) std::swap(c[1], c[2]);  // a terrain: y up
      std::swap(f.normal[1], f.normal[2]);
    }
    test::write_stl(dir.file("m" + std::to_string(k) + ".stl"), s);
    all += s.facets.size() - 1;  // one has no area
    objects += std::string(k ? ",\n" : "") + R"({"type": "model", "file": "m)" + std::to_string(k) +
               R"(.stl", "transform": {"translate": [)" + std::to_string(3 * k) + ", 0, " + std::to_string(k) + "]}}";
  }
  const std::string path = dir.write("models.json", "{\"objects\": [\n" + objects + "\n]}\n");
  expect_scene_as_one(path, 8, {2, 3, 4}, [&](int R, const nlohmann::json& s) {
    EXPECT_EQ(s.at("scene").at("triangles").get<std::uint64_t>(), all);
    EXPECT_EQ(facets_read(s, all / std::uint64_t(R) + 3, "its window of each file, give or take a facet"), all);
  });
}

// An STL the stream cannot read as the importer does (text, Materialise
// colours) is read whole by every rank, with a note saying why, and gives
// one process's image.
TEST_F(MpiFixture, AnStlTheStreamCannotReadIsReadWholeWithANote) {
  test::StlFile s = test::stl_grid(12, 9);
  s.facets.back().attribute = 0;
  s.header = std::string("COLOR=\x90\x30\x30\xff", 10);
  const std::string path = dir.file("magics.stl");
  test::write_stl(path, s);
  auto with = [&](const std::string& tag) {
    return std::vector<std::string>{path, "--size", "32x24", "--pes", "4", "-o", dir.file(tag + ".pfm")};
  };
  ASSERT_EQ(one(with("one")).exit_code, 0);
  const RunResult r = ranks(2, with("r2"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("magics.stl: read whole by every rank (not as a stream in windows: its header names "
                       "Materialise colours (COLOR=))"),
            std::string::npos)
      << r.err;
  EXPECT_TRUE(test::read_file(dir.file("r2.pfm")) == test::read_file(dir.file("one.pfm")));
}

// A binary STL with a corner that is not a number near its end, and one cut
// short: every rank stops with one process's one line naming the file and
// the facet (the stream's, or the importer path's for the truncated file,
// which the stream leaves to it); nothing is written.
TEST_F(MpiFixture, ABrokenStlEndsEveryRankWithOneProcesssLine) {
  test::StlFile s = test::stl_grid(30, 20);
  s.facets[s.facets.size() - 5].corner[1][0] = std::numeric_limits<float>::quiet_NaN();
  test::write_stl(dir.file("nan.stl"), s);
  const std::string bytes = test::stl_bytes(test::stl_grid(30, 20));
  dir.write("cut.stl", bytes.substr(0, bytes.size() - 30));
  for (const std::string name : {"nan.stl", "cut.stl"}) {
    SCOPED_TRACE(name);
    auto with = [&](const std::string& tag) {
      return std::vector<std::string>{dir.file(name), "--size", "32x24", "--pes", "4", "-o", dir.file(tag + ".pfm")};
    };
    const RunResult single = one(with("one"));
    EXPECT_EQ(single.exit_code, 2);
    ASSERT_EQ(single.error_lines().size(), 1u) << single.err;
    const std::string line = single.error_lines()[0];
    const std::string message = line.substr(line.find(name + ":"));
    EXPECT_NE(message.find(name == "nan.stl" ? "face " + std::to_string(s.facets.size() - 5) : "(truncated file)"),
              std::string::npos)
        << message;
    for (int R : {3, 4}) {
      const RunResult r = ranks(R, with("r" + std::to_string(R)));
      expect_refused(r, {message});
      EXPECT_FALSE(test::file_exists(dir.file("r" + std::to_string(R) + ".pfm")));
    }
  }
}

// A scene of several imported model files (ASCII STL): a share keeps only
// their counts, materials and maps while the scene is planned, and reads
// each again when it is built, keeping the objects dealt to it: the same as
// one process on 2 and 3 ranks, each rank reading at most its share and one
// model.
TEST_F(MpiFixture, ModelFilesReadAgainAreTheSameAsOneProcess) {
  std::string objects;
  std::uint64_t all = 0, largest = 0;
  for (int k = 0; k < 4; ++k) {
    const int n = 6 + 4 * k;  // an n x n grid of quads, two triangles each, on a wave
    std::string t = "solid s" + std::to_string(k) + "\n";
    const auto vertex = [&](int a, int b) {
      return "vertex " + std::to_string(a * 0.125) + " " + std::to_string(0.05 * ((a * 5 + b * 3 + k) % 4)) + " " +
             std::to_string(b * 0.125) + "\n";
    };
    for (int b = 0; b < n; ++b)
      for (int a = 0; a < n; ++a)
        for (int half = 0; half < 2; ++half) {
          t += "facet normal 0 1 0\nouter loop\n";
          t += half ? vertex(a, b) + vertex(a + 1, b + 1) + vertex(a + 1, b)
                    : vertex(a, b) + vertex(a, b + 1) + vertex(a + 1, b + 1);
          t += "endloop\nendfacet\n";
        }
    t += "endsolid s" + std::to_string(k) + "\n";
    dir.write("m" + std::to_string(k) + ".stl", t);
    all += std::uint64_t(2 * n * n);
    largest = std::max<std::uint64_t>(largest, 2 * n * n);
    objects += std::string(k ? ",\n" : "") + R"({"type": "model", "file": "m)" + std::to_string(k) +
               R"(.stl", "transform": {"translate": [)" + std::to_string(2 * k) + ", 0, " + std::to_string(k) + "]}}";
  }
  const std::string path = dir.write("models.json", "{\"objects\": [\n" + objects + "\n]}\n");
  expect_scene_as_one(path, 6, {2, 3}, [&](int R, const nlohmann::json& s) {
    EXPECT_EQ(facets_read(s, all / std::uint64_t(R) + largest, "its share of the models and at most one more"), all);
  });
}
#endif

// An OBJ entry (or a PLY or binary STL model) is streamed in windows, so
// it is held to the scene's limit (R times one rank's), not one rank's:
// over one rank's limit it is refused on one process, naming the entry,
// and renders on two ranks, the same image.
TEST_F(MpiFixture, AModelFileOverOneRanksLimitRendersOnTwoRanks) {
  grid_obj(dir, "big.obj", 40, 20, 3);  // 3200 triangles
  std::vector<std::pair<std::string, std::string>> entries = {{R"("type": "obj", "file": "big.obj")", "2000"}};
#ifdef OPSILA_HAVE_ASSIMP
  test::PlyFile ply = test::ply_grid(41, 21, 0);  // 1604 triangles
  for (auto& v : ply.vertices) v[2] *= 0.2;
  test::write_ply(dir.file("big.ply"), ply);
  entries.push_back({R"("type": "model", "file": "big.ply")", "1000"});
  test::StlFile stl = test::stl_grid(41, 21);  // 1602 triangles
  for (auto& f : stl.facets)
    for (auto& c : f.corner) c[2] *= 0.2f;
  test::write_stl(dir.file("big.stl"), stl);
  entries.push_back({R"("type": "model", "file": "big.stl")", "1000"});
#endif
  for (const auto& [entry, limit] : entries) {
    SCOPED_TRACE(entry);
    env.erase("OPSILA_RANK_TRIANGLE_LIMIT");
    const std::string path = dir.write("big.json", R"({"objects": [{)" + entry + "}]}");
    auto with = [&](const std::string& out) {
      return std::vector<std::string>{path, "--size", "32x24", "--pes", "4", "-q", "-o", dir.file(out)};
    };
    ASSERT_EQ(one(with("unlimited.pfm")).exit_code, 0);
    env["OPSILA_RANK_TRIANGLE_LIMIT"] = limit;
    expect_refused(one(with("alone.pfm")), {"big.json:", "objects[0]", " " + limit});
    EXPECT_FALSE(test::file_exists(dir.file("alone.pfm")));
    const RunResult two = ranks(2, with("two.pfm"));
    ASSERT_EQ(two.exit_code, 0) << two.err;
    EXPECT_TRUE(test::read_file(dir.file("two.pfm")) == test::read_file(dir.file("unlimited.pfm")));
  }
}

// A broken face near the end of a big OBJ, in the last rank's window: every
// rank reads every line, so every rank stops on it; one error line, one
// process's FILE:LINE, nothing written.
TEST_F(MpiFixture, ABrokenObjEndsEveryRankWithOneProcesssLine) {
  const std::string path = grid_obj(dir, "broken.obj", 30, 20, 3, 18);
  auto with = [&](const std::string& tag) {
    return std::vector<std::string>{path, "--size", "32x24", "--pes", "4", "-o", dir.file(tag + ".pfm")};
  };
  const RunResult single = one(with("one"));
  ASSERT_EQ(single.error_lines().size(), 1u) << single.err;
  const std::string line = single.error_lines()[0];
  const std::string message = line.substr(line.find("broken.obj:"));
  for (int R : {3, 4}) {
    const RunResult r = ranks(R, with("r" + std::to_string(R)));
    expect_refused(r, {message});
    EXPECT_FALSE(test::file_exists(dir.file("r" + std::to_string(R) + ".pfm")));
  }
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
    ASSERT_EQ(two.exit_code, 0) << two.err;
    EXPECT_TRUE(test::read_file(dir.file("two.pfm")) == test::read_file(dir.file("one.pfm")));
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

// A bad flag is the same on every rank: one line, from the lowest, once.
TEST_F(MpiFixture, ABadFlagOnEveryRankIsOneLine) {
  for (const char* command : {"render", "bench"}) {
    std::vector<std::string> a = launch(3);
    a.insert(a.end(), {OPSILA_BINARY, command, scene("whitted.json"), "-o", dir.file("x.png"), "--pes", "0"});
    if (std::string(command) == "bench") a.erase(a.end() - 4, a.end() - 2);  // bench has no -o
    const RunResult r = test::run_program("/usr/bin/timeout", a, env);
    EXPECT_EQ(r.exit_code, 2) << command << ": " << r.err;
    const auto errors = r.error_lines();
    ASSERT_EQ(errors.size(), 1u) << command << ": " << r.err;
    EXPECT_EQ(errors[0].rfind("opsila: error: rank 0: --pes 0", 0), 0u) << errors[0];
    EXPECT_TRUE(dir.entries().empty()) << "an output file was left behind";
  }
}

TEST_F(MpiFixture, MoreRanksThanPesAreRefused) {
  const RunResult r = ranks(3, {scene("whitted.json"), "-o", dir.file("x.pfm"), "--size", "32x24", "--pes", "2"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  const auto errors = r.error_lines();
  ASSERT_EQ(errors.size(), 1u) << r.err;
  EXPECT_NE(errors[0].find("3 MPI ranks for 2 PEs"), std::string::npos) << errors[0];
  EXPECT_TRUE(dir.entries().empty()) << "an output file was left behind";
}

// `mpirun -np R opsila bench`: every rank renders its PEs, rank 0 alone
// reports: each rank's figures, the rank x rank traffic (every descriptor
// sent is received, and the per-level count from the PE traffic agrees), the
// exchange's share of the frame. Baselines and the scatter curve are left out.
TEST_F(MpiFixture, BenchOnSeveralRanksReportsEveryRank) {
  std::vector<std::string> a = launch(3);
  a.insert(a.end(), {OPSILA_BINARY, "bench", scene("whitted.json"), "--quick", "--size", "64x48", "--json",
                     dir.file("b.json"), "--csv", dir.file("csv")});
  const RunResult r = test::run_program("/usr/bin/timeout", a, env);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // One report (rank 0's), every rank's device named.
  EXPECT_EQ(test::count_of(r.out, "opsila bench: "), 1u) << r.out;
  EXPECT_NE(r.out.find("MPI ranks: 3"), std::string::npos) << r.out;
  for (int k = 0; k < 3; ++k)
    EXPECT_NE(r.err.find("device: rank " + std::to_string(k) + " of 3"), std::string::npos) << r.err;
  const nlohmann::json j = stats(dir.file("b.json"));
  EXPECT_EQ(j.at("ranks"), 3);
  const nlohmann::json& mpi = j.at("mpi");
  ASSERT_EQ(mpi.at("per_rank").size(), 3u);
  EXPECT_TRUE(mpi.at("exchange_balanced").get<bool>());
  const auto sent = mpi.at("descriptors_sent").get<std::uint64_t>();
  EXPECT_GT(sent, 0u);
  EXPECT_EQ(sent, mpi.at("descriptors_received").get<std::uint64_t>());
  std::uint64_t by_level = 0;
  for (const auto& n : mpi.at("descriptors_between_ranks_by_level")) by_level += n.get<std::uint64_t>();
  EXPECT_EQ(by_level, sent) << "the PE traffic and the ranks' own counts disagree";
  for (const char* key : {"exchange_share", "exposed_share", "mpi_share"}) {
    EXPECT_GT(mpi.at(key).get<double>(), 0.0) << key;
    EXPECT_LE(mpi.at(key).get<double>(), 1.0) << key;
  }
  EXPECT_LE(mpi.at("exposed_share").get<double>(), mpi.at("exchange_share").get<double>());
  for (const auto& rank : mpi.at("per_rank")) {
    EXPECT_GT(rank.at("device_bytes").get<std::uint64_t>(), 0u);
    EXPECT_GT(rank.at("host_peak_bytes").get<std::uint64_t>(), 0u);
  }
  EXPECT_TRUE(j.at("baselines").empty());
  EXPECT_TRUE(j.at("scatter").empty());
  EXPECT_TRUE(j.at("targets").at("opsila_vs_megakernel").is_null());
  EXPECT_TRUE(test::file_exists(dir.file("csv/ranks.csv")));
  EXPECT_EQ(test::count_of(test::read_file(dir.file("csv/ranks.csv")), "\n"), 4u);  // header + 3 ranks
  EXPECT_TRUE(test::file_exists(dir.file("csv/rank_traffic.csv")));
  EXPECT_FALSE(test::file_exists(dir.file("csv/scatter.csv")));
}

// `mpirun -np R opsila bench` reads a JSON scene in shares, as render does
// (with its default --balance, measured, as on one process): every rank's report says
// what it read (about 1/R of the facets) and held, and its preparation
// times; the banks, rays and per-rank shares are those `opsila render`
// builds on as many ranks; the whole-scene baselines are left out, saying why.
TEST_F(MpiFixture, BenchReadsSharesAndReportsEveryRank) {
  const std::string path = share_scene(dir, 6, 5);
  const std::vector<std::string> view = {path, "--size", "64x48", "--pes", "12", "-q"};
  std::vector<std::string> render_args = view;
  render_args.insert(render_args.end(), {"--balance", "measured", "-o", dir.file("r.pfm"), "--stats", dir.file("r.json")});
  const int R = 3;
  const RunResult rendered = ranks(R, render_args);
  ASSERT_EQ(rendered.exit_code, 0) << rendered.err;
  std::vector<std::string> a = launch(R);
  a.insert(a.end(), {OPSILA_BINARY, "bench"});
  a.insert(a.end(), view.begin(), view.end());
  a.insert(a.end(), {"--quick", "--json", dir.file("b.json"), "--csv", dir.file("csv")});
  const RunResult r = test::run_program("/usr/bin/timeout", a, env);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("scene read in shares"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("not measured: the baselines"), std::string::npos) << r.out;
  const nlohmann::json j = stats(dir.file("b.json")), s = stats(dir.file("r.json"));
  const std::uint64_t N = s.at("scene").at("triangles");
  EXPECT_EQ(j.at("balance"), "measured") << "the bench's default, on ranks as on one process";
  EXPECT_EQ(j.at("scene").at("triangles"), N) << "the whole scene's count, not rank 0's share";
  EXPECT_EQ(j.at("scene").at("clusters"), s.at("clusters"));
  for (const char* key : {"bank_bytes", "texture_bytes", "global_bytes", "replicated_bytes"})
    EXPECT_EQ(j.at("memory").at(key), s.at("memory").at(key)) << key;
  for (const char* kind : {"primary", "secondary", "shadow"})
    EXPECT_EQ(j.at("render").at("rays_by_kind").at(kind), s.at("rays").at(kind)) << kind;
  EXPECT_TRUE(j.at("render").at("deterministic").get<bool>());
  const nlohmann::json& per_rank = j.at("mpi").at("per_rank");
  ASSERT_EQ(per_rank.size(), std::size_t(R));
  std::uint64_t read = 0;
  for (int k = 0; k < R; ++k) {
    const nlohmann::json& share = per_rank.at(k).at("share");
    const nlohmann::json& rendered_share = s.at("mpi").at("per_rank").at(k).at("share");
    EXPECT_LE(share.at("facets_read").get<std::uint64_t>(), N / R + 80) << "rank " << k;
    EXPECT_EQ(share.at("facets_read"), rendered_share.at("facets_read")) << "rank " << k;
    EXPECT_EQ(share.at("facets_held"), rendered_share.at("facets_held")) << "rank " << k;
    // The pilots ran on the shares: the share kept beside a pilot's banks.
    EXPECT_GT(share.at("pilot_facets_held").get<std::uint64_t>(), share.at("facets_read").get<std::uint64_t>());
    for (const char* stage : {"read_seconds", "partition_seconds", "exchange_seconds", "bank_seconds"})
      EXPECT_GE(share.at(stage).get<double>(), 0.0) << stage;
    EXPECT_GT(per_rank.at(k).at("host_peak_bytes").get<std::uint64_t>(), 0u);
    EXPECT_GT(per_rank.at(k).at("render_seconds").get<double>(), 0.0);
    read += share.at("facets_read").get<std::uint64_t>();
  }
  EXPECT_EQ(read, N);
  EXPECT_TRUE(j.at("baselines").empty());
  EXPECT_NE(j.at("baselines_left_out").get<std::string>().find("whole scene"), std::string::npos);
  // ranks.csv: a header and one row per rank, with the share's figures.
  const std::string csv = test::read_file(dir.file("csv/ranks.csv"));
  EXPECT_NE(csv.find(",facets_read,facets_held,"), std::string::npos) << csv;
  EXPECT_NE(csv.find(",pilot_facets_held\n"), std::string::npos) << csv;
  EXPECT_EQ(test::count_of(csv, "\n"), std::size_t(R) + 1);
  EXPECT_EQ(test::count_of(csv, ",,"), 0u) << "a rank's share figures are missing: " << csv;
}

// More ranks than PEs: one error line, nothing written.
TEST_F(MpiFixture, BenchWithMoreRanksThanPesIsRefusedOnce) {
  std::vector<std::string> a = launch(3);
  a.insert(a.end(), {OPSILA_BINARY, "bench", scene("whitted.json"), "--quick", "--pes", "2", "--json",
                     dir.file("b.json")});
  const RunResult r = test::run_program("/usr/bin/timeout", a, env);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  const auto errors = r.error_lines();
  ASSERT_EQ(errors.size(), 1u) << r.err;
  EXPECT_NE(errors[0].find("3 MPI ranks for 2 PEs"), std::string::npos) << errors[0];
  EXPECT_TRUE(dir.entries().empty()) << "an output file was left behind";
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
  ASSERT_EQ(four.exit_code, 0) << four.err;
  EXPECT_TRUE(test::read_file(dir.file("four.pfm")) == test::read_file(dir.file("unlimited.pfm")));
}

TEST_F(MpiFixture, BadDeviceOnOneRankEndsEveryRankCleanly) {
  const std::vector<std::string> args = {scene("whitted.json"), "-o", dir.file("x.pfm"), "--size", "32x24"};
  std::vector<std::string> bad = args;
  bad.insert(bad.end(), {"--device", "no-such-device"});
  const RunResult r = ranks(2, args, {bad});  // ranks 0 and 1 fine, rank 2 bad
  EXPECT_EQ(r.exit_code, 2) << r.err;
  const auto errors = r.error_lines();
  ASSERT_EQ(errors.size(), 1u) << r.err;
  EXPECT_EQ(errors[0].rfind("opsila: error: rank 2: --device no-such-device", 0), 0u) << errors[0];
  EXPECT_TRUE(dir.entries().empty()) << "an output file was left behind";
}

// A device fault on one rank in the middle of a frame, while the others
// wait for it in the exchange: one error line naming that rank, every rank
// ended (MPI_Abort), a non-zero exit, no output, no hang.
TEST_F(MpiFixture, AFaultOnOneRankMidFrameEndsEveryRank) {
  const std::vector<std::string> args = {scene("hundreds.json"), "-o", dir.file("x.pfm"), "--size", "64x48"};
  std::vector<std::string> faulty = {"OPSILA_FAULT_ROUND=2", OPSILA_BINARY, "render"};
  faulty.insert(faulty.end(), args.begin(), args.end());
  std::vector<std::string> a = launch(2);
  a.insert(a.end(), {OPSILA_BINARY, "render"});
  a.insert(a.end(), args.begin(), args.end());
  a.insert(a.end(), {":", "-np", "1", "/usr/bin/env"});  // rank 2 runs with the fault
  a.insert(a.end(), faulty.begin(), faulty.end());
  const RunResult r = test::run_program("/usr/bin/timeout", a, env);
  EXPECT_NE(r.exit_code, 0) << r.err;
  EXPECT_NE(r.exit_code, 124) << "the ranks hung";
  const auto errors = r.error_lines();
  ASSERT_EQ(errors.size(), 1u) << r.err;
  EXPECT_EQ(errors[0].rfind("opsila: error: rank 2: OpenCL: device fault at round 2", 0), 0u) << errors[0];
  EXPECT_TRUE(dir.entries().empty()) << "an output file was left behind";
}

}  // namespace
}  // namespace opsila
