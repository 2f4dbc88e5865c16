// A PLY model streamed by R ranks, each keeping its window (host/input/
// ply_window.cpp): whatever the block size (down to a byte, so that values
// and lines cross block borders) and the number of ranks, the windows
// together are the importer path's triangles (model_import.cpp), in order,
// with the same ids, materials and attributes, bit for bit; every rank has
// the same figures and warnings, or the same one error.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "scene/scene.h"
#include "formats/assimp/model_import.h"
#include "formats/ply/ply_reader.h"
#include "ply_file.h"
#include "test_util.h"
#include "window_text.h"

namespace opsila {
namespace {

namespace fs = std::filesystem;

using test::ply_grid;
using test::PlyFile;
using test::write_ply;

#ifdef OPSILA_HAVE_ASSIMP

std::string one_process(const std::string& path) { return test::imported_text(path); }

std::string on_ranks(const std::string& path, int R, std::size_t block) {
  return test::windows_text(R, [&](const ModelWindow& w, std::uint64_t& fans) {
    return load_ply_window(path, std::size_t(1) << 24, w, fans, block);
  });
}

class PlyWindow : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = fs::temp_directory_path() / ("opsila_ply_window_" + std::to_string(::getpid()));
    fs::create_directories(dir);
  }
  void TearDown() override { fs::remove_all(dir); }
  std::string file(const PlyFile& p, const std::string& name) {
    const std::string path = (dir / name).string();
    write_ply(path, p);
    return path;
  }
  // The windows of 1..4 ranks, with blocks of 1, 7 and 2^20 bytes, against
  // one process; returns one process's text.
  std::string expect_same(const PlyFile& p, const std::string& what) {
    const std::string path = file(p, what + ".ply");
    EXPECT_EQ(ply_stream_refusal(path), "") << what;
    const std::string whole = one_process(path);
    EXPECT_EQ(whole.rfind("error", 0), std::string::npos) << what << ": the importer reads it: " << whole;
    for (std::size_t block : {std::size_t(1), std::size_t(7), std::size_t(1) << 20})
      for (int R : {1, 2, 3, 4}) {
        SCOPED_TRACE(what + ": blocks of " + std::to_string(block) + " bytes, " + std::to_string(R) + " ranks");
        EXPECT_EQ(on_ranks(path, R, block), whole);
        if (HasFailure()) return whole;
      }
    return whole;
  }
  // A ply_grid file's figures: every face but the one of two corners is a
  // facet, one triangle is degenerate; `attributes`: normals or uv.
  void expect_grid(const PlyFile& p, const std::string& what, bool attributes) {
    const std::string whole = expect_same(p, what);
    EXPECT_EQ(whole.find(" attr ") != std::string::npos, attributes) << whole;
    EXPECT_NE(whole.find("facets " + std::to_string(p.faces.size() - 1) + " "), std::string::npos) << whole;
    EXPECT_NE(whole.find("degenerate (zero-area) triangle(s)"), std::string::npos) << whole;
    EXPECT_NE(whole.find(": 1 point or line primitive(s) skipped"), std::string::npos) << whole;
  }
  fs::path dir;
};

