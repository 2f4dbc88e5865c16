// Hostile input: memory and time bounded by what the input asks for, limits
// checked before anything is built, one FILE:LINE: message per refusal.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "scene/scene.h"
#include "formats/obj/obj_loader.h"
#include "formats/json/scene_file.h"
#include "test_util.h"

namespace opsila {
namespace {

using test::RunResult;
using test::TempDir;
using test::run_opsila;
namespace fs = std::filesystem;

std::string error_of(const std::string& text, std::size_t max_triangles = kMaxTriangles) {
  try {
    load_scene_from_string(text, "s.json", "", max_triangles);
  } catch (const InputError& e) {
    return e.what();
  }
  return "<no error>";
}

const char* kSphere = R"({"type": "sphere", "center": [0, 0, 0], "radius": 1})";

// A scene that fails only after everything has been read (no facets).
std::string long_key_scene(std::size_t key_bytes, std::size_t numbers) {
  std::string text = "{\"" + std::string(key_bytes, 'k') + "\": [";
  for (std::size_t i = 0; i < numbers; ++i) text += i ? ",1" : "1";
  return text + "],\n\"objects\": []}";
}

// Peak memory of the opsila process, generous for sanitizer builds: the
// point is a few hundred MB at most, never gigabytes.
constexpr long kFewHundredMB = 400L * 1024;

TEST(HardInput, LongKeyOverALongArrayCostsLittleMemory) {
  TempDir dir;
  const std::string scene = dir.write("long.json", long_key_scene(500000, 250000));
  const RunResult r = run_opsila({"render", scene, "-o", dir.file("o.png"), "--reference"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_LT(r.max_rss_kb, kFewHundredMB);
  // The warning quotes a short prefix of the key, not the key.
  ASSERT_NE(r.err.find("unknown key 'kkkk"), std::string::npos) << r.err.substr(0, 400);
  std::size_t longest = 0, start = 0;
  for (std::size_t end; (end = r.err.find('\n', start)) != std::string::npos; start = end + 1)
    longest = std::max(longest, end - start);
  EXPECT_LT(longest, 400u);
  EXPECT_EQ(r.error_lines().size(), 1u);
  EXPECT_NE(r.err.find("no facets"), std::string::npos);
}

TEST(HardInput, LinesOfDeepKeysAfterLongArraysAreExact) {
  std::string text = "{\"pad\": [";
  for (int i = 0; i < 1000; ++i) text += i ? ",\n0" : "0";
  text += "],\n\"objects\": [\n" + std::string(kSphere) + ",\n{\"type\": \"box\",\n\"min\": [0,0,0],\n"
          "\"max\": [1, \"x\", 1]}]}";
  const std::string msg = error_of(text);
  EXPECT_NE(msg.find("s.json:1005: objects[1].max[1]: expected a number"), std::string::npos) << msg;
}

TEST(HardInput, ErrorMessagesQuoteShortPrefixes) {
  const std::string name(100000, 'x');
  for (const std::string& text :
       {"{\"objects\": [{\"type\": \"" + name + "\"}]}",
        "{\"materials\": {\"" + name + "\": {\"Kd\": -1}}, \"objects\": []}",
        "{\"objects\": [\"" + name + "\"x]}", "{\"objects\": [1e" + std::string(5000, '9') + "]}",
        "{\"objects\": [" + std::string(kSphere) + "]} " + name}) {
    const std::string msg = error_of(text);
    EXPECT_LT(msg.size(), 400u) << msg.substr(0, 400);
    EXPECT_EQ(msg.rfind("s.json:1:", 0), 0u) << msg.substr(0, 200);
    EXPECT_EQ(msg.find("json.exception"), std::string::npos) << msg.substr(0, 200);
  }
}

TEST(HardInput, LibraryTextNeverReachesTheUser) {
  const std::string msg = error_of("{\n\"depth\": 1e999, \"objects\": []}");
  EXPECT_EQ(msg.rfind("s.json:2:", 0), 0u) << msg;
  EXPECT_NE(msg.find("out of range"), std::string::npos) << msg;
  EXPECT_EQ(msg.find("json.exception"), std::string::npos) << msg;
}

TEST(HardInput, BytesAfterTheDocumentAreAnError) {
  const std::string scene = "{\"objects\": [" + std::string(kSphere) + "]}";
  EXPECT_EQ(error_of(scene), "<no error>");
  const std::string nul = error_of(scene + std::string("\n\0garbage", 9));
  EXPECT_EQ(nul.rfind("s.json:2:", 0), 0u) << nul;
  EXPECT_NE(nul.find("NUL"), std::string::npos) << nul;
  EXPECT_EQ(error_of(scene + "\n{}").rfind("s.json:2:", 0), 0u);
  EXPECT_EQ(error_of(scene + " x").rfind("s.json:1:", 0), 0u);
}

// A file of a format the importer does not read (VRML, JT) went to the JSON
// reader, which named its first byte; it is named as no scene and no model.
// A scene under any other name still reads.
TEST(HardInput, AFileThatIsNoSceneAndNoModelFormatIsNamedSo) {
  TempDir dir;
  const std::string scene = "\xEF\xBB\xBF \n{\"objects\": [" + std::string(kSphere) + "]}";
  EXPECT_EQ(load_scene(dir.write("s.scene", scene)).num_facets, load_scene(dir.write("s.json", scene)).num_facets);
  EXPECT_GT(load_scene(dir.write("noext", scene)).num_facets, 0);
  const std::pair<const char*, std::string> cases[] = {
      {"m.wrl", "#VRML V2.0 utf8\n"}, {"m.jt", std::string("Version 8.1 JT\0\0", 17)}, {"m", "solid\n"}};
  for (const auto& [name, bytes] : cases) {
    const std::string e = test::error_of([&] { load_scene(dir.write(name, bytes)); });
    const std::string ext = fs::path(name).extension().string();
    EXPECT_EQ(e, dir.file(name) + ": not a JSON scene (it does not start with '{'), and " +
                     (ext.empty() ? "without an extension it is no model" : "'" + ext + "' is no model format") +
                     " the importer reads (see scenes/FORMAT.md)");
  }
}

TEST(HardInput, OversizedFilesAreRefusedBeforeTheyAreRead) {
  TempDir dir;
  // Sparse files: gigabytes on paper, nothing on disk.
  const auto sparse = [&](const std::string& name, off_t size) {
    const std::string path = dir.write(name, "");
    EXPECT_EQ(::truncate(path.c_str(), size), 0);
    return path;
  };
  const std::string json = sparse("huge.json", off_t(2) << 30);
  RunResult r = run_opsila({"render", json, "-o", dir.file("o.png"), "--reference"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("too large"), std::string::npos) << r.err;
  EXPECT_LT(r.max_rss_kb, kFewHundredMB);
  // Within the OBJ size limit, but binary: refused at its first bytes.
  const std::string obj = sparse("zeros.obj", (off_t(2) << 30) - 1);
  r = run_opsila({"render", obj, "-o", dir.file("o.png"), "--reference"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("zeros.obj:1: NUL byte"), std::string::npos) << r.err;
  EXPECT_LT(r.max_rss_kb, kFewHundredMB);
  EXPECT_EQ(r.error_lines().size(), 1u);
}

TEST(HardInput, TotalGeometryIsCheckedBeforeAnythingIsBuilt) {
  // Each terrain is within the limit on its own; the three together are not
  // (2600 MiB hold 20.5 million triangles, the three 24 million).
  const std::string terrain = R"({"type": "terrain", "size": [10, 10], "quads": 2000})";
  TempDir dir;
  const std::string scene =
      dir.write("three.json", "{\"objects\": [\n" + terrain + ",\n" + terrain + ",\n" + terrain + "]}");
  const RunResult r =
      run_opsila({"render", scene, "-o", dir.file("o.png"), "--reference", "--host-memory", "2600M"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("three.json:4: objects[2]: would make 8000000 more triangles"), std::string::npos)
      << r.err;
  EXPECT_LT(r.max_rss_kb, kFewHundredMB);  // 16 million triangles were not built
  // Generators are counted the same way, whatever comes first.
  const std::string boxes =
      R"({"type": "scatter", "count": 1000000, "shapes": ["box"], "min": [0,0,0], "max": [9,9,9]})";
  const std::string msg = error_of("{\"objects\": [" + terrain + ",\n" + boxes + "]}", std::size_t(1) << 24);
  EXPECT_NE(msg.find("s.json:2: objects[1]: would make 12000000 more triangles"), std::string::npos) << msg;
}

TEST(HardInput, ManyKeysInOneObjectAreRefusedBeforeParsing) {
  std::string keys;
  for (int i = 0; i < 1025; ++i) keys += "\"k" + std::to_string(i) + "\": 0,\n";
  const std::string msg = error_of("{\"materials\": {\"m\": {\n" + keys + "\"Kd\": 1}}, \"objects\": []}");
  EXPECT_NE(msg.find("s.json:1026: more than 1024 keys in one object"), std::string::npos) << msg;
}

TEST(HardInput, GeneratorItemLimit) {
  const std::string msg = error_of(
      R"({"objects": [{"type": "scatter", "count": 1000001, "min": [0,0,0], "max": [1,1,1]}]})");
  EXPECT_NE(msg.find("objects[0].count: must be in 1..1000000"), std::string::npos) << msg;
}

TEST(HardInput, ImageSizeLimitIsTheRenderersAndNamesTheKey) {
  const std::string sphere = std::string(kSphere);
  EXPECT_EQ(error_of("{\"image\": {\"width\": 16384, \"height\": 16}, \"objects\": [" + sphere + "]}"),
            "<no error>");
  std::string msg = error_of("{\"image\": {\"width\": 16385, \"height\": 16}, \"objects\": [" + sphere + "]}");
  EXPECT_NE(msg.find("s.json:1: image.width: must be in 1..16384, not 16385"), std::string::npos) << msg;
  // A whole number is named as written, not rounded to nine digits.
  msg = error_of("{\"image\": {\"width\": 2147483648, \"height\": 16}, \"objects\": [" + sphere + "]}");
  EXPECT_NE(msg.find("image.width: must be in 1..16384, not 2147483648"), std::string::npos) << msg;
  msg = error_of("{\"image\":\n{\"size\": [16384, 16384]}, \"objects\": [" + sphere + "]}");
  EXPECT_NE(msg.find("s.json:2: image.size: 16384 x 16384 pixels; at most 67108864"), std::string::npos) << msg;
}

TEST(HardInput, UnknownMaterialIsAWarningAndTheDefault) {
  const Scene s = load_scene_from_string(
      R"({"materials": {"red": {"Kd": [1, 0, 0]}}, "objects": [{"type": "box", "min": [0,0,0],
          "max": [1,1,1], "material": "gold"}]})",
      "s.json", "");
  ASSERT_FALSE(s.triangles.empty());
  EXPECT_EQ(s.triangles[0].material, 0);
  ASSERT_EQ(s.warnings.size(), 1u);
  EXPECT_NE(s.warnings[0].find("s.json:2: objects[0].material: unknown material 'gold' (defined: red)"),
            std::string::npos)
      << s.warnings[0];
}

// A polygon of zero area is a degenerate facet, as in an OBJ: one warning,
// not drawn, its id kept (the next object's facet is 2, not 1).
TEST(HardInput, ZeroAreaPolygonIsAWarningAndKeepsItsId) {
  const Scene s = load_scene_from_string(
      R"({"objects": [{"type": "polygon", "vertices": [[0,0,0], [1,0,0], [1,1,0]]},
          {"type": "polygon", "vertices": [[0,0,0], [1,1,1], [2,2,2]]},
          {"type": "polygon", "vertices": [[0,0,1], [1,0,1], [1,1,1]]}]})",
      "s.json", "");
  ASSERT_EQ(s.triangles.size(), 2u);
  EXPECT_EQ(s.triangles[0].facet_id, 0);
  EXPECT_EQ(s.triangles[1].facet_id, 2);
  EXPECT_EQ(s.triangles[1].object_id, 2);
  EXPECT_EQ(s.num_facets, 3);
  ASSERT_EQ(s.warnings.size(), 1u);
  EXPECT_NE(s.warnings[0].find("s.json:2: objects[1].vertices: the polygon has zero area"), std::string::npos)
      << s.warnings[0];
}

