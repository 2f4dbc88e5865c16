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

#include "core/scene.h"
#include "input/obj_loader.h"
#include "test_util.h"

namespace opsila {
namespace {

namespace fs = std::filesystem;

const std::string kData = std::string(OPSILA_SOURCE_DIR) + "/tests/data";

using test::hex;

// A triangle with its attributes' values (indices differ between scenes).
std::string triangle_text(const Scene& s, const Triangle& t) {
  std::ostringstream o;
  for (const Vec3* v : {&t.v0, &t.v1, &t.v2}) o << hex((*v)[0]) << ' ' << hex((*v)[1]) << ' ' << hex((*v)[2]) << ' ';
  o << t.facet_id << ' ' << t.object_id << ' ' << t.material;
  if (t.attributes >= 0) {
    const VertexAttributes& a = s.attributes.at(std::size_t(t.attributes));
    o << " attr " << a.has_normals << a.has_uv;
    for (int c = 0; c < 3; ++c)
      o << ' ' << hex(a.normal[c][0]) << ' ' << hex(a.normal[c][1]) << ' ' << hex(a.normal[c][2]) << ' '
        << hex(a.uv[c][0]) << ' ' << hex(a.uv[c][1]);
  }
  return o.str();
}

// What every rank (or the one process) has besides its triangles.
std::string figures_text(const Scene& s, std::size_t triangles, const Vec3& lo, const Vec3& hi) {
  std::ostringstream o;
  o << "objects " << s.num_objects << " facets " << s.num_facets << " triangles " << triangles << "\n";
  o << "bounds " << hex(lo[0]) << ' ' << hex(lo[1]) << ' ' << hex(lo[2]) << ' ' << hex(hi[0]) << ' ' << hex(hi[1])
    << ' ' << hex(hi[2]) << "\n";
  for (const MaterialDesc& m : s.materials) o << "material " << m.name << ' ' << hex(m.kd[0]) << ' ' << m.map_kd << "\n";
  for (const std::string& w : s.warnings) o << "warning " << w << "\n";
  for (const std::string& f : s.input_files) o << "input " << f << "\n";
  o << "camera " << hex(s.camera.eye[0]) << ' ' << hex(s.camera.eye[1]) << ' ' << hex(s.camera.eye[2]) << "\n";
  return o.str();
}

std::string error_text(const InputError& e) {
  std::string o = "error " + std::string(e.what()) + "\n";
  for (const std::string& w : e.warnings) o += "warning " + w + "\n";
  return o;
}

// One process: the figures, then its triangles, then the objects it would
// spread over R ranks' windows given which rank holds each triangle.
std::string one_process(const std::string& path) {
  try {
    const Scene s = load_obj(path);
    Vec3 lo, hi;
    s.bounds(lo, hi);
    std::string o = figures_text(s, s.triangles.size(), lo, hi);
    for (const Triangle& t : s.triangles) o += triangle_text(s, t) + "\n";
    return o;
  } catch (const InputError& e) {
    return error_text(e);
  }
}

// R ranks: each one's figures (which must agree), then the windows' triangles
// in rank order; the spread objects each rank names must be those whose
// triangles lie on several ranks.
std::string on_ranks(const std::string& path, int R, const ObjStreaming& how) {
  std::string figures, triangles;
  std::vector<std::set<int>> holders;  // by object: ranks holding its triangles
  std::vector<int> spread;
  for (int r = 0; r < R; ++r) {
    try {
      ObjWindow w;
      w.rank = r, w.ranks = R;
      w.load_maps = false;
      std::uint64_t fans = 0;
      const Scene counted = load_obj_window(path, std::size_t(1) << 24, w, fans, how);
      EXPECT_TRUE(counted.triangles.empty()) << "the counting read keeps nothing";
      w.plan_all = w.plan_total = counted.share.total_triangles;
      w.fans = fans;
      w.load_maps = true;
      const Scene s = load_obj_window(path, std::size_t(1) << 24, w, fans, how);
      const std::string mine = figures_text(s, s.share.total_triangles, s.share.lo, s.share.hi);
      if (r == 0) figures = mine, spread = s.share.spread;
      EXPECT_EQ(mine, figures) << "rank " << r << " agrees with rank 0";
      EXPECT_EQ(s.share.spread, spread) << "rank " << r;
      for (const Triangle& t : s.triangles) {
        triangles += triangle_text(s, t) + "\n";
        if (holders.size() <= std::size_t(t.object_id)) holders.resize(std::size_t(t.object_id) + 1);
        holders[std::size_t(t.object_id)].insert(r);
      }
    } catch (const InputError& e) {
      const std::string mine = error_text(e);
      if (r == 0) figures = mine;
      EXPECT_EQ(mine, figures) << "rank " << r << " fails as rank 0 does";
    }
  }
  std::vector<int> several;
  for (std::size_t o = 0; o < holders.size(); ++o)
    if (holders[o].size() > 1) several.push_back(static_cast<int>(o));
  EXPECT_EQ(spread, several) << "spread: the objects whose triangles lie on several ranks";
  return figures + triangles;
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

TEST(ObjWindow, WindowsTogetherAreOneProcess) {
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

TEST(ObjWindow, ErrorsAreOneProcessesOnEveryRank) {
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
TEST(ObjWindow, SameResultForEveryTestFile) {
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
