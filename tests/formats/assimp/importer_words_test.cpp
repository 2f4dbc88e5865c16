// What the importer reads by its own rules, checked first where those rules
// would change the model or crash: numbers its reader would split, the
// base64 of FBX text's embedded files; and its own refusal, which may quote
// the rest of the file, shown as one short line. No OpenCL needed.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>

#include "core/errors.h"
#include "formats/json/scene_file.h"
#include "test_util.h"

namespace opsila {
namespace {

using test::TempDir;

std::string error_loading(const std::string& path) {
  return test::error_of([&] { load_scene(path); });
}

std::string stl_with(const std::string& number) {
  return "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 " + number +
         "\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n";
}

std::string off_with(const std::string& number) {
  return "OFF\n3 1 0\n0 0 " + number + "\n1 0 0\n0 1 0\n3 0 1 2\n";
}

// The importer's number reader stops at the first character it cannot take
// and reads the rest as the next number: '0.5.5' became 0.5 and .5, the
// model silently changed. Whole numbers in every spelling it reads load.
TEST(ImporterWords, NumbersTheReaderWouldSplitAreRefusedWithTheirLine) {
  TempDir dir;
  for (const std::string bad : {"0.5.5", "1-2", "0.4x2", "1,5", "1e", "-", ".", "nanx", "0x10"}) {
    SCOPED_TRACE(bad);
    std::string e = error_loading(dir.write("bad.stl", stl_with(bad)));
    EXPECT_NE(e.find(dir.file("bad.stl") + ":4: STL 'vertex' needs 3 numbers; '" + bad + "' is not one"),
              std::string::npos)
        << e;
    e = error_loading(dir.write("bad.off", off_with(bad)));
    EXPECT_NE(e.find(dir.file("bad.off") + ":3: OFF vertex 1: '" + bad + "' is not a number"), std::string::npos) << e;
  }
  for (const std::string good : {"1e-5", "-.5", "5.", "+1", "1E+05", "0.25e1", "-0"}) {
    SCOPED_TRACE(good);
    EXPECT_EQ(load_scene(dir.write("good.stl", stl_with(good))).num_facets, 1);
    EXPECT_EQ(load_scene(dir.write("good.off", off_with(good))).num_facets, 1);
  }
}

// One byte of an embedded texture's base64 changed (a line break, '!', a
// byte past ASCII, a '=' inside) corrupted the importer's heap and killed
// the process; a byte more or less left a broken texture unsaid.
TEST(ImporterWords, ABrokenEmbeddedFileInFbxTextIsRefusedWithItsLine) {
  const std::string box = "/usr/share/assimp/models/FBX/embedded_ascii/box.FBX";
  if (!std::filesystem::exists(box)) GTEST_SKIP() << "Debian package assimp-testmodels is not installed";
  TempDir dir;
  const std::string file = test::read_file(box);
  const std::size_t first = file.find("\"iVBOR") + 1, at = first + 1000;
  const std::size_t length = file.find('"', first) - first;
  ASSERT_LT(at, file.size());
  const std::string line = ":" + std::to_string(std::count(file.begin(), file.begin() + long(at), '\n') + 1) + ": ";
  const struct {
    std::string bytes, what;
  } cases[] = {
      {file.substr(0, at) + "\n" + file.substr(at + 1), "character 1001, byte 10, is not base64"},
      {file.substr(0, at) + "!" + file.substr(at + 1), "character 1001, '!', is not base64"},
      {file.substr(0, at) + "\xfa" + file.substr(at + 1), "character 1001, byte 250, is not base64"},
      {file.substr(0, at) + "=" + file.substr(at + 1), "character 1001, '=', is not base64"},
      {file.substr(0, at) + file.substr(at + 1),
       "its " + std::to_string(length - 1) + " characters are not whole groups of four"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.what);
    const std::string e = error_loading(dir.write("box.fbx", c.bytes));
    EXPECT_NE(e.find(dir.file("box.fbx") + line + "FBX embedded file (Content): " + c.what), std::string::npos) << e;
  }
  EXPECT_GT(load_scene(dir.write("box.fbx", file)).num_facets, 0);
}

// The importer's own refusal of a bad number quoted the rest of the file
// (here about 60 kB over hundreds of lines) in the message.
TEST(ImporterWords, TheImportersRefusalIsOneShortLine) {
  const std::string duck = "/usr/share/assimp/models/Collada/duck.dae";
  if (!std::filesystem::exists(duck)) GTEST_SKIP() << "Debian package assimp-testmodels is not installed";
  TempDir dir;
  std::string file = test::read_file(duck);
  const std::size_t array = file.find('>', file.find("<float_array")) + 1;
  ASSERT_NE(array, std::string::npos);
  file.insert(array, "b");
  const std::string e = error_loading(dir.write("duck.dae", file));
  EXPECT_EQ(e.rfind(dir.file("duck.dae") + ": the model importer cannot read it: ", 0), 0u) << e;
  EXPECT_NE(e.find("b"), std::string::npos) << e;
  EXPECT_EQ(e.find('\n'), std::string::npos) << e;
  EXPECT_LT(e.size(), dir.file("duck.dae").size() + 300) << e;
  EXPECT_EQ(e.substr(e.size() - 3), "...") << e;
}

// A glTF cut inside a data URI: the JSON reader's message quoted all it had
// read of the string (16 kB here).
TEST(ImporterWords, AJsonErrorInGltfQuotesAShortPrefix) {
  TempDir dir;
  const std::string text = "{\"asset\": {\"version\": \"2.0\"},\n\"buffers\": [{\"uri\": "
                           "\"data:application/octet-stream;base64," + std::string(20000, 'A');
  const std::string e = error_loading(dir.write("cut.gltf", text));
  EXPECT_EQ(e.rfind(dir.file("cut.gltf") + ": not glTF JSON (parse error at line 2", 0), 0u) << e.substr(0, 400);
  EXPECT_LT(e.size(), dir.file("cut.gltf").size() + 300) << e.substr(0, 400);
  EXPECT_EQ(e.substr(e.size() - 4), "...)") << e.substr(0, 400);
}

// The MD5 reader trusts every index: a weight's joint past the joints (a
// joint line missing, or one number changed) freed memory it did not own and
// killed the process. Every count and index is checked first.
TEST(ImporterWords, Md5IndicesTheReaderWouldTrustAreChecked) {
  const std::string cube = "/usr/share/assimp/models/MD5/SimpleCube.md5mesh";
  if (!std::filesystem::exists(cube)) GTEST_SKIP() << "Debian package assimp-testmodels is not installed";
  TempDir dir;
  const std::string file = test::read_file(cube);
  const auto changed = [&](const std::string& from, const std::string& to) {
    const std::size_t at = file.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return file.substr(0, at) + to + file.substr(at + from.size());
  };
  const std::string joint1 = file.substr(file.find("\"joint1\""), file.find('\n', file.find("\"joint1\"")) + 1 -
                                                                   file.find("\"joint1\""));
  const struct {
    std::string bytes, what;
  } cases[] = {
      {changed(joint1, ""), ":58: MD5 weight's joint 2 out of range (2 joints)"},
      {changed("weight 0 1 ", "weight 0 3 "), ":58: MD5 weight's joint 3 out of range (3 joints)"},
      {changed("\"root\" 0 ", "\"root\" 1 "), ":9: MD5 joint parent 1 out of range (1)"},
      {changed("vert 0 ( 0.1875 -0.25 ) 0 2", "vert 0 ( 0.1875 -0.25 ) 15 2"),
       ":18: MD5 vert's weights 15 + 2 run past the mesh's 16 weights"},
      {changed("vert 0 (", "vert 24 ("), ":18: MD5 vert index 24 out of range (24)"},
      {changed("vert 0 ( 0.1875 -0.25 ) 0 2", "vert 0 ( 0.1875 -0.25 ) -1 2"),
       ":18: MD5 vert's first weight '-1' is not a whole number"},
      {changed("tri 0 ", "tri 0 24 "), ":44: MD5 tri's vertex 24 out of range (24 vertices)"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.what);
    const std::string e = error_loading(dir.write("cube.md5mesh", c.bytes));
    EXPECT_NE(e.find(dir.file("cube.md5mesh") + c.what), std::string::npos) << e;
  }
  EXPECT_GT(load_scene(dir.write("cube.md5mesh", file)).num_facets, 0);
}

// A motion-capture file holds bones and no surfaces; the importer draws
// stand-in shapes for them in a colourless material, which rendered as a
// black image with exit 0.
TEST(ImporterWords, ASkeletonWithoutSurfacesIsNamedSo) {
  TempDir dir;
  const std::string bvh =
      "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation "
      "Yrotation\n  JOINT Chest\n  {\n    OFFSET 0 5 0\n    CHANNELS 3 Zrotation Xrotation Yrotation\n"
      "    End Site\n    {\n      OFFSET 0 5 0\n    }\n  }\n}\nMOTION\nFrames: 1\nFrame Time: 0.033\n"
      "0 0 0 0 0 0 0 0 0\n";
  const std::string e = error_loading(dir.write("walk.bvh", bvh));
  EXPECT_NE(e.find(dir.file("walk.bvh") + ": a skeleton (motion capture), no surfaces"), std::string::npos) << e;
}

// The importer's own refusal was shown bare ("file: XFile is too small."),
// as if opsila had said it: it is now told as the importer's.
TEST(ImporterWords, TheImportersOwnRefusalIsToldAsItsOwn) {
  TempDir dir;
  const std::string e = error_loading(dir.write("tiny.x", "xof 0303txt"));
  EXPECT_EQ(e.rfind(dir.file("tiny.x") + ": the model importer cannot read it: ", 0), 0u) << e;
  EXPECT_EQ(e.find('\n'), std::string::npos) << e;
}

}  // namespace
}  // namespace opsila
