// An OBJ streamed by R ranks, each keeping its window (host/input/
// obj_stream.cpp): whatever the block and chunk sizes (down to a few bytes,
// so that lines cross block borders) and the number of ranks, the windows
// together are one process's triangles, in order, with the same ids,
// materials and attributes; every rank has the same warnings, counts,
// bounds and spread objects, or the same error.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "scene/scene.h"
#include "formats/obj/obj_loader.h"
#include "test_util.h"
#include "window_text.h"

namespace opsila {
namespace {

namespace fs = std::filesystem;

const std::string kData = std::string(OPSILA_SOURCE_DIR) + "/tests/data";


// One process: the figures, then its triangles, then the objects it would
// spread over R ranks' windows given which rank holds each triangle.
std::string one_process(const std::string& path) {
  return test::loaded_text([&] { return load_obj(path); });
}

// R ranks, each reading its window with blocks of `how`.
std::string on_ranks(const std::string& path, int R, const ObjStreaming& how) {
  return test::windows_text(R, [&](const ModelWindow& w, std::uint64_t& fans) {
    return load_obj_window(path, std::size_t(1) << 24, w, fans, how);
  });
}

void expect_same_windows(const std::string& path, const std::string& what) {
  const std::string whole = one_process(path);
  for (std::size_t block : {std::size_t(1), std::size_t(5), std::size_t(64), std::size_t(1) << 20})
    for (const ObjChunking chunking : {ObjChunking{3, 1}, ObjChunking{16, 3}, ObjChunking{}})
      for (int R : {1, 2, 3, 4}) {
        SCOPED_TRACE(what + ": blocks of " + std::to_string(block) + " bytes, chunks of " +
                     std::to_string(chunking.chunk_bytes) + ", " + std::to_string(R) + " ranks");
        ASSERT_EQ(on_ranks(path, R, ObjStreaming{block, chunking}), whole);
      }
}

// Quads and a pentagon (fans of several triangles), 'o' sections, usemtl,
// vt and vn, negative indices across blocks, a face naming a vertex defined
// after it, short, degenerate and unknown lines.
const std::string kBody =
    "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\n"
    "f 1 2 3\no first\nusemtl red\nf -4/-3 -3/-2 -2/-1\nf 1/1/1 2/2/1 4/3/1 3/1/1\n"
    "f 1 2\nf 1 1 1\nwhatever 1 2\nusemtl blue\no second\n# comment\nv 2 2 2\nf -1 -2 -3 -4\n"
    "f 1 2 6 3\nv 3 0 1\no third\nf 5 1 2 4 3\nusemtl red\nf 5 1 2\nf 1/9 2/1 3/2\nf 2 4 5 6\n";

TEST(ModelWindow, WindowsTogetherAreOneProcess) {
  test::TempDir dir;
  expect_same_windows(dir.write("lf.obj", kBody), "LF");
  std::string crlf;
  for (char c : kBody) crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
  expect_same_windows(dir.write("crlf.obj", crlf), "CRLF");
  expect_same_windows(dir.write("bom.obj", "\xef\xbb\xbf" + kBody), "BOM");
  expect_same_windows(dir.write("groups.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 1\ng a\nf 1 2 3\nf 1 2 4\n"
                                              "g b\nf 2 3 4 1\ng c\nf 1 3 4\nf 1 2 4 3\n"),
                      "groups");
}

TEST(ModelWindow, ErrorsAreOneProcessesOnEveryRank) {
  test::TempDir dir;
  const std::string good = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 3\n";
  expect_same_windows(dir.write("number.obj", good + "v 1 x 2\nf 1 2 3\nv nan 0 0\n"), "a bad number");
  expect_same_windows(dir.write("negative.obj", good + "f 1 2 3\nf -1 -2 -9\n"), "a negative index");
  expect_same_windows(dir.write("past.obj", good + "f 1 2 9\nv 1 2 3\n"), "an index past the end");
  expect_same_windows(dir.write("huge.obj", good + "v 3e38 0 0\nv 0 3e38 0\nv -3e38 -3e38 0\nf 6 7 8\n"),
                      "a facet too large");
  expect_same_windows(dir.write("nul.obj", good + "v 1 x 2\n" + std::string(3000, ' ') + std::string(1, '\0')),
                      "a NUL byte after a parse error");
  expect_same_windows(dir.write("flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\nf 3 2 1\n"), "all degenerate");
}

// The repository's OBJ files, good and bad, with their material libraries.
TEST(ModelWindow, SameResultForEveryTestFile) {
  int files = 0;
  for (const std::string dir : {kData, kData + "/bad"}) {
    for (const auto& e : fs::directory_iterator(dir)) {
      if (e.path().extension() != ".obj" || fs::file_size(e.path()) > (1u << 16)) continue;
      expect_same_windows(e.path().string(), e.path().filename().string());
      ++files;
    }
  }
  EXPECT_GT(files, 10);
}

}  // namespace
}  // namespace opsila