TEST_F(PlyWindow, WindowsTogetherAreTheImportersTriangles) {
  expect_grid(ply_grid(9, 7, 0), "binary_le", false);
  PlyFile be = ply_grid(8, 6, 5);
  be.format = "binary_big_endian";
  be.props = {{"double", "x"}, {"float", "y"}, {"float", "z"}, {"float", "nx"}, {"float", "ny"}, {"float", "nz"},
              {"float", "u"}, {"float", "v"}};
  expect_grid(be, "binary_be_normals_uv", true);
  PlyFile text = ply_grid(7, 5, 6);
  text.format = "ascii";
  text.props = {{"float", "x"}, {"float", "y"}, {"double", "z"}, {"float", "s"}, {"float", "t"}, {"uchar", "red"},
                {"float", "nx"}, {"float", "ny"}, {"float", "nz"}};
  for (auto& v : text.vertices) v[5] = 200;  // a colour: not used
  text.count_type = "int", text.index_type = "uint";
  expect_grid(text, "ascii_uv_normals_colour", true);
  PlyFile ints = ply_grid(6, 6, 2);
  ints.props = {{"short", "x"}, {"int", "y"}, {"uchar", "z"}, {"float", "texture_u"}, {"float", "texture_v"}};
  for (auto& v : ints.vertices) v[0] *= 8, v[1] *= 4, v[2] = v[2] * 10 + 10;
  ints.count_type = "ushort", ints.index_type = "uint";
  ints.list_name = "vertex_index";
  expect_grid(ints, "integer_positions", true);
  PlyFile odd = ply_grid(5, 4, 3);
  odd.props = {{"float", "x"}, {"float", "y"}, {"float", "z"}, {"float", "nx"}, {"float", "ny"}, {"float", "nz"}};
  odd.vertices[3][3] = std::numeric_limits<double>::quiet_NaN();  // not a normal: the triangle has none
  odd.vertices[4][0] = -0.0;
  expect_grid(odd, "nan_normal_negative_zero", true);
  expect_grid(ply_grid(40, 30, 0), "many_faces", false);
}

// Files the importer path reads, odd but not wrong: faces of 0, 1 and 300
// corners, properties in another order.
TEST_F(PlyWindow, OddFilesAreTheImportersToo) {
  const PlyFile p = ply_grid(6, 5, 0);
  PlyFile empty = p;
  empty.faces.insert(empty.faces.begin() + 3, std::vector<long long>{});
  empty.faces.insert(empty.faces.begin() + 5, std::vector<long long>{4});
  expect_same(empty, "empty_and_point_faces");
  PlyFile large = p;
  large.count_type = "int";
  large.faces.insert(large.faces.begin(), std::vector<long long>(300, 7));
  large.faces[0][1] = 8, large.faces[0][2] = 14;
  expect_same(large, "a_face_of_300_corners");
  PlyFile order = p;
  order.format = "binary_big_endian";
  order.props = {{"float", "z"}, {"ushort", "confidence"}, {"float", "x"}, {"float", "y"}};
  for (auto& v : order.vertices) v = {v[2], 3, v[0], v[1]};
  expect_same(order, "properties_in_another_order");
}

