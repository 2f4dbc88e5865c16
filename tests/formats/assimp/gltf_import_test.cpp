// What a glTF asks of the importer, bounded and trimmed before the import:
// accessors whose elements the file does not hold are held to the
// importer's memory budget (gltf_checks.cpp), and skins and animations,
// which opsila never uses, are not read at all (gltf_still.h).
#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "formats/json/scene_file.h"
#include "gltf_test_files.h"
#include "test_util.h"

namespace opsila {
namespace {

using namespace test;  // the helpers of test_util.h and gltf_test_files.h

std::string error_loading(const std::string& path) { return error_of([&] { load_scene(path); }); }

// Accessors whose elements the file does not hold (no bufferView: zeros; or
// sparse: a few values) made the importer allocate whatever their count
// said: 12.9 GB for a 700-byte file (fuzz_model). What a mesh uses is
// estimated first and held to the importer's memory budget.
std::string unheld(const std::string& accessor, const std::string& primitive) {
  return R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
  "meshes": [{"primitives": [)" + primitive + R"(]}],
  "buffers": [{"uri": "tri.bin", "byteLength": 36}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0],
                 "max": [1, 1, 0]}, )" + accessor + "]}";
}

TEST(GltfImport, ElementsTheFileDoesNotHoldAreBoundedBeforeTheImport) {
  TempDir dir;
  dir.write("tri.bin", triangle_bytes());
  // Line indices, sparse: 1,616,904,193 of them from 2 bytes of data.
  const std::string sparse = dir.write(
      "sparse.gltf", unheld(R"({"componentType": 5121, "count": 1616904193, "type": "SCALAR", "sparse": {"count": 1,
        "indices": {"bufferView": 0, "componentType": 5121}, "values": {"bufferView": 0}}})",
                            R"({"attributes": {"POSITION": 0}, "indices": 1, "mode": 1})"));
  const RunResult r = run_opsila({"render", sparse, "-o", dir.file("x.png"), "--size", "8x8"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
  EXPECT_NE(r.error_lines()[0].find(sparse + ": meshes[0].primitives[0].indices (accessors[1], 1616904193 elements): "
                                             "importing the model would take about "),
            std::string::npos)
      << r.err;
  EXPECT_LT(r.max_rss_kb, 1 << 20) << "refused before the importer allocates";
  EXPECT_FALSE(test::file_exists(dir.file("x.png")));
  // Positions, sparse: one of 178,956,970 held in the file.
  const std::string few_held = R"({"componentType": 5126, "count": COUNT, "type": "VEC3", "sparse": {"count": 1,
        "indices": {"bufferView": 0, "componentType": 5121}, "values": {"bufferView": 0}}})";
  const auto positions = [&](const char* count) {
    std::string a = few_held;
    return a.replace(a.find("COUNT"), 5, count);
  };
  const std::string zeros =
      dir.write("zeros.gltf", unheld(positions("178956970"), R"({"attributes": {"POSITION": 1}})"));
  EXPECT_NE(error_loading(zeros).find(zeros + ": meshes[0].primitives[0].attributes.POSITION (accessors[1], "
                                              "178956970 elements): importing"),
            std::string::npos)
      << error_loading(zeros);
  // The same, few enough, loads; an unused huge accessor is not read at all.
  EXPECT_NO_THROW(load_scene(dir.write(
      "few.gltf", unheld(positions("300"), R"({"attributes": {"POSITION": 0}}, {"attributes": {"POSITION": 1}})"))));
  EXPECT_NO_THROW(load_scene(
      dir.write("unused.gltf", unheld(positions("178956970"), R"({"attributes": {"POSITION": 0}})"))));
  // The budget is the importer's (OPSILA_IMPORT_MEMORY): a triangle takes a
  // few KiB to import.
  const std::string tri = dir.write("tri.gltf", gltf("tri.bin"));
  const RunResult small = test::run_program(
      OPSILA_BINARY, {"render", tri, "-o", dir.file("y.png"), "--size", "8x8"}, {{"OPSILA_IMPORT_MEMORY", "4096"}});
  EXPECT_EQ(small.exit_code, 2) << small.err;
  EXPECT_NE(small.err.find("more than the 4096 bytes the model importer may use"), std::string::npos) << small.err;
  EXPECT_EQ(test::run_program(OPSILA_BINARY, {"render", tri, "-o", dir.file("z.png"), "--size", "8x8"},
                              {{"OPSILA_IMPORT_MEMORY", "1048576"}})
                .exit_code,
            0);
}

