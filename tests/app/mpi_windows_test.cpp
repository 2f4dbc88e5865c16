// Model files streamed in windows under mpiexec: each rank keeps only its
// window of a bare OBJ, PLY or STL (or of each in a scene), the ranks cut
// them together, and the image, item buffer and banks are one process's;
// files the stream cannot read, files over one rank's limit, and broken
// files (one process's one error line). The fixture: tests/mpi_fixture.h.
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <string>
#include <utility>
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
// A bare PLY of strips: each rank streams its window of the strips'
// triangles; the image, item buffer and banks of one process, which reads
// it with the same stream.
TEST_F(MpiFixture, PlyStripsReadInWindowsAreTheSameAsOneProcess) {
  test::PlyFile p = test::ply_grid(21, 11, 0);
  p.faces.clear();
  p.face_element = false;
  std::vector<std::vector<long long>> faces;
  p.strips = test::grid_strips(21, 11, faces);
  const std::string path = dir.file("strips.ply");
  test::write_ply(path, p);
  expect_windows_as_one(path, faces.size());
}

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
    auto with = [&](const std::string& tag) {
      return std::vector<std::string>{path, "--size", "32x24", "--pes", "4", "-q", "-o", dir.file(tag + ".pfm")};
    };
    ASSERT_EQ(one(with("unlimited")).exit_code, 0);
    expect_two_ranks_past_the_limit(limit, with, {"big.json:", "objects[0]", " " + limit}, "unlimited");
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

}  // namespace
}  // namespace opsila