// The files a share refuses: one error naming the file, the element and
// where (line or byte), the same on every rank; one process refuses them
// too: a text file is read through by the stream before the importer,
// which ignored the rest of a line, took "2x" as 2 and 2.9 as an index 2.
TEST_F(PlyWindow, BadFilesGiveOneErrorOnEveryRank) {
  const PlyFile p = ply_grid(5, 4, 0);
  const auto expect_error = [&](const PlyFile& q, const std::string& name, const std::string& tail,
                                const std::vector<std::string>& fragments) {
    const std::string path = file(q, name + ".ply");
    if (!tail.empty()) std::ofstream(path, std::ios::binary | std::ios::app) << tail;
    EXPECT_EQ(one_process(path).rfind("error ", 0), 0u) << name << ": one process";
    for (int R : {1, 3}) {
      const std::string text = on_ranks(path, R, 6);
      EXPECT_EQ(text.rfind("error " + path + ":", 0), 0u) << name << ": " << text;
      EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1) << name << ": one error line: " << text;
      for (const std::string& f : fragments) EXPECT_NE(text.find(f), std::string::npos) << name << ": " << f << ": " << text;
    }
  };
  const std::string last = "'face' element " + std::to_string(p.faces.size()) + " of " + std::to_string(p.faces.size());
  PlyFile q = p;
  q.faces.back() = {0, 1, 20};
  expect_error(q, "index_out_of_range", "", {last + " at byte ", "vertex index 20 out of range (the file has 20 vertices)"});
  q.faces.back() = {0, -1, 2};
  expect_error(q, "negative_index", "", {last + " at byte ", "vertex index -1 out of range"});
  q.format = "ascii";
  q.faces.back() = {0, 1, 20};
  expect_error(q, "ascii_index_out_of_range", "", {".ply:" + std::to_string(10 + 20 + p.faces.size()) + ": PLY " + last});
  q = p;
  q.face_count = p.faces.size() - 1;  // both readers had dropped the last face
  expect_error(q, "data_after_the_last_face", "",
               {"PLY data goes on past the " + std::to_string(p.faces.size() - 1) + " 'face' element(s)", "(from byte "});
  q.format = "ascii";
  expect_error(q, "ascii_data_after_the_last_face", "", {".ply:" + std::to_string(10 + 20 + p.faces.size()) + ": PLY data goes on past"});
  q = p;
  q.face_count = std::uint64_t(1) << 40;
  expect_error(q, "a_trillion_faces", "", {"of 1099511627776 at byte ", "the file ends early (truncated)"});
  q = p;
  q.face_count = p.faces.size() + 1;
  expect_error(q, "truncated", std::string("\x03\x01\x00\x00\x00", 5), {" at byte 699: the file ends early (truncated)"});
  q.format = "ascii";
  expect_error(q, "ascii_truncated", "3 0 1", {".ply:47: ", "the file ends early (truncated)"});
  expect_error(q, "ascii_short_line", "3 0 1\n", {".ply:47: ", "fewer values on the line than the header's properties"});
  expect_error(q, "ascii_long_line", "3 0 1 2 3\n", {".ply:47: ", "more values on the line than the header's properties"});
  q.faces.pop_back();
  expect_error(q, "not_a_number", "3 0 1 2x\n", {"'2x' is not a number of its property's type"});
  expect_error(q, "a_fraction", "3 0 1 2.9\n", {"'2.9' is not a number of its property's type"});
  expect_error(q, "past_32_bits", "3 0 1 99999999999\n", {"'99999999999' is not a number of its property's type"});
  q = p;
  q.vertices[6][1] = std::nan("");
  expect_error(q, "nan", "", {"mesh 0 face 0: a vertex is not a finite number"});
  q.vertices[6][1] = -INFINITY;
  q.format = "ascii";
  // Text: the face that uses it, and the vertex's line (header 10 lines).
  expect_error(q, "ascii_infinity", "", {": PLY 'face' element ", ": vertex 6 (line 17) is not a finite number"});
  q = p;
  q.vertices.resize(1000);
  expect_error(q, "too_many_vertices", "", {".ply:4: PLY header asks for 1000 vertices"});
  q = p;
  q.faces.clear();
  expect_error(q, "no_faces", "", {"no facets"});
}

// A list count outside its type, or of a type that is no integer, is
// named as such, not taken for a truncated file (a signed count of -1 read
// as 4 billion) nor read past its type's range.
TEST_F(PlyWindow, ListCountsOutsideTheirTypeAreNamed) {
  PlyFile p = ply_grid(3, 3, 0);
  p.count_type = "int";
  p.face_count = p.faces.size() + 1;
  const std::string negative = file(p, "negative_count.ply");
  std::ofstream(negative, std::ios::binary | std::ios::app) << std::string("\xff\xff\xff\xff", 4) << std::string(12, '\0');
  EXPECT_NE(one_process(negative).find("list length -1 is negative"), std::string::npos) << one_process(negative);
  p.face_count = UINT64_MAX;
  p.count_type = "float";
  const std::string real = file(p, "float_count.ply");
  EXPECT_NE(one_process(real).find("the list 'vertex_indices' has a count type that is not an integer type"),
            std::string::npos)
      << one_process(real);
  // Both readers had taken a corner 3.99 as vertex 3.
  p.count_type = "uchar";
  p.index_type = "float";
  p.face_count = p.faces.size();
  for (const char* format : {"ascii", "binary_little_endian"}) {
    p.format = format;
    const std::string floats = file(p, std::string("float_indices_") + format + ".ply");
    EXPECT_EQ(one_process(floats), "error " + floats + ": PLY 'face' element: the list 'vertex_indices' holds "
                                   "floating-point values, where vertex indices are integers\n");
  }
  p.index_type = "int";
  PlyFile flat = p;  // both readers had put every vertex at z = 0
  flat.props = {{"float", "x"}, {"float", "y"}};
  for (auto& v : flat.vertices) v.resize(2);
  const std::string no_z = file(flat, "no_z.ply");
  EXPECT_EQ(one_process(no_z), "error " + no_z + ": PLY 'vertex' element: no 'z' property (a position is x, y and z)\n");
  p.format = "ascii";
  p.faces.back().assign(300, 0);
  const std::string wide = file(p, "wide_count.ply");
  EXPECT_NE(one_process(wide).find("list length 300 does not fit its count type"), std::string::npos)
      << one_process(wide);
  EXPECT_NE(on_ranks(wide, 2, 7).find("'300' is not a number of its property's type"), std::string::npos)
      << on_ranks(wide, 2, 7);
}