// The importer reads buffer 0 of a GLB from its BIN chunk whatever the
// buffer's uri says (a file's bytes were drawn from a chunk of zeros), reads
// chunk 1's BIN and ignores any later one, and dropped an image in a view
// of no bytes without a word: each is refused.
TEST(GltfImport, AGlbHoldsBufferZeroInItsOneBinChunk) {
  TempDir dir;
  dir.write("tri.bin", triangle_bytes());
  std::string json = gltf("");
  json.erase(json.find(R"("uri": "", )"), 11);
  json.resize((json.size() + 3) / 4 * 4, ' ');
  EXPECT_EQ(load_scene(dir.write("ok.glb", glb(json, std::uint32_t(json.size()), triangle_bytes()))).num_facets, 1);
  std::string uri = gltf("tri.bin");
  uri.resize((uri.size() + 3) / 4 * 4, ' ');
  const std::string zeros = std::string(36, '\0');
  EXPECT_NE(error_loading(dir.write("uri.glb", glb(uri, std::uint32_t(uri.size()), zeros)))
                .find("uri.glb: buffers[0]: a uri in a GLB file (the importer reads buffer 0 from the GLB's BIN "
                      "chunk whatever the uri names)"),
            std::string::npos);
  const std::string two = glb(json, std::uint32_t(json.size()), zeros) + le32(36) + std::string("BIN\0", 4) +
                          triangle_bytes();
  std::string fixed = two;
  fixed.replace(8, 4, le32(std::uint32_t(two.size())));
  EXPECT_NE(error_loading(dir.write("two.glb", fixed)).find("two.glb: GLB chunk 2: a BIN chunk past chunk 1"),
            std::string::npos)
      << error_loading(dir.file("two.glb"));
  std::string empty = gltf("tri.bin", R"("byteOffset": 0, "byteLength": 0)");
  EXPECT_NE(error_loading(dir.write("empty.gltf", empty))
                .find("empty.gltf: bufferViews[0]: byteLength 0 or none (a buffer view holds at least 1 byte)"),
            std::string::npos);
}

// A triangle bound to a skin of one joint, whose translation an animation
// moves; `uri` is its buffer (empty: a GLB's binary chunk). glTF 2 makes
// inverseBindMatrices optional (identity matrices); Debian's assimp 5.2
// faulted on a skin without them.
// A data URI's base64 is checked whole: the importer decoded a character
// outside the alphabet as some value and rendered other geometry, exit 0.
TEST(GltfImport, ADataUriThatIsNotBase64IsNamed) {
  TempDir dir;
  const std::string prefix = "data:application/octet-stream;base64,";
  const std::string triangle = "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA";  // triangle_bytes()
  EXPECT_EQ(error_loading(dir.write("ok.gltf", gltf(prefix + triangle))), "<no error>");
  std::string starred = triangle;
  starred.replace(16, 4, "****");
  const std::string star = dir.write("star.gltf", gltf(prefix + starred));
  EXPECT_EQ(error_loading(star),
            star + ": buffers[0]: uri: the data URI is not base64 (character 17 of its data is not in the alphabet)");
  const std::string cut = dir.write("cut.gltf", gltf(prefix + triangle.substr(1)));
  EXPECT_NE(error_loading(cut).find("its length is not a multiple of 4"), std::string::npos) << error_loading(cut);
}

// A name holding \u0000 was cut there by the importer: "tri.bin\u0000x"
// read tri.bin, a file the glTF does not name. Refused, with its line (the
// buffers are on line 2).
TEST(GltfImport, ANulInAUriIsRefused) {
  TempDir dir;
  dir.write("tri.bin", triangle_bytes());
  const std::string cut = dir.write("cut.gltf", gltf("tri.bin\\u0000x"));
  EXPECT_EQ(error_loading(cut), cut + ":2: a string may not hold \\u0000 (a NUL)");
  // An escaped backslash before "u0000" is no escape of a NUL.
  const std::string slash = dir.write("slash.gltf", gltf("tri.bin\\\\u0000x"));
  EXPECT_EQ(error_loading(slash).find("a string may not hold"), std::string::npos) << error_loading(slash);
}

