// A binary STL streamed by R ranks, each keeping its window (host/input/
// stl_window.cpp): whatever the block size (down to one record) and the
// number of ranks, the windows together are the importer path's triangles
// (model_import.cpp), in order, with the same ids, material and normals,
// bit for bit; every rank has the same figures and warnings, or one
// process's one error. A file the stream cannot read exactly as the
// importer does is left to it, with the reason.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "scene/scene.h"
#include "formats/assimp/model_window.h"
#include "formats/stl/stl_reader.h"
#include "stl_file.h"
#include "test_util.h"
#include "window_text.h"

namespace opsila {
namespace {

namespace fs = std::filesystem;

using test::stl_grid;
using test::StlFile;

#ifdef OPSILA_HAVE_ASSIMP

std::string on_ranks(const std::string& path, int R, std::size_t block, std::size_t limit = std::size_t(1) << 24) {
  return test::windows_text(R, [&](const ModelWindow& w, std::uint64_t& fans) {
    return load_stl_window(path, limit, w, fans, block);
  });
}

class StlWindow : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = fs::temp_directory_path() / ("opsila_stl_window_" + std::to_string(::getpid()));
    fs::create_directories(dir);
  }
  void TearDown() override { fs::remove_all(dir); }
  std::string file(const StlFile& s, const std::string& name) {
    const std::string path = (dir / name).string();
    test::write_stl(path, s);
    return path;
  }
  // The windows of 1..4 ranks, with blocks of 1 record (a block is at least
  // one), 3 records and 2^20 bytes, against one process; returns one
  // process's text.
  std::string expect_same(const StlFile& s, const std::string& what) {
    const std::string path = file(s, what + ".stl");
    EXPECT_EQ(stl_stream_refusal(path), "") << what;
    const std::string whole = test::imported_text(path);
    EXPECT_EQ(whole.rfind("error", 0), std::string::npos) << what << ": the importer reads it: " << whole;
    for (std::size_t block : {std::size_t(1), std::size_t(3 * 50 + 17), std::size_t(1) << 20})
      for (int R : {1, 2, 3, 4}) {
        SCOPED_TRACE(what + ": blocks of " + std::to_string(block) + " bytes, " + std::to_string(R) + " ranks");
        EXPECT_EQ(on_ranks(path, R, block), whole);
        if (HasFailure()) return whole;
      }
    return whole;
  }
  fs::path dir;
};

// Every facet of a stl_grid is one, with the importer's normals (the
// facet's, on each corner; a zero one kept as the importer keeps it), one
// triangle is degenerate, and the material is CONTRACT's default (the
// importer's white "DefaultMaterial" is its placeholder).
TEST_F(StlWindow, WindowsTogetherAreTheImportersTriangles) {
  const StlFile grid = stl_grid(9, 7);
  const std::string whole = expect_same(grid, "grid");
  EXPECT_NE(whole.find("facets " + std::to_string(grid.facets.size()) + " "), std::string::npos) << whole;
  EXPECT_NE(whole.find(": 1 degenerate (zero-area) triangle(s)"), std::string::npos) << whole;
  EXPECT_NE(whole.find(" attr 10 "), std::string::npos) << "the facets' normals: " << whole;
  EXPECT_NE(whole.find("\nmaterial default "), std::string::npos) << whole;
  EXPECT_EQ(whole.find("\nmaterial ", whole.find("\nmaterial default ") + 1), std::string::npos) << "one material";
  StlFile solid = stl_grid(6, 5);
  solid.header = "solid written by a writer that calls every STL solid";  // binary: its size says so
  expect_same(solid, "solid_header");
  StlFile odd = stl_grid(5, 4);
  odd.facets[3].normal = {std::numeric_limits<float>::quiet_NaN(), 0, 1};  // not a normal: the triangle has none
  odd.facets[4].normal = {0, std::numeric_limits<float>::infinity(), 0};
  odd.facets[5].corner[1][0] = -0.0f;
  odd.facets[6].normal = {0, 0, 7};  // not unit: kept as given
  const std::string text = expect_same(odd, "nan_normal_negative_zero");
  EXPECT_NE(text.find(" 3 0 0\n"), std::string::npos) << "facet 3 has no attributes: " << text;
  expect_same(stl_grid(40, 30), "many_facets");
  StlFile one;
  one.facets = {stl_grid(2, 2).facets[0]};
  expect_same(one, "one_facet");
}

// Files the importer path refuses too: one error, one process's, the same
// on every rank.
TEST_F(StlWindow, BadFilesGiveOneErrorOnEveryRank) {
  const StlFile grid = stl_grid(5, 4);
  const auto expect_error = [&](const StlFile& s, const std::string& name, const std::string& fragment) {
    const std::string path = file(s, name + ".stl");
    EXPECT_EQ(stl_stream_refusal(path), "") << name << ": the stream reads it";
    const std::string whole = test::imported_text(path);
    EXPECT_EQ(whole.rfind("error " + path + ": ", 0), 0u) << name << ": one process: " << whole;
    EXPECT_NE(whole.find(fragment), std::string::npos) << name << ": " << whole;
    EXPECT_EQ(std::count(whole.begin(), whole.end(), '\n'), 1) << name << ": one error line: " << whole;
    for (int R : {1, 3}) EXPECT_EQ(on_ranks(path, R, 2 * 50), whole) << name << " on " << R << " ranks";
  };
  StlFile s = grid;
  s.facets[17].corner[2][1] = std::numeric_limits<float>::quiet_NaN();
  expect_error(s, "nan", "mesh 0 face 17: a vertex is not a finite number");
  s = grid;
  s.facets.back().corner[0][2] = -std::numeric_limits<float>::infinity();
  expect_error(s, "infinity", "mesh 0 face " + std::to_string(grid.facets.size() - 1) + ": a vertex is not a finite number");
  s = grid;
  s.facets[9].corner = {{{-3e38f, 0, 0}, {3e38f, 0, 0}, {0, 3e38f, 1}}};
  expect_error(s, "overflow", "mesh 0 face 9: facet too large: its edge vectors overflow float");
  s = grid;
  for (auto& f : s.facets) f.corner[2] = f.corner[1];
  expect_error(s, "all_zero_area", "no facets (the model has no drawable polygons)");
  // Over the triangle limit: refused on every rank, before any is kept.
  const std::string path = file(grid, "limit.stl");
  for (int R : {1, 3}) {
    const std::string text = on_ranks(path, R, 50, 20);
    EXPECT_EQ(text, "error " + path + ": too many triangles (more than 20)\n") << R << " ranks";
  }
}

