// PLY triangle strips (a 'tristrips' element, -1 restarting a strip): read
// by the project's PLY stream on one process and on ranks alike, each strip
// triangle a facet of its own, the odd ones turned to face as the even
// ones; the same triangles, ids and image as the file that lists them as
// a 'face' element. And a PLY element nothing reads is named in a warning.
#include <gtest/gtest.h>

#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "formats/assimp/model_import.h"
#include "formats/ply/ply_reader.h"
#include "ply_file.h"
#include "test_util.h"
#include "window_text.h"

namespace opsila {
namespace {

using test::PlyFile;

#ifdef OPSILA_HAVE_ASSIMP

// Every occurrence of `from` in `text` replaced by `to`.
std::string replaced(std::string text, const std::string& from, const std::string& to) {
  for (std::size_t at = text.find(from); at != std::string::npos; at = text.find(from, at + to.size()))
    text.replace(at, from.size(), to);
  return text;
}

struct PlyStrips : ::testing::Test {
  test::TempDir dir;
  // A w x h grid as strips (in `format`) and as the faces they make: the
  // strip file's path; `faces_path` gets the other's.
  std::string write_pair(int w, int h, const std::string& format, const std::string& name, std::string& faces_path,
                         bool with_faces = false) {
    PlyFile strips = test::ply_grid(w, h, 0), faces = strips;
    strips.format = faces.format = format;
    if (!with_faces) strips.faces.clear(), faces.faces.clear(), strips.face_element = false;
    strips.strips = test::grid_strips(w, h, faces.faces);
    const std::string path = dir.file(name + "_strips.ply");
    faces_path = dir.file(name + "_faces.ply");
    test::write_ply(path, strips);
    test::write_ply(faces_path, faces);
    return path;
  }
  // The strip file reads as the face file on one process and on 1..3 ranks.
  void expect_as_faces(const std::string& strips, const std::string& faces, std::size_t triangles) {
    const std::string whole = test::imported_text(strips);
    EXPECT_EQ(whole.rfind("error", 0), std::string::npos) << whole;
    EXPECT_NE(whole.find("triangles " + std::to_string(triangles) + "\n"), std::string::npos) << whole;
    EXPECT_EQ(replaced(whole, strips, faces), test::imported_text(faces));
    for (int R : {1, 2, 3}) {
      const std::string windows = test::windows_text(R, [&](const ModelWindow& w, std::uint64_t& fans) {
        return load_ply_window(strips, std::size_t(1) << 24, w, fans, 5);
      });
      EXPECT_EQ(windows, whole) << R << " ranks";
    }
  }
};

TEST_F(PlyStrips, StripsAreTheirTrianglesInEveryFormat) {
  for (const char* format : {"binary_little_endian", "binary_big_endian", "ascii"}) {
    SCOPED_TRACE(format);
    std::string faces;
    const std::string strips = write_pair(9, 5, format, format, faces);
    EXPECT_EQ(ply_stream_refusal(strips), "");
    expect_as_faces(strips, faces, 2 * 8 * 4);
  }
}

// Faces, then strips: the strips' facets are numbered after the faces'.
TEST_F(PlyStrips, StripsFollowTheFaces) {
  std::string faces;
  const std::string strips = write_pair(6, 4, "binary_little_endian", "both", faces, true);
  expect_as_faces(strips, faces, 2 * 5 * 3 + 2 * 5 * 3 + 4);
}

// Strips the stream cannot read (a second property) are refused by name,
// never read as one triangle; a bad index names the element and where.
TEST_F(PlyStrips, StripsTheStreamCannotReadAreRefused) {
  PlyFile p = test::ply_grid(4, 3, 0);
  std::vector<std::vector<long long>> ignored;
  p.strips = test::grid_strips(4, 3, ignored);
  p.extra_strip_header = "property uchar flags\n";
  p.format = "ascii";
  const std::string path = dir.file("flags.ply");
  test::write_ply(path, p);
  test::expect_error([&] { load_model(path); },
                     {path + ": PLY triangle strips are read only", "'tristrips' elements hold more than one list"});
  p.extra_strip_header.clear();
  p.strips = {{0, 1, 2, 12}};
  const std::string bad = dir.file("bad_index.ply");
  test::write_ply(bad, p);
  test::expect_error([&] { load_model(bad); },
                     {bad + ":", "PLY 'tristrips' element 1 of 1", "vertex index 12 out of range (the file has 12"});
}

// A strip file read from memory (fuzz_model's path) reads as from its
// file; one whose header only the importer's reading accepts never
// reaches the importer (it asked for 12 GB for a 600-byte file).
TEST_F(PlyStrips, StripsFromMemoryAndHeadersOnlyTheImporterReads) {
  std::string faces;
  const std::string strips = write_pair(4, 3, "binary_little_endian", "mem", faces);
  const std::string bytes = test::read_file(strips);
  const Scene from_file = load_model(strips), from_memory = load_model_from_memory(bytes, strips, "ply");
  ASSERT_EQ(from_memory.triangles.size(), from_file.triangles.size());
  for (std::size_t t = 0; t < from_file.triangles.size(); ++t) {
    EXPECT_EQ(from_memory.triangles[t].object_id, from_file.triangles[t].object_id);
    EXPECT_EQ(from_memory.triangles[t].facet_id, from_file.triangles[t].facet_id);
    EXPECT_EQ(from_memory.triangles[t].fan, from_file.triangles[t].fan);
    EXPECT_EQ(from_memory.triangles[t].v0, from_file.triangles[t].v0);
    EXPECT_EQ(from_memory.triangles[t].v2, from_file.triangles[t].v2);
  }
  // A stray byte after a count, which the importer's header reading skips.
  std::string odd = bytes;
  odd.insert(odd.find("element vertex ") + 17, "\x01");
  const std::string path = dir.write("odd.ply", odd);
  for (const auto& load : {std::function<void()>([&] { load_model(path); }),
                           std::function<void()>([&] { load_model_from_memory(odd, path, "ply"); })})
    test::expect_error(load, {path + ": PLY triangle strips are read only by opsila's PLY reader, which cannot "
                                     "read this file (" + path + ":4: PLY header"});
}

// An element nothing reads: one warning naming it and its count.
TEST_F(PlyStrips, AnElementNothingReadsIsNamed) {
  const std::string path = dir.write(
      "grid.ply",
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nelement range_grid 6\n"
      "property list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n"
      "1 0\n1 1\n1 2\n1 3\n0\n0\n");
  const Scene s = load_model(path);
  ASSERT_EQ(s.warnings.size(), 1u);
  EXPECT_EQ(s.warnings[0], path + ":9: the PLY element 'range_grid' (6 of them) is not read: only 'vertex', "
                                  "'face' and 'tristrips' give facets, so nothing of it is drawn");
}

// The command line: the strips' triangle count in --stats, and the image
// and item buffer of the file listing them as faces.
TEST_F(PlyStrips, RenderedAsTheirFaces) {
  for (const char* format : {"binary_little_endian", "ascii"}) {
    SCOPED_TRACE(format);
    std::string faces;
    const std::string strips = write_pair(7, 6, format, format, faces);
    for (const std::string& path : {strips, faces}) {
      const test::RunResult r = test::run_opsila({"render", path, "--size", "40x30", "--pes", "4", "-q", "-o",
                                                  path + ".pfm", "--item-buffer", path + ".npy", "--stats",
                                                  path + ".json"});
      ASSERT_EQ(r.exit_code, 0) << r.err;
      const auto stats = nlohmann::json::parse(test::read_file(path + ".json"));
      EXPECT_EQ(stats.at("scene").at("triangles").get<int>(), 2 * 6 * 5) << path;
    }
    EXPECT_TRUE(test::read_file(strips + ".pfm") == test::read_file(faces + ".pfm"));
    EXPECT_TRUE(test::read_file(strips + ".npy") == test::read_file(faces + ".npy"));
  }
}

#endif

}  // namespace
}  // namespace opsila