// A key given twice: the importer read the first, the checks the last, so a
// bad first value passed them (a bufferView offset near 2^64 made the
// importer read before its buffer); the later one's line is named. And a
// mode past 6, drawn as triangles.
TEST(GltfImport, ARepeatedKeyAndAnUnknownModeAreRefused) {
  TempDir dir;
  dir.write("tri.bin", triangle_bytes());
  const std::string once = gltf("tri.bin");
  EXPECT_EQ(error_loading(dir.write("once.gltf", once)), "<no error>");
  const std::string wrap = R"({"bufferViews": [{"buffer": 0, "byteOffset": 18446744073709551608, "byteLength": 36}],)";
  const std::string twice = dir.write("twice.gltf", wrap + once.substr(1));
  EXPECT_EQ(error_loading(twice), twice + ":3: bufferViews: key given twice (the model importer reads the first, "
                                          "these checks the last: give each key once)");
  std::string moded = once;
  const std::string attributes = R"("POSITION": 0}})";
  moded.replace(moded.find(attributes), attributes.size(), R"("POSITION": 0}, "mode": 4294967296})");
  const std::string mode = dir.write("mode.gltf", moded);
  EXPECT_EQ(error_loading(mode), mode + ": meshes[0].primitives[0]: mode 4294967296 (a glTF primitive's mode is 0 to 6)");
}

// Placements and references the importer takes as they come: a matrix of
// 4 numbers, the zero quaternion (the mesh placed as a point), a material
// index past the end (its message was 'Missing section "materials"').
TEST(GltfImport, MalformedPlacementsAndMaterialsAreNamed) {
  TempDir dir;
  dir.write("tri.bin", triangle_bytes());
  const auto with = [&](const std::string& name, const std::string& from, const std::string& to) {
    std::string text = gltf("tri.bin");
    text.replace(text.find(from), from.size(), to);
    return dir.write(name, text);
  };
  const std::string four = with("four.gltf", R"({"mesh": 0})", R"({"mesh": 0, "matrix": [1, 0, 0, 0]})");
  EXPECT_EQ(error_loading(four), four + ": nodes[0]: 'matrix' is not 16 finite numbers");
  const std::string projective = with("projective.gltf", R"({"mesh": 0})",
                                      R"({"mesh": 0, "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, -1, 0, 0, 0, 0]})");
  EXPECT_EQ(error_loading(projective),
            projective + ": nodes[0]: 'matrix' is not affine (its last row, elements 3, 7, 11, 15, is not 0 0 0 1)");
  const std::string zero = with("zero.gltf", R"({"mesh": 0})", R"({"mesh": 0, "rotation": [0, 0, 0, 0]})");
  EXPECT_EQ(error_loading(zero), zero + ": nodes[0]: 'rotation' is not a unit quaternion (its length is 0.000000)");
  const std::string turned = with("turned.gltf", R"({"mesh": 0})", R"({"mesh": 0, "rotation": [0, 0.7071068, 0, 0.7071068]})");
  EXPECT_EQ(error_loading(turned), "<no error>");
  const std::string past = with("past.gltf", R"({"POSITION": 0})", R"({"POSITION": 0}, "material": 3)");
  EXPECT_EQ(error_loading(past), past + ": meshes[0].primitives[0]: 'material' names no entry of 'materials'");
}