// Files the stream leaves to the importer path (read whole): text, a size
// that is not the header's count of records (truncated, padded, an empty
// file), no facets, Materialise colours; the importer path then reads or
// refuses them as one process does.
TEST_F(StlWindow, FilesItCannotReadAsTheImporterDoesAreLeftToIt) {
  const StlFile grid = stl_grid(3, 3);
  const auto refused = [&](const std::string& name, const std::string& bytes) {
    const std::string path = (dir / name).string();
    std::ofstream(path, std::ios::binary) << bytes;
    return path;
  };
  const std::string ascii = refused("ascii.stl",
                                    "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
                                    "endloop\nendfacet\nendsolid t\n");
  EXPECT_EQ(stl_stream_refusal(ascii), "an ASCII STL");
  EXPECT_EQ(test::imported_text(ascii).rfind("error", 0), std::string::npos);
  const std::string bytes = test::stl_bytes(grid);
  const std::string truncated = refused("truncated.stl", bytes.substr(0, bytes.size() - 7));
  EXPECT_EQ(stl_stream_refusal(truncated), "its size, " + std::to_string(bytes.size() - 7) +
                                                " bytes, is not 84 + 50 x the " + std::to_string(grid.facets.size()) +
                                                " facets its header counts");
  EXPECT_NE(test::imported_text(truncated).find("(truncated file)"), std::string::npos);
  StlFile more = grid;
  more.count = grid.facets.size() + 1000;
  const std::string counted = file(more, "count_too_large.stl");
  EXPECT_NE(stl_stream_refusal(counted).find("is not 84 + 50 x the " + std::to_string(more.count) + " facets"),
            std::string::npos);
  EXPECT_NE(test::imported_text(counted).find("(truncated file)"), std::string::npos);
  EXPECT_NE(stl_stream_refusal(refused("padded.stl", bytes + "\n")).find("is not 84 + 50 x"), std::string::npos);
  EXPECT_EQ(stl_stream_refusal(refused("short.stl", bytes.substr(0, 60))),
            "it is shorter than a binary STL's 84-byte header");
  const std::string empty = refused("empty.stl", test::stl_bytes(StlFile{}));
  EXPECT_EQ(stl_stream_refusal(empty), "its header counts no facets");
  EXPECT_EQ(test::imported_text(empty).rfind("error " + empty + ": ", 0), 0u);
  StlFile colour = grid;
  colour.facets.back().attribute = 0;  // no facet colour: the header's is the material's
  colour.header = std::string("made by Magics COLOR=\xc0\x40\x20\xff", 25);
  const std::string coloured = file(colour, "materialise.stl");
  EXPECT_EQ(stl_stream_refusal(coloured), "its header names Materialise colours (COLOR=)");
  const std::string imported = test::imported_text(coloured);
  EXPECT_EQ(imported.rfind("error", 0), std::string::npos) << imported;
  EXPECT_NE(imported.find("\nmaterial ", imported.find("\nmaterial default ") + 1), std::string::npos)
      << "the importer makes the header's colour a material of its own: " << imported;
  colour.header = "MATERIAL=\x10\x20\x30\x40";
  EXPECT_EQ(stl_stream_refusal(file(colour, "material.stl")), "its header names Materialise colours (MATERIAL=)");
  const std::string missing = (dir / "missing.stl").string();
  EXPECT_EQ(stl_stream_refusal(missing).rfind("its size: " + missing + ": ", 0), 0u) << stl_stream_refusal(missing);
}

// Every STL of the fuzzing corpus (its first byte picks the format) and of
// the importer's test models (when installed): the stream reads it as the
// importer path does, or leaves it to the importer path.
TEST_F(StlWindow, EveryTestFileIsTheImportersOrLeftToIt) {
  const fs::path models = "/usr/share/assimp/models/STL";
  const std::vector<std::string> files = test::corpus_models(dir, 0, "stl", models);  // fuzz_model.cpp's "stl"
  ASSERT_GE(files.size(), 2u) << "the corpus has STL files";
  int streamed = 0;
  for (const std::string& path : files) {
    SCOPED_TRACE(path);
    if (!stl_stream_refusal(path).empty()) continue;
    ++streamed;
    const std::string whole = test::imported_text(path);
    for (int R : {1, 2, 3}) EXPECT_EQ(on_ranks(path, R, 13 * 50), whole);
  }
  std::printf("%d of %zu STL files streamed\n", streamed, files.size());
  EXPECT_GE(streamed, fs::is_directory(models) ? 3 : 1) << "the binary ones are read as a stream";
}

#endif

}  // namespace
}  // namespace opsila
