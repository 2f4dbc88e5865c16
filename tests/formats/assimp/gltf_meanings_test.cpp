// What a glTF 2 states that the importer would ignore or misread
// (gltf_meanings.cpp): refused before the import, naming the key. Each had
// rendered something else than the file says, with exit 0, or failed in
// the importer's words.
#include <gtest/gtest.h>

#include <string>

#include <nlohmann/json.hpp>

#include "formats/json/scene_file.h"
#include "gltf_test_files.h"
#include "test_util.h"

namespace opsila {
namespace {

using namespace test;
using Json = nlohmann::json;

// One triangle (tri.bin), a material with a base colour, and a second
// accessor (the triangle's normals' place) for the attribute checks.
Json triangle() {
  return Json::parse(R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
    "nodes": [{"mesh": 0}], "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "material": 0}]}],
    "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [1, 0.5, 0, 1]}}],
    "buffers": [{"uri": "tri.bin", "byteLength": 36}],
    "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}],
    "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0],
                   "max": [1, 1, 0]}]})");
}

class GltfMeanings : public ::testing::Test {
 protected:
  void SetUp() override { dir.write("tri.bin", triangle_bytes()); }
  // The error loading `g` ("<no error>" when it loads).
  std::string error(const Json& g) {
    const std::string path = dir.write("m.gltf", g.dump());
    const std::string e = error_of([&] { load_scene(path); });
    return e.rfind(path + ": ", 0) == 0 ? e.substr(path.size() + 2) : e;
  }
  TempDir dir;
};

TEST_F(GltfMeanings, ASoundFileLoads) { EXPECT_EQ(error(triangle()), "<no error>"); }

TEST_F(GltfMeanings, ARequiredExtensionTheImporterDoesNotReadIsRefused) {
  Json g = triangle();
  g["extensionsRequired"] = {"KHR_materials_emissive_strength", "KHR_draco_mesh_compression", "EXT_mesh_gpu_instancing"};
  EXPECT_EQ(error(g), "extensionsRequired[2]: 'EXT_mesh_gpu_instancing' is required, and the model importer does "
                      "not read it (what it changes would be lost)");
  g["extensionsRequired"] = {"KHR_materials_emissive_strength", "KHR_texture_transform"};
  EXPECT_EQ(error(g), "<no error>") << "shading extensions and what the importer reads";
  g["asset"]["version"] = "3.0";
  EXPECT_EQ(error(g), "asset.version: '3.0' (glTF 1.x and 2.x are read)");
}

TEST_F(GltfMeanings, PositionsAndNormalsAreFloatTriples) {
  Json g = triangle();
  g["accessors"][0]["type"] = "VEC2";
  EXPECT_NE(error(g).find("meshes[0].primitives[0].attributes.POSITION: accessor 0 is \"VEC2\" of componentType "
                          "5126; the model importer reads positions and normals as float VEC3"),
            std::string::npos)
      << error(g);
  g = triangle();
  g["accessors"][0]["componentType"] = 5122;  // KHR_mesh_quantization's shorts
  EXPECT_NE(error(g).find("is \"VEC3\" of componentType 5122"), std::string::npos) << error(g);
}

// The scene to show and the buffers' files are named by their keys: the
// importer had said "No scene", and a missing buffer file was named alone.
TEST_F(GltfMeanings, TheSceneAndTheBufferFilesAreNamedByTheirKeys) {
  Json g = triangle();
  g["scene"] = 1;
  EXPECT_EQ(error(g), "scene: '1' is not the index of one of its 1 scene(s)");
  g["scene"] = "one";
  EXPECT_EQ(error(g), "scene: '\"one\"' is not the index of one of its 1 scene(s)");
  g.erase("scene");
  EXPECT_EQ(error(g), "<no error>") << "without 'scene', the first";
  g["scenes"] = Json::array();
  EXPECT_EQ(error(g), "scenes: none: nothing places a mesh (a glTF shows the nodes of a scene)");
  g = triangle();
  g["buffers"][0]["uri"] = "gone.bin";
  EXPECT_EQ(error(g), "buffers[0]: uri 'gone.bin': " + dir.path() + "/gone.bin: cannot open: No such file or directory");
}