// A node that mirrors its mesh (a negative determinant) turns its winding
// (glTF 2.0, "Transformations"), so that Ng is the mesh's own normal under
// the inverse transpose, as a smooth normal is: the triangle, facing +z in
// its frame, still faces +z mirrored in x and faces -z mirrored in z, as it
// does turned by 180 degrees about y (determinant +1, winding kept). Before,
// a mirrored glass part was drawn inside out.
TEST(GltfImport, AMirroringNodeKeepsTheFacetsFacingOut) {
  TempDir dir;
  dir.write("tri.bin", triangle_bytes());
  std::string text = gltf("tri.bin");
  const std::string one = R"("nodes": [0]}], "nodes": [{"mesh": 0}])";
  ASSERT_NE(text.find(one), std::string::npos);
  text.replace(text.find(one), one.size(),
               R"("nodes": [0, 1, 2, 3]}], "nodes": [{"mesh": 0}, {"mesh": 0, "scale": [-1, 1, 1]},
                  {"mesh": 0, "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, -2, 0, 0, 0, 0, 1]},
                  {"mesh": 0, "rotation": [0, 1, 0, 0]}])");
  const Scene s = load_scene(dir.write("mirrors.gltf", text));
  ASSERT_EQ(s.triangles.size(), 4u);
  const float want[4] = {1, 1, -1, -1};  // the placements in node order
  for (int k = 0; k < 4; ++k) {
    const Triangle& t = s.triangles[k];
    const Vec3 a = t.v1 - t.v0, b = t.v2 - t.v0;
    EXPECT_EQ(a[0] * b[1] - a[1] * b[0], want[k]) << "placement " << k;
  }
}

std::string skinned_bytes() {
  std::string b = triangle_bytes();
  for (int v = 0; v < 3; ++v) b += std::string(8, '\0');  // JOINTS_0: joint 0, four u16
  for (int v = 0; v < 3; ++v) b += f32(1) + f32(0) + f32(0) + f32(0);  // WEIGHTS_0
  b += f32(0) + f32(1);  // key times
  for (float x : {0.f, 0.f, 0.f, 0.f, 2.f, 0.f}) b += f32(x);  // translations
  return b;
}

std::string skinned(const std::string& uri) {
  const std::string buffer = uri.empty() ? "" : R"("uri": ")" + uri + R"(", )";
  return R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0, 1]}],
  "nodes": [{"mesh": 0, "skin": 0}, {"translation": [0, 0, 0]}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "JOINTS_0": 1, "WEIGHTS_0": 2}}]}],
  "skins": [{"joints": [1]}],
  "animations": [{"samplers": [{"input": 3, "output": 4}],
                  "channels": [{"sampler": 0, "target": {"node": 1, "path": "translation"}}]}],
  "buffers": [{)" + buffer + R"("byteLength": 140}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 24},
                  {"buffer": 0, "byteOffset": 60, "byteLength": 48}, {"buffer": 0, "byteOffset": 108, "byteLength": 8},
                  {"buffer": 0, "byteOffset": 116, "byteLength": 24}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
                {"bufferView": 1, "componentType": 5123, "count": 3, "type": "VEC4"},
                {"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC4"},
                {"bufferView": 3, "componentType": 5126, "count": 2, "type": "SCALAR", "min": [0], "max": [1]},
                {"bufferView": 4, "componentType": 5126, "count": 2, "type": "VEC3"}]})";
}