TEST(HardInput, WarningsBeforeAnErrorAreStillPrinted) {
  TempDir dir;
  const std::string scene = dir.write("typo.json", "{\"objcts\": [" + std::string(kSphere) + "]}");
  const RunResult r = run_opsila({"render", scene, "-o", dir.file("o.png"), "--reference"});
  EXPECT_EQ(r.exit_code, 2);
  const std::size_t warning = r.err.find("warning: " + scene + ":1: objcts: unknown key 'objcts'");
  const std::size_t error = r.err.find("error: " + scene + ":1: objects: no facets");
  EXPECT_NE(warning, std::string::npos) << r.err;
  EXPECT_NE(error, std::string::npos) << r.err;
  EXPECT_LT(warning, error);
  EXPECT_TRUE(test::TempDir::list(dir.path()) == (std::vector<std::string>{"typo.json"}));
}

TEST(HardInput, NegativeNsAndColoursAreRefusedByEveryReader) {
  std::vector<std::string> warnings;
  const auto mtl_error = [&](const std::string& text) {
    try {
      parse_mtl(text, "m.mtl", warnings);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("<no error>");
  };
  EXPECT_EQ(mtl_error("newmtl a\nNs 0\nKd 0 0.5 1\n"), "<no error>");
  EXPECT_NE(mtl_error("newmtl a\nNs -1\n").find("m.mtl:2: 'Ns' must not be negative"), std::string::npos);
  EXPECT_NE(mtl_error("newmtl a\n\nKd 1 -0.5 1\n").find("m.mtl:3: 'Kd' must not be negative"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"materials": {"m": {"Ns": -1}}, "objects": []})").find("materials.m.Ns: must not be negative"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"materials": {"m": {"Tf": [0, -1, 0]}}, "objects": []})").find("materials.m.Tf"),
            std::string::npos);
}

