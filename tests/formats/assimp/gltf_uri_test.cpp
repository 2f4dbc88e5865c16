// glTF names its files by URI, percent-encoded (gltf_uris.h): a name's
// decoding is the file where it exists, else the name as written.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "formats/assimp/gltf_uris.h"
#include "formats/json/scene_file.h"
#include "gltf_test_files.h"
#include "test_util.h"

namespace opsila {
namespace {

namespace fs = std::filesystem;
using namespace test;  // the helpers of test_util.h and gltf_test_files.h

TEST(GltfUris, EscapesAreDecodedWhenWhole) {
  EXPECT_EQ(percent_decoded("Brick%20Wall%2fa%C3%A9.png").value(), "Brick Wall/a\xC3\xA9.png");
  EXPECT_FALSE(percent_decoded("plain name.bin").has_value()) << "nothing to decode";
  EXPECT_FALSE(percent_decoded("50%.bin").has_value()) << "not an escape";
  EXPECT_FALSE(percent_decoded("a%4").has_value()) << "cut short";
  EXPECT_FALSE(percent_decoded("a%g0").has_value()) << "not hex";
  EXPECT_FALSE(percent_decoded("a%00b").has_value()) << "a NUL would cut the name";
}

TEST(GltfUris, ABufferNamedByItsEncodingIsRead) {
  TempDir dir;
  dir.write("tri angle.bin", triangle_bytes());
  const std::string encoded = dir.write("encoded.gltf", gltf("tri%20angle.bin"));
  EXPECT_EQ(load_scene(encoded).triangles.size(), 1u);
  // The file as written when only it exists ("50%.bin" is no escape; "a%41.bin" names itself here).
  dir.write("50%.bin", triangle_bytes());
  EXPECT_EQ(load_scene(dir.write("percent.gltf", gltf("50%.bin"))).triangles.size(), 1u);
  dir.write("a%41.bin", triangle_bytes());
  EXPECT_EQ(load_scene(dir.write("literal.gltf", gltf("a%41.bin"))).triangles.size(), 1u);
  // Neither: the message quotes the uri as written.
  const std::string missing = dir.write("missing.gltf", gltf("no%20such.bin"));
  const RunResult r = run_opsila({"render", missing, "-o", dir.file("x.png"), "--size", "8x8"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find(missing + ": buffers[0]: uri 'no%20such.bin': "), std::string::npos) << r.err;
  EXPECT_FALSE(file_exists(dir.file("x.png")));
  // Both: the decoding is the file (a 35-byte decoy as written would be refused as short).
  dir.write("b%20c.bin", triangle_bytes().substr(0, 35));
  dir.write("b c.bin", triangle_bytes());
  EXPECT_EQ(load_scene(dir.write("both.gltf", gltf("b%20c.bin"))).triangles.size(), 1u);
}

// Exporters encode an image's name as a URI: the map is found, and the
// render is the same bytes as the model with plain names.
TEST(GltfUris, AnImageNamedByItsEncodingIsItsTexture) {
  const fs::path model = "/usr/share/assimp/models/glTF2/BoxTextured-glTF";
  if (!fs::exists(model)) GTEST_SKIP() << "Debian package assimp-testmodels is not installed";
  TempDir dir;
  fs::copy_file(model / "BoxTextured0.bin", dir.file("Box Textured0.bin"));
  fs::copy_file(model / "CesiumLogoFlat.png", dir.file("Cesium Logo.png"));
  std::stringstream text;
  text << std::ifstream(model / "BoxTextured.gltf").rdbuf();
  std::string json = text.str();
  for (const auto& [plain, encoded] : {std::pair<std::string, std::string>{"BoxTextured0.bin", "Box%20Textured0.bin"},
                                       {"CesiumLogoFlat.png", "Cesium%20Logo.png"}}) {
    const std::size_t at = json.find("\"" + plain + "\"");
    ASSERT_NE(at, std::string::npos) << plain;
    json.replace(at + 1, plain.size(), encoded);
  }
  const std::string encoded = dir.write("encoded.gltf", json);
  const Scene scene = load_scene(encoded);
  ASSERT_EQ(scene.textures.size(), 1u);
  EXPECT_EQ(fs::path(scene.textures[0].path).filename(), "Cesium Logo.png");
  const RunResult a = run_opsila({"render", encoded, "-o", dir.file("a.png"), "--size", "32x24"});
  const RunResult b =
      run_opsila({"render", (model / "BoxTextured.gltf").string(), "-o", dir.file("b.png"), "--size", "32x24"});
  ASSERT_EQ(a.exit_code, 0) << a.err;
  ASSERT_EQ(b.exit_code, 0) << b.err;
  EXPECT_EQ(a.err.find("warning"), std::string::npos) << a.err;
  EXPECT_EQ(read_file(dir.file("a.png")), read_file(dir.file("b.png")));
}

}  // namespace
}  // namespace opsila