TEST(GltfImport, SkinsAndAnimationsAreNotReadAndTheMeshRendersAsStored) {
  TempDir dir;
  dir.write("tri.bin", triangle_bytes());
  dir.write("skinned.bin", skinned_bytes());
  std::string json = skinned("");
  json.resize((json.size() + 3) / 4 * 4, ' ');
  const std::string plain = dir.write("plain.gltf", gltf("tri.bin"));
  const std::string text = dir.write("skinned.gltf", skinned("skinned.bin"));
  const std::string binary = dir.write("skinned.glb", glb(json, std::uint32_t(json.size()), skinned_bytes()));
  const RunResult first = run_opsila({"render", plain, "-o", dir.file("plain.png"), "--size", "32x24"});
  ASSERT_EQ(first.exit_code, 0) << first.err;
  for (const std::string& model : {text, binary}) {
    SCOPED_TRACE(model);
    const RunResult r = run_opsila({"render", model, "-o", dir.file("skinned.png"), "--size", "32x24"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(test::read_file(dir.file("skinned.png")), test::read_file(dir.file("plain.png")));
  }
  // 2,000 channels sharing one sampler of 10,000 keys: the importer took
  // 490 MB for this 300 KB file, its keys; not read, they take nothing
  // (within 64 MiB of the watchdog's budget, and of the plain triangle's
  // peak: a sanitizer build's own is larger).
  std::string keys;
  for (int k = 0; k < 10000; ++k) keys += f32(float(k));
  keys += std::string(12 * 10000, '\0');
  dir.write("keys.bin", triangle_bytes() + keys);
  std::string nodes = R"({"mesh": 0})", channels, roots = "0";
  for (int n = 1; n <= 2000; ++n) {
    nodes += ", {}";
    roots += ", " + std::to_string(n);
    channels += std::string(n > 1 ? ", " : "") + R"({"sampler": 0, "target": {"node": )" + std::to_string(n) +
                R"(, "path": "translation"}})";
  }
  const std::string animated = dir.write("animated.gltf", R"({"asset": {"version": "2.0"}, "scene": 0,
  "scenes": [{"nodes": [)" + roots + R"(]}], "nodes": [)" + nodes + R"(],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
  "animations": [{"samplers": [{"input": 1, "output": 2}], "channels": [)" + channels + R"(]}],
  "buffers": [{"uri": "keys.bin", "byteLength": 160036}],
  "bufferViews": [{"buffer": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 40000},
                  {"buffer": 0, "byteOffset": 40036, "byteLength": 120000}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
                {"bufferView": 1, "componentType": 5126, "count": 10000, "type": "SCALAR", "min": [0], "max": [9999]},
                {"bufferView": 2, "componentType": 5126, "count": 10000, "type": "VEC3"}]})");
  const RunResult r = test::run_program(OPSILA_BINARY, {"render", animated, "-o", dir.file("a.png"), "--size", "32x24"},
                                        {{"OPSILA_IMPORT_MEMORY", std::to_string(64 << 20)}});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_LT(r.max_rss_kb, first.max_rss_kb + 100 * 1024) << "the animation's keys were read";
}

// One triangle's positions and `indices` (16-bit) after them in tri.bin.
std::string indexed_gltf(TempDir& dir, const std::vector<std::uint16_t>& indices, const std::string& name) {
  std::string bin = triangle_bytes();
  for (std::uint16_t i : indices) bin += std::string{char(i & 0xff), char(i >> 8)};
  dir.write(name + ".bin", bin);
  const std::string n = std::to_string(indices.size()), bytes = std::to_string(2 * indices.size());
  return dir.write(name + ".gltf", R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
  "nodes": [{"mesh": 0}], "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
  "buffers": [{"uri": ")" + name + R"(.bin", "byteLength": )" + std::to_string(bin.size()) + R"(}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                  {"buffer": 0, "byteOffset": 36, "byteLength": )" + bytes + R"(}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0],
                 "max": [1, 1, 0]},
                {"bufferView": 1, "componentType": 5123, "count": )" + n + R"(, "type": "SCALAR"}]})");
}

// The importer drops a face whose indices run past the vertices, and the
// vertices left over from a count that is no multiple of 3, and goes on:
// the render showed less than the file held, with exit 0. Refused; a
// mesh with no face left also says what the importer said.
TEST(GltfImport, IndicesPastTheVerticesAndLeftOverIndicesAreRefused) {
  TempDir dir;
  EXPECT_EQ(error_loading(indexed_gltf(dir, {0, 1, 2, 2, 1, 0}, "ok")), "<no error>");
  const std::string past = indexed_gltf(dir, {0, 1, 2, 0, 1, 9}, "past");
  EXPECT_EQ(error_loading(past), past + ": a mesh primitive's indices name vertices past the end of its attributes "
                                        "(the importer would drop those faces): every index must be below the "
                                        "POSITION accessor's count");
  const std::string all = indexed_gltf(dir, {0, 1, 7}, "all");
  EXPECT_NE(error_loading(all).find("; the importer: Mesh \"meshes[0]\" has no faces"), std::string::npos)
      << error_loading(all);
  const std::string left = indexed_gltf(dir, {0, 1, 2, 0}, "left");
  EXPECT_EQ(error_loading(left), left + ": a triangles primitive's vertex or index count is not a multiple of 3 "
                                        "(the importer would drop the rest)");
}

}  // namespace
}  // namespace opsila