// The hit order's limits (docs/CONTRACT.md, Limits) are met where the
// reader still knows the file, the line and the key.
TEST(HardInput, HitOrderLimitsNameTheLineAndKey) {
  std::string ring;  // a polygon of 65,539 corners: 65,537 fan triangles
  for (int k = 0; k < 65539; ++k) ring += std::string(k ? "," : "") + "[" + std::to_string(k % 7) + ",1," + std::to_string(k % 5) + "]";
  std::string msg = error_of("{\"objects\": [{\"type\": \"polygon\", \"vertices\": [" + ring + "]}]}");
  EXPECT_NE(msg.find("s.json:1: objects[0].vertices: the facet fans into 65537 triangles, more than 65536"),
            std::string::npos) << msg.substr(0, 200);
  std::string mats;  // 65,536 inline materials and the default: one too many
  for (int k = 0; k < 65536; ++k) mats += std::string(k ? "," : "") + "{\"Kd\": 0.5}";
  msg = error_of(R"({"objects": [{"type": "scatter", "min": [0,0,0], "max": [1,1,1], "count": 2, "materials": [)" +
                 mats + "]}]}");
  EXPECT_NE(msg.find("s.json:1: objects[0].materials[65535]: more than 65536 materials"), std::string::npos)
      << msg.substr(0, 200);

  std::string obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf";
  for (int k = 0; k < 65539; ++k) obj += " " + std::to_string(1 + k % 3);
  try {
    load_obj_from_string(obj + "\n", "m.obj", "", ObjChunking{1024, 2});  // chunks: the error is still its line
    ADD_FAILURE() << "a fan of 65,537 triangles was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("m.obj:5: 'f' line of 65539 corners: the facet fans into 65537"),
              std::string::npos) << e.what();
  }
  std::string mtl;
  for (int k = 0; k < 65536; ++k) mtl += "newmtl m" + std::to_string(k) + "\nKd 1 1 1\n";
  std::vector<std::string> warnings;
  try {
    parse_mtl(mtl, "m.mtl", warnings);
    ADD_FAILURE() << "65,537 materials were read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("m.mtl:131071: 'newmtl': more than 65536 materials"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace opsila
