// OBJ files read in chunks on several threads (host/formats/obj/obj_chunks.cpp):
// whatever the chunk size (down to one line a chunk, so that every line
// is at a chunk border) and the threads, the same scene, warnings and error
// messages as one parser reading the lines in turn.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "scene/scene.h"
#include "formats/obj/obj_loader.h"
#include "formats/obj/obj_parser.h"
#include "test_util.h"

namespace opsila {
namespace {

namespace fs = std::filesystem;

const std::string kData = std::string(OPSILA_SOURCE_DIR) + "/tests/data";

using test::hex;

// Everything the loader hands on, as text (or the error and its warnings).
std::string outcome(const std::string& text, const std::string& base_dir, const ObjChunking& chunking,
                    std::size_t max_triangles = std::size_t(1) << 24) {
  std::ostringstream o;
  try {
    const Scene s = load_obj_from_string(text, "t.obj", base_dir, chunking, max_triangles);
    o << "objects " << s.num_objects << " facets " << s.num_facets << "\n";
    for (const Triangle& t : s.triangles) {
      for (const Vec3* v : {&t.v0, &t.v1, &t.v2}) o << hex((*v)[0]) << ' ' << hex((*v)[1]) << ' ' << hex((*v)[2]) << ' ';
      o << t.facet_id << ' ' << t.object_id << ' ' << t.material << ' ' << t.attributes << "\n";
    }
    for (const VertexAttributes& a : s.attributes) {
      o << a.has_normals << a.has_uv;
      for (int c = 0; c < 3; ++c)
        o << ' ' << hex(a.normal[c][0]) << ' ' << hex(a.normal[c][1]) << ' ' << hex(a.normal[c][2]) << ' '
          << hex(a.uv[c][0]) << ' ' << hex(a.uv[c][1]);
      o << "\n";
    }
    for (const MaterialDesc& m : s.materials) o << "material " << m.name << ' ' << hex(m.kd[0]) << ' ' << m.map_kd << "\n";
    for (const std::string& w : s.warnings) o << "warning " << w << "\n";
    for (const std::string& f : s.input_files) o << "input " << f << "\n";
    o << "camera " << hex(s.camera.eye[0]) << ' ' << hex(s.camera.eye[1]) << ' ' << hex(s.camera.eye[2]) << "\n";
  } catch (const InputError& e) {
    o << "error " << e.what() << "\n";
    for (const std::string& w : e.warnings) o << "warning " << w << "\n";
  }
  return o.str();
}

const ObjChunking kWhole{std::size_t(1) << 40, 1};

void expect_same_in_chunks(const std::string& text, const std::string& base_dir, const std::string& what,
                           std::size_t max_triangles = std::size_t(1) << 24) {
  const std::string whole = outcome(text, base_dir, kWhole, max_triangles);
  for (std::size_t bytes : {1, 2, 3, 7, 16, 29, 64, 256})
    for (int threads : {1, 3}) {
      SCOPED_TRACE(what + ": chunks of " + std::to_string(bytes) + " bytes, " + std::to_string(threads) + " threads");
      ASSERT_EQ(outcome(text, base_dir, ObjChunking{bytes, threads}, max_triangles), whole);
    }
}

TEST(ObjChunks, SplitEndsEveryChunkAtALineEnd) {
  const std::string text = "v 0 0 0\r\nv 1 0 0\rv 0 1 0\nf 1 2 3 1 2 3 1 2 3 1 2 3\r\n\r\nf 1 2 3";
  for (std::size_t bytes = 1; bytes <= text.size() + 1; ++bytes) {
    const std::vector<std::string_view> parts = obj_parse::split_lines(text, bytes);
    std::string joined;
    for (std::size_t k = 0; k < parts.size(); ++k) {
      joined += std::string(parts[k]);
      ASSERT_FALSE(parts[k].empty());
      if (k + 1 < parts.size()) {
        const char last = parts[k].back();
        ASSERT_TRUE(last == '\n' || last == '\r') << bytes << ": chunk " << k << " ends mid-line";
        ASSERT_FALSE(last == '\r' && parts[k + 1].front() == '\n') << bytes << ": a CRLF pair split";
        ASSERT_GE(parts[k].size(), std::min(bytes, text.size())) << "a chunk ends at the first line end past its size";
      }
    }
    ASSERT_EQ(joined, text) << bytes;
  }
  // Never after a line that goes on in the next (a backslash before its end).
  const std::string continued = "v 0 0 0\nf 1 \\\n2 \\\r\n3\nf 1 \\\r2 3\n";
  for (std::size_t bytes = 1; bytes <= continued.size(); ++bytes) {
    const std::vector<std::string_view> parts = obj_parse::split_lines(continued, bytes);
    for (std::size_t k = 0; k + 1 < parts.size(); ++k) {
      const std::string_view p = parts[k];
      const std::size_t eol = p.size() >= 2 && p.substr(p.size() - 2) == "\r\n" ? p.size() - 2 : p.size() - 1;
      ASSERT_FALSE(eol > 0 && p[eol - 1] == '\\') << bytes << ": chunk " << k << " ends inside a continued line";
    }
  }
  // A border in the middle of a face line: the chunk takes the whole line.
  const std::vector<std::string_view> two = obj_parse::split_lines("v 1 2 3\nf 1 2 3 4 5\nv 4 5 6\n", 12);
  ASSERT_EQ(two.size(), 2u);
  EXPECT_EQ(two[0], "v 1 2 3\nf 1 2 3 4 5\n");
}

// Every line at a chunk border: sections, materials, negative indices that
// reach back across chunks, attributes, short and degenerate faces, unknown
// statements, CRLF and lone CR line ends, a byte-order mark.
TEST(ObjChunks, SameSceneAsOneParser) {
  const std::string body =
      "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\n"
      "f 1 2 3\no first\nusemtl red\nf -4/-3 -3/-2 -2/-1\ng part\nf 1//1 2//1 4//1 3//1\n"
      "f 1 2\nf 1 1 1\nwhatever 1 2\nusemtl blue\no second\n# comment\nv 2 2 2\nf -1 -2 -3 -4\n"
      "g other\nf 2/-9 3/-1 4/-2\nusemtl red\nf 5 1 2\nmtllib nothing.mtl\nf 1/9 2/1 3/2\n"
      "f 1 2 \\\n3 4\nv 3 \\\n\\\n3 3\nf -1 \\\n1 2\n";  // lines that go on in the next
  expect_same_in_chunks(body, "", "LF");
  std::string crlf, cr;
  for (char c : body) {
    crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
    cr += c == '\n' ? '\r' : c;
  }
  expect_same_in_chunks(crlf, "", "CRLF");
  expect_same_in_chunks(cr, "", "CR");
  expect_same_in_chunks("\xef\xbb\xbf" + body, "", "BOM");
}

// Errors at chunk borders: the first error of the file, named as one parser
// names it, with the warnings before it.
TEST(ObjChunks, SameErrorAsOneParser) {
  const std::string good = "mtllib a.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  expect_same_in_chunks(good + "v 1 x 2\nf 1 2 3\nv nan 0 0\n", "", "a bad number");
  expect_same_in_chunks(good + "f 1 2 3\nf -1 -2 -9\n", "", "a negative index past the file's start");
  expect_same_in_chunks(good + "f -1 -2 -9\nv 1 x 2\n", "", "a merge-time error before a chunk's error");
  expect_same_in_chunks(good + "f 1 2 9\nv 1 2 3\n", "", "an index past the end");
  expect_same_in_chunks(good + "f 1 2\nf 1 2 -99\n", "", "a short face's bad index");
  expect_same_in_chunks(good + "v 1 2 3\n\x01\nf 1 2 3\n", "", "a control byte");
  expect_same_in_chunks(good + "f 1 2 3\nf 1 2 3\nf 1 2 3\nf 1 2 3 1\n", "", "too many triangles", 4);
  expect_same_in_chunks(good + "f 1 2 3\n", "", "exactly the triangle limit", 2);
  expect_same_in_chunks(std::string("\xff\xfe") + good, "", "UTF-16");
  expect_same_in_chunks(good + "f 1 \\\n2 \\\n 9\nv 1 2 3\n", "", "a continued face's bad index");
  expect_same_in_chunks(good + "f 1 \\\n2 3\nv 1 \\\n\\\n2\nv 1 x 2\n", "", "an error after continued lines");
}

// The repository's OBJ files, good and bad, with their material libraries.
TEST(ObjChunks, SameResultForEveryTestFile) {
  int files = 0;
  for (const std::string dir : {kData, kData + "/bad", std::string(OPSILA_SOURCE_DIR) + "/tests/oclgrind"}) {
    for (const auto& e : fs::directory_iterator(dir)) {
      if (e.path().extension() != ".obj") continue;
      std::ifstream in(e.path(), std::ios::binary);
      std::ostringstream text;
      text << in.rdbuf();
      if (text.str().size() > (1u << 20)) continue;  // the one-byte chunks would take long
      expect_same_in_chunks(text.str(), dir, e.path().filename().string());
      ++files;
    }
  }
  EXPECT_GT(files, 20);
}

}  // namespace
}  // namespace opsila