// Files the stream leaves to the importer path (read whole): other
// elements, a texture named in a comment, partial normals or uv.
TEST_F(PlyWindow, FilesItCannotReadAsTheImporterDoesAreLeftToIt) {
  const PlyFile p = ply_grid(3, 3, 0);
  PlyFile q = p;
  q.extra_header = "comment TextureFile wood.png\n";
  EXPECT_EQ(ply_stream_refusal(file(q, "texture.ply")), "a comment names a texture");
  q = p;
  q.props.push_back({"float", "nx"});
  for (auto& v : q.vertices) v.push_back(1);
  EXPECT_EQ(ply_stream_refusal(file(q, "nx.ply")), "its vertices have some normal components, not all");
  q = p;
  q.extra_header = "element edge 0\nproperty int vertex1\n";
  EXPECT_EQ(ply_stream_refusal(file(q, "edges.ply")),
            "its elements are not 'vertex' then 'face' (or 'tristrips', or both)");
  q = p;
  q.list_name = "vertex_indices";
  q.extra_header = "property uchar red\n";
  EXPECT_EQ(ply_stream_refusal(file(q, "face_colour.ply")),
            "its 'face' elements hold more than one list of vertex indices");
  const std::string missing = (dir / "missing.ply").string();
  EXPECT_EQ(ply_stream_refusal(missing).rfind("its header: " + missing + ": cannot open", 0), 0u);
  std::ofstream(dir / "odd_header.ply") << "ply\nformat ascii 1.0\nmade by hand\nend_header\n";
  EXPECT_EQ(ply_stream_refusal((dir / "odd_header.ply").string()),
            "its header: " + (dir / "odd_header.ply").string() + ":3: PLY header: unknown line 'made'");
}

// Every PLY input of the fuzzing corpus (its first byte picks the format)
// and every PLY of the importer's test models (when installed): the stream
// reads it as the importer path does, or leaves it to the importer path; a
// file the importer refuses, the stream refuses too.
TEST_F(PlyWindow, EveryTestFileIsTheImportersOrLeftToIt) {
  const fs::path models = "/usr/share/assimp/models/PLY";
  const std::vector<std::string> files = test::corpus_models(dir, 4, "ply", models);  // fuzz_model.cpp's "ply"
  ASSERT_GE(files.size(), 5u) << "the corpus has PLY files";
  int streamed = 0;
  for (const std::string& path : files) {
    SCOPED_TRACE(path);
    if (!ply_stream_refusal(path).empty()) continue;
    ++streamed;
    const std::string whole = one_process(path);
    for (int R : {1, 2, 3}) {
      const std::string windows = on_ranks(path, R, 13);
      if (whole.rfind("error ", 0) == 0) EXPECT_EQ(windows.rfind("error " + path + ":", 0), 0u) << windows;
      else EXPECT_EQ(windows, whole);
    }
  }
  EXPECT_GE(streamed, 6) << "most of them are read as a stream";
}

#endif

}  // namespace
}  // namespace opsila