TEST_F(GltfMeanings, BaseColoursAndTextureTransformsHoldTheirNumbers) {
  for (const Json& bad : {Json::parse("[-1, 0, 0, 1]"), Json::parse("[1, 0, 0]"), Json::parse("[1e39, 0, 0, 1]"),
                          Json("red")}) {
    Json g = triangle();
    g["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"] = bad;
    EXPECT_EQ(error(g), "materials[0].pbrMetallicRoughness.baseColorFactor: expected 4 numbers from 0 to 1, not " +
                            bad.dump());
  }
  Json g = triangle();
  g["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = {
      {"index", 0}, {"extensions", {{"KHR_texture_transform", {{"offset", {0.5}}}}}}};
  EXPECT_EQ(error(g), "materials[0].pbrMetallicRoughness.baseColorTexture.extensions.KHR_texture_transform.offset: "
                      "expected 2 numbers, not [0.5]");
}

// The importer appends its stand-in for "no material" after a glTF 2's
// own, unnamed like them: the file's are used as given, black included
// (which had been taken for the stand-in and drawn in the default grey).
TEST_F(GltfMeanings, TheFilesOwnUnnamedMaterialsAreUsedWhateverTheirColour) {
  for (double grey : {0.0, 0.1, 1.0}) {
    SCOPED_TRACE(grey);
    Json g = triangle();
    g["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"] = {grey, grey, grey, 1};
    const Scene s = load_scene(dir.write("grey.gltf", g.dump()));
    ASSERT_EQ(s.triangles.size(), 1u);
    const MaterialDesc& m = s.materials.at(std::size_t(s.triangles[0].material));
    EXPECT_NE(s.triangles[0].material, 0);
    EXPECT_FLOAT_EQ(m.kd[0], static_cast<float>(grey));
  }
  Json none = triangle();
  none.erase("materials");
  none["meshes"][0]["primitives"][0].erase("material");
  const Scene s = load_scene(dir.write("none.gltf", none.dump()));
  EXPECT_EQ(s.triangles.at(0).material, 0) << "a primitive without a material takes the default";
}

// A reference past its collection, or no index at all: the importer named
// only the collection ("Array index 1 is out of bounds (1) for "meshes"")
// or a missing section.
TEST_F(GltfMeanings, AReferenceIsTheIndexOfAnEntryNamedByItsKey) {
  const auto with = [](const char* pointer, const Json& value) {
    Json g = triangle();
    g["textures"] = Json::parse(R"([{"source": 0}])");
    g["images"] = Json::parse(R"([{"uri": "missing.png"}])");
    g[Json::json_pointer(pointer)] = value;
    return g;
  };
  const struct {
    const char* pointer;
    Json value;
    std::string what;
  } cases[] = {
      {"/nodes/0/mesh", 1, "nodes[0].mesh: '1' is not the index of one of its 1 'meshes' entries"},
      {"/nodes/0/mesh", -1, "nodes[0].mesh: '-1' is not the index of one of its 1 'meshes' entries"},
      {"/scenes/0/nodes", Json::array({5}), "scenes[0].nodes[0]: '5' is not the index of one of its 1 'nodes'"},
      {"/materials/0/pbrMetallicRoughness/baseColorTexture", Json::parse(R"({"index": 3})"),
       "materials[0].pbrMetallicRoughness.baseColorTexture.index: '3' is not the index of one of its 1 'textures'"},
      {"/textures/0/source", 5, "textures[0].source: '5' is not the index of one of its 1 'images' entries"},
      {"/textures/0/sampler", 0, "textures[0].sampler: '0' is not the index of one of its 0 'samplers' entries"},
      {"/nodes/0/camera", "a", "nodes[0].camera: '\"a\"' is not the index of one of its 0 'cameras' entries"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.what);
    EXPECT_EQ(error(with(c.pointer, c.value)).substr(0, c.what.size()), c.what);
  }
}

}  // namespace
}  // namespace opsila
