// Models through the Open Asset Import Library: CONTRACT's ids (mesh index,
// running face index), materials, texture maps, framing, and one clear
// "FILE: problem" for a broken file of every format. No OpenCL needed.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "formats/assimp/model_import.h"
#include "formats/json/scene_file.h"
#include "test_util.h"

namespace opsila {
namespace {

namespace fs = std::filesystem;

const fs::path kModels = "/usr/share/assimp/models";

#define REQUIRE_TEST_MODELS()                                                                    \
  if (!fs::is_directory(kModels)) GTEST_SKIP() << "Debian package assimp-testmodels is not installed " \
                                                  "(tools/setup.sh installs it)"

std::string error_of(const std::string& path) {
  return test::error_of([&] { load_scene(path); });
}

void expect_framed(const Scene& s) {
  Vec3 lo, hi;
  s.bounds(lo, hi);
  EXPECT_FALSE(s.has_camera);
  EXPECT_FALSE(s.has_lights);
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(s.camera.look_at[a], 0.5f * (lo[a] + hi[a]), 1e-3f * (hi[a] - lo[a]) + 1e-6f);
    EXPECT_TRUE(std::isfinite(s.camera.eye[a]));
  }
  // Outside the box (on the +x, +y, +z side, as CONTRACT's framing puts it).
  EXPECT_GT(s.camera.eye[2], hi[2]);
}

TEST(ModelImport, HandWrittenPlyFansPolygonsAndKeepsFaceIds) {
  test::TempDir dir;
  const std::string ply = dir.write("quad.ply",
                                    "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\n"
                                    "property float z\nelement face 2\nproperty list uchar int vertex_indices\n"
                                    "end_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 2 1\n4 0 1 2 3\n3 1 4 2\n");
  ASSERT_TRUE(is_imported_model(ply));
  const Scene s = load_scene(ply);
  ASSERT_EQ(s.triangles.size(), 3u);  // the quad is fanned: (0 1 2), (0 2 3)
  EXPECT_EQ(s.num_facets, 2);
  EXPECT_EQ(s.num_objects, 1);
  EXPECT_EQ(s.triangles[0].facet_id, 0);
  EXPECT_EQ(s.triangles[1].facet_id, 0);
  EXPECT_EQ(s.triangles[2].facet_id, 1);
  EXPECT_EQ(s.triangles[1].v0, (Vec3{0, 0, 0}));
  EXPECT_EQ(s.triangles[1].v2, (Vec3{0, 1, 0}));
  // A PLY has no material: the importer's stand-in is CONTRACT's default.
  for (const Triangle& t : s.triangles) EXPECT_EQ(t.material, 0);
  EXPECT_EQ(s.materials[0].illum, 2);
  EXPECT_FLOAT_EQ(s.materials[0].kd[1], 0.8f);
  expect_framed(s);
}

TEST(ModelImport, TestModelsOfSeveralFormats) {
  REQUIRE_TEST_MODELS();
  struct Case {
    const char* file;
    int objects, facets;
  };
  const Case cases[] = {
      {"PLY/cube.ply", 1, 6},
      {"STL/Spider_binary.stl", 1, 1368},
      {"3DS/cubes_with_alpha.3DS", 5, 60},
      {"glTF2/BoxTextured-glTF/BoxTextured.gltf", 1, 12},
      {"glTF2/BoxTextured-glTF-Binary/BoxTextured.glb", 1, 12},
      {"Collada/duck.dae", 1, 2144},
      {"FBX/box.fbx", 1, 12},  // the file stores triangles
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.file);
    const fs::path path = kModels / c.file;
    if (!fs::exists(path)) {
      ADD_FAILURE() << "missing test model";
      continue;
    }
    Scene s;
    ASSERT_NO_THROW(s = load_scene(path.string()));
    EXPECT_EQ(s.num_objects, c.objects);
    EXPECT_EQ(s.num_facets, c.facets);
    // Object ids are mesh indices; facet ids run over the meshes in order,
    // so each object's facets form one range, objects in order.
    int last_object = 0, last_facet = -1;
    std::set<int> objects;
    for (const Triangle& t : s.triangles) {
      EXPECT_GE(t.object_id, 0);
      EXPECT_LT(t.object_id, s.num_objects);
      EXPECT_GE(t.facet_id, 0);
      EXPECT_LT(t.facet_id, s.num_facets);
      EXPECT_GE(t.object_id, last_object);
      EXPECT_GE(t.facet_id, last_facet);
      last_object = t.object_id;
      last_facet = t.facet_id;
      objects.insert(t.object_id);
    }
    EXPECT_EQ(static_cast<int>(objects.size()), c.objects);
    expect_framed(s);
  }
}

// A text STL makes a mesh of every solid; an empty one keeps its place in
// the list, so the solids after it keep their object ids (CONTRACT: the mesh's
// index), and the file renders (the importer's validation refused it
// whole: "The mesh emptySolid contains no vertices").
TEST(ModelImport, AnEmptySolidKeepsItsPlace) {
  test::TempDir dir;
  const std::string facet = "facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n";
  const Scene s = load_scene(dir.write("solids.stl", "solid a\n" + facet + "endsolid a\nsolid empty\nendsolid empty\n"
                                                     "solid c\n" + facet + facet + "endsolid c\n"));
  EXPECT_EQ(s.num_objects, 3);
  EXPECT_EQ(s.num_facets, 3);
  ASSERT_EQ(s.triangles.size(), 3u);
  EXPECT_EQ(s.triangles[0].object_id, 0);
  EXPECT_EQ(s.triangles[1].object_id, 2);
  EXPECT_EQ(s.triangles[2].facet_id, 2);
  EXPECT_NE(error_of(dir.write("none.stl", "solid a\nendsolid a\n")).find("no facets"), std::string::npos);
}

TEST(ModelImport, MaterialsAndTextureMaps) {
  REQUIRE_TEST_MODELS();
  // COLLADA duck: one material with a diffuse texture (a TGA beside it).
  const Scene duck = load_scene((kModels / "Collada/duck.dae").string());
  ASSERT_EQ(duck.materials.size(), 2u);
  const MaterialDesc& m = duck.materials[1];
  EXPECT_EQ(m.illum, 2);
  ASSERT_GE(m.map_kd, 0);
  EXPECT_EQ(duck.textures[m.map_kd].width, 512);
  EXPECT_NE(duck.textures[m.map_kd].path.find("duckCM.tga"), std::string::npos);
  EXPECT_FLOAT_EQ(m.ks[0], duck.materials[1].ks[1]);
  int with_uv = 0;
  for (const Triangle& t : duck.triangles) with_uv += t.attributes >= 0 && duck.attributes[t.attributes].has_uv;
  EXPECT_EQ(with_uv, static_cast<int>(duck.triangles.size()));
  // glTF: the texture is a PNG beside the file, or embedded in the GLB.
  for (const char* f : {"glTF2/BoxTextured-glTF/BoxTextured.gltf", "glTF2/BoxTextured-glTF-Binary/BoxTextured.glb"}) {
    SCOPED_TRACE(f);
    const Scene box = load_scene((kModels / f).string());
    bool mapped = false;
    for (const MaterialDesc& mm : box.materials) mapped = mapped || mm.map_kd >= 0;
    EXPECT_TRUE(mapped);
    ASSERT_EQ(box.textures.size(), 1u);
    EXPECT_EQ(box.textures[0].width, 211);  // CesiumLogoFlat.png
    EXPECT_TRUE(box.warnings.empty()) << box.warnings.front();
  }
  // A missing texture is one warning; the model still loads.
  const Scene cube = load_scene((kModels / "3DS/cube_with_diffuse_texture.3DS").string());
  bool warned = false;
  for (const std::string& w : cube.warnings) warned = warned || w.find("texture map") != std::string::npos;
  EXPECT_TRUE(warned);
}

// CONTRACT: a material is used as the file gives it, whatever its name; only the
// importer's placeholder (no name or DefaultMaterial, no map, grey or no
// diffuse colour) is "no material". NFF names its coloured materials
// DefaultMaterial; HL1 MDL leaves its textured ones unnamed.
TEST(ModelImport, MaterialsAreUsedWhateverTheirName) {
  REQUIRE_TEST_MODELS();
  const Scene nff = load_scene((kModels / "NFF/NFF/WithCamera.nff").string());
  // Four meshes: a grey one (the placeholder) and red, green, blue ones.
  ASSERT_EQ(nff.materials.size(), 4u);
  EXPECT_EQ(nff.materials[1].kd, (Vec3{0.8f, 0, 0}));
  EXPECT_EQ(nff.materials[2].kd, (Vec3{0, 0.8f, 0}));
  EXPECT_EQ(nff.materials[3].kd, (Vec3{0, 0, 0.8f}));
  EXPECT_EQ(nff.materials[1].ka, (Vec3{0, 0, 0}));  // as the file gives it, not CONTRACT's default 0.8
  std::set<int> used;
  for (const Triangle& t : nff.triangles) used.insert(t.material);
  EXPECT_EQ(used, (std::set<int>{0, 1, 2, 3}));
  // An NFF material with a map is used too, grey or not.
  const Scene spheres = load_scene((kModels / "NFF/NFF/spheres.nff").string());
  EXPECT_EQ(spheres.materials.size(), 4u);  // default + blue + two with the earth map
  // HL1 MDL: unnamed materials, each with a texture and no diffuse colour.
  const Scene man = load_scene((kModels / "MDL/MDL (HL1)/man.mdl").string());
  ASSERT_EQ(man.materials.size(), 6u);
  for (std::size_t k = 1; k < man.materials.size(); ++k) {
    SCOPED_TRACE(k);
    EXPECT_EQ(man.materials[k].kd, (Vec3{1, 1, 1}));
    if (k <= 3) EXPECT_GE(man.materials[k].map_kd, 0);  // the file's meshes use the first three
  }
  for (const Triangle& t : man.triangles) EXPECT_GT(t.material, 0);
  // The placeholder of a format without materials is still CONTRACT's default
  // (PLY: unnamed; STL: DefaultMaterial, both with a grey diffuse colour).
  for (const char* f : {"PLY/cube.ply", "STL/Spider_binary.stl"}) {
    SCOPED_TRACE(f);
    const Scene s = load_scene((kModels / f).string());
    EXPECT_EQ(s.materials.size(), 1u);
    for (const Triangle& t : s.triangles) EXPECT_EQ(t.material, 0);
  }
}

// CONTRACT: a material with a map_Kd (map_Ka) but no Kd (Ka) takes (1, 1, 1):
// the texture alone gives the colour. glTF 1, IQM, SMD and HL1 MDL
// materials carry a texture and no diffuse colour; where the file gives a
// diffuse colour beside the map it is kept.
TEST(ModelImport, TextureOnlyMaterialsTakeDiffuseOne) {
  REQUIRE_TEST_MODELS();
  struct Case {
    const char* file;
    std::size_t textured;  // materials with a map and no diffuse colour
  };
  const Case cases[] = {{"glTF/CesiumMilkTruck/CesiumMilkTruck.gltf", 2},
                        {"IQM/mrfixit.iqm", 2},
                        {"SMD/holy_grailref.smd", 1},
                        {"MDL/MDL (HL1)/chrome_sphere.mdl", 1}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.file);
    const Scene s = load_scene((kModels / c.file).string());
    std::size_t white = 0;
    for (const MaterialDesc& m : s.materials) {
      if (m.map_kd < 0) continue;
      EXPECT_EQ(m.kd, (Vec3{1, 1, 1}));
      EXPECT_GT(s.textures[m.map_kd].width, 0);
      ++white;
    }
    EXPECT_EQ(white, c.textured);
  }
  // The truck's untextured materials keep the colours the file gives.
  const Scene truck = load_scene((kModels / "glTF/CesiumMilkTruck/CesiumMilkTruck.gltf").string());
  ASSERT_EQ(truck.materials.size(), 5u);
  EXPECT_EQ(truck.materials[4].map_kd, -1);
  EXPECT_FLOAT_EQ(truck.materials[4].kd[0], 0.064f);
  // IQM gives no ambient colour and no ambient map: Ka stays 0.
  const Scene iqm = load_scene((kModels / "IQM/mrfixit.iqm").string());
  EXPECT_EQ(iqm.materials[1].ka, (Vec3{0, 0, 0}));
  // A diffuse colour beside a map is kept as given (NFF: red with a map
  // whose file is not there, a warning).
  const Scene spheres = load_scene((kModels / "NFF/NFF/spheres.nff").string());
  ASSERT_EQ(spheres.materials.size(), 4u);
  EXPECT_EQ(spheres.materials[3].kd, (Vec3{1, 0, 0}));
}

TEST(ModelImport, BrokenFileOfEveryFormatIsOneClearError) {
  test::TempDir dir;
  for (const char* ext : {"ply", "stl", "gltf", "glb", "fbx", "dae", "3ds"}) {
    SCOPED_TRACE(ext);
    const std::string path = dir.write(std::string("broken.") + ext, std::string("\x01\x02garbage, not a model\n", 23));
    const std::string msg = error_of(path);
    EXPECT_EQ(msg.rfind(path + ": ", 0), 0u) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    EXPECT_NE(msg, "<no error>");
    const test::RunResult r = test::run_opsila({"render", path, "-o", dir.file("x.png")});
    EXPECT_EQ(r.exit_code, 2) << r.err;
    ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
    EXPECT_NE(r.error_lines()[0].find(path), std::string::npos);
    EXPECT_FALSE(test::file_exists(dir.file("x.png")));
  }
  EXPECT_NE(error_of(dir.file("none.ply")).find("cannot open"), std::string::npos);
}

// Some of the importer's readers loop forever on malformed files; a read that
// outlives its budget is one error line and exit 2, never a hang. A zero
// budget makes any read too slow, so the test needs no hanging file.
TEST(ModelImport, AnImportThatOutlivesItsBudgetIsOneClearError) {
  REQUIRE_TEST_MODELS();
  test::TempDir dir;
  const std::string model = (kModels / "PLY" / "Wuson.ply").string();
  ASSERT_TRUE(fs::exists(model));
  const test::RunResult r = test::run_program(OPSILA_BINARY, {"render", model, "-o", dir.file("x.png"), "--size", "8x8"},
                                              {{"OPSILA_IMPORT_TIMEOUT", "0"}});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
  EXPECT_NE(r.error_lines()[0].find(model + ": the model importer did not finish"), std::string::npos) << r.err;
  EXPECT_FALSE(test::file_exists(dir.file("x.png")));
  // With the default budget the same file loads.
  EXPECT_EQ(test::run_opsila({"render", model, "-o", dir.file("y.png"), "--size", "8x8"}).exit_code, 0);
  // A budget that is no number of seconds is refused, named, not ignored.
  for (const char* bad : {"abc", "-1", "nan", "5abc", "1e400"}) {
    const test::RunResult b = test::run_program(
        OPSILA_BINARY, {"render", model, "-o", dir.file("z.png"), "--size", "8x8"}, {{"OPSILA_IMPORT_TIMEOUT", bad}});
    EXPECT_EQ(b.exit_code, 2) << bad;
    ASSERT_EQ(b.error_lines().size(), 1u) << b.err;
    EXPECT_NE(b.error_lines()[0].find(std::string("OPSILA_IMPORT_TIMEOUT=") + bad + ": expected a number of seconds"),
              std::string::npos)
        << b.err;
    EXPECT_FALSE(test::file_exists(dir.file("z.png")));
  }
}

// A reader that grows without end (a corrupted Q3O file took 19 GB in the
// watchdog's 60 s) is stopped by its memory budget: one error line, exit
// 2. A budget of 1 MiB stops the read of a 200,000-vertex text PLY (which
// takes tens of MiB and most of a second); the default budget reads it.
TEST(ModelImport, AnImportThatOutgrowsItsMemoryIsOneClearError) {
  test::TempDir dir;
  std::string ply = "ply\nformat ascii 1.0\nelement vertex 200000\nproperty float x\nproperty float y\n"
                    "property float z\nelement face 100000\nproperty list uchar int vertex_indices\nend_header\n";
  for (int i = 0; i < 200000; ++i) ply += std::to_string(i % 1000) + " " + std::to_string(i / 1000) + " 0.5\n";
  for (int f = 0; f < 100000; ++f) ply += "3 " + std::to_string(2 * f) + " " + std::to_string(2 * f + 1) + " " +
                                         std::to_string((2 * f + 1000) % 200000) + "\n";
  const std::string model = dir.write("big.ply", ply);
  const test::RunResult r = test::run_program(OPSILA_BINARY, {"render", model, "-o", dir.file("x.png"), "--size", "8x8"},
                                              {{"OPSILA_IMPORT_MEMORY", "1048576"}});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
  EXPECT_NE(r.error_lines()[0].find(model + ": the model importer took more than 1 MiB of memory"), std::string::npos)
      << r.err;
  EXPECT_FALSE(test::file_exists(dir.file("x.png")));
  EXPECT_EQ(test::run_opsila({"render", model, "-o", dir.file("y.png"), "--size", "8x8"}).exit_code, 0);
}

// Readers opsila does not check first fault on some truncated files (the
// Half-Life MDL reader on the first 30% of one of Debian's test models:
// SIGSEGV inside the library). The run ends with one error line naming the
// file and exit 2, as for any bad input; no output file appears, and a
// good model still loads afterwards in the same way.
TEST(ModelImport, AFaultInsideTheImporterIsOneClearError) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "built with AddressSanitizer, which reports the library's out-of-bounds read itself "
                  "(and ends the run) before it faults";
#endif
  REQUIRE_TEST_MODELS();
  test::TempDir dir;
  const fs::path whole = kModels / "MDL" / "MDL (HL1)" / "unnamed_bones.mdl";
  ASSERT_TRUE(fs::exists(whole));
  const std::string bytes = test::read_file(whole.string());
  const std::string model = dir.write("cut.mdl", bytes.substr(0, bytes.size() * 3 / 10));
  const test::RunResult r = test::run_opsila({"render", model, "-o", dir.file("x.png"), "--size", "8x8"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
  EXPECT_NE(r.error_lines()[0].find(model + ": the model importer failed while reading it"), std::string::npos)
      << r.err;
  EXPECT_FALSE(test::file_exists(dir.file("x.png")));
}

// An exception the importer lets escape ends in std::terminate, whose
// runtime text ("terminate called after throwing ...") came before
// opsila's line; the importer's stderr is shut while it reads, so the
// whole of stderr is the one line (a COB file cut after 363 bytes).
TEST(ModelImport, AnImporterThatGivesUpPrintsNothingButTheLine) {
  REQUIRE_TEST_MODELS();
  test::TempDir dir;
  const fs::path whole = kModels / "COB" / "molecule.cob";
  ASSERT_TRUE(fs::exists(whole));
  const std::string model = dir.write("cut.cob", test::read_file(whole.string()).substr(0, 363));
  const test::RunResult r = test::run_opsila({"render", model, "-o", dir.file("x.png"), "--size", "8x8", "-q"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(r.err, "opsila: error: " + model + ": the model importer failed while reading it (malformed file?)\n");
  EXPECT_FALSE(test::file_exists(dir.file("x.png")));
}

// Counts in an OFF header that no file of that size can hold are refused
// before the importer allocates for them (found by fuzz_model).
TEST(ModelImport, OffCountsBeyondTheFileAreRefused) {
  test::TempDir dir;
  const std::string path = dir.write("huge.off", "OFF\n3 90000000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  const std::string msg = error_of(path);
  EXPECT_EQ(msg.rfind(path + ": OFF header asks for 90000000000000 faces", 0), 0u) << msg;
  const std::string ok = dir.write("ok.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(load_scene(ok).triangles.size(), 1u);
}

// Only the readers that claim a file's extension read it. Two readers claim
// .gltf and .glb; when both refuse the content the importer would go on to
// any reader whose keyword starts the file, and some allocate what a header
// asks first (fuzz_model: OFF text and a Quick3D header named .gltf asked for
// 45 GB and 1.2 TB). Now no reader takes those files. An STL
// whose free-form header starts with "offset" is still an STL.
TEST(ModelImport, OnlyTheReadersTheNameClaimsReadTheFile) {
  test::TempDir dir;
  const std::vector<std::pair<std::string, std::string>> foreign = {
      {"off.gltf", "OFF\n3 90000000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"},
      {"off.glb", "OFF\n3 90000000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"},
      {"ply.glb", "ply\nformat ascii 1.0\nelement vertex 3000000000\nproperty float x\nend_header\n"},
      {"q3d.gltf", "quick3Do\377\377\377\377\377\377\377\377\377\377\377\377"}};
  for (const auto& [name, text] : foreign) {
    const std::string path = dir.write(name, text);
    const std::string msg = error_of(path);
    EXPECT_EQ(msg.rfind(path + ": ", 0), 0u) << msg;
    EXPECT_EQ(msg.find("bad_alloc"), std::string::npos) << msg;
    // glTF's readers refuse it, and no other reader is asked.
    EXPECT_TRUE(msg.find("No suitable reader") != std::string::npos || msg.find("GLTF") != std::string::npos)
        << msg;
  }
  const std::string fuzzed =
      test::read_file(std::string(OPSILA_SOURCE_DIR) + "/tests/fuzz/corpus_model/quick3d-header-as-gltf");
  ASSERT_FALSE(fuzzed.empty());
  EXPECT_THROW(load_model_from_memory(fuzzed.substr(1), "fuzz.gltf", "gltf"), InputError);

  std::string stl(80, ' ');
  const std::string header = "offset 900000000000 model";
  stl.replace(0, header.size(), header);
  const std::uint32_t count = 1;
  stl.append(reinterpret_cast<const char*>(&count), 4);
  const float tri[12] = {0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0};  // normal, then three vertices
  stl.append(reinterpret_cast<const char*>(tri), sizeof tri);
  stl.append(2, '\0');  // attribute byte count
  EXPECT_EQ(load_scene(dir.write("offset.stl", stl)).triangles.size(), 1u);
}

// Element counts in a PLY header that no file of that size can hold are
// refused before the importer allocates for them; true counts load.
TEST(ModelImport, PlyCountsBeyondTheFileAreRefused) {
  test::TempDir dir;
  const std::string body = "property float x\nproperty float y\nproperty float z\nelement face 1\n"
                           "property list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  const std::string huge = dir.write("huge.ply", "ply\nformat ascii 1.0\nelement vertex 3000000000\n" + body);
  const std::string msg = error_of(huge);
  EXPECT_EQ(msg.rfind(huge + ": PLY header asks for 3000000000 'vertex' elements", 0), 0u) << msg;
  const std::string ok = dir.write("ok.ply", "ply\nformat ascii 1.0\nelement vertex 3\n" + body);
  EXPECT_EQ(load_scene(ok).triangles.size(), 1u);
}

TEST(ModelImport, SceneFileModelObjects) {
  REQUIRE_TEST_MODELS();
  test::TempDir dir;
  const std::string scene = dir.write(
      "s.json", std::string(R"({"objects": [{"type": "box", "min": [0,0,0], "max": [1,1,1]},
        {"type": "model", "file": ")") + (kModels / "3DS/cubes_with_alpha.3DS").string() +
                    R"(", "transform": {"translate": [5, 0, 0]}},
        {"type": "model", "file": ")" + (kModels / "PLY/cube.ply").string() + R"("}]})");
  const Scene s = load_scene(scene);
  EXPECT_EQ(s.num_objects, 1 + 5 + 1);
  EXPECT_EQ(s.num_facets, 6 + 60 + 6);
  EXPECT_EQ(s.triangles.back().object_id, 6);
  EXPECT_EQ(s.triangles.back().facet_id, 71);
  const std::string bad = dir.write("b.json", R"({"objects": [{"type": "model", "file": "s.json"}]})");
  const std::string msg = error_of(bad);
  EXPECT_NE(msg.find("objects[0].file"), std::string::npos) << msg;
  EXPECT_NE(msg.find("not a model format"), std::string::npos) << msg;
}

// A scene the importer flags incomplete holds its stand-in shapes, not the
// file's surfaces: a file of cameras or lights says so. UTF-16 text, which
// its readers read in part or not at all, is named before them.
TEST(ModelImport, AnIncompleteSceneSaysSo) {
  REQUIRE_TEST_MODELS();
  const std::string cameras = (kModels / "Collada/cameras.dae").string();
  EXPECT_EQ(error_of(cameras), cameras + ": no facets: the model importer found no surfaces in it (3 camera(s) and 0 "
                                         "light(s) only); its stand-in shapes for the nodes are not drawn");
  for (const char* model : {"ASE/ThreeCubesGreen_UTF16LE.ASE", "ASE/ThreeCubesGreen_UTF16BE.ASE",
                            "AC/SphereWithLight_UTF16LE.ac", "Collada/cube_UTF16LE.dae"}) {
    const std::string path = (kModels / model).string();
    EXPECT_EQ(error_of(path), path + ":1: UTF-16 text is not supported (save the file as UTF-8 or ASCII)");
  }
}

// glTF primitive modes (scenes/FORMAT.md): triangle strips and fans are
// read as their triangles, each a facet; points and lines make none (a
// model of nothing else is "no facets").
std::string gltf_of_mode(int mode) {
  // Six vertices (0,0) (1,0) (0,1) (1,1) (0,2) (1,2) in the plane z = 0, base64 floats.
  const std::string data =
      "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAACAPwAAgD8AAAAAAAAAAAAAAEAAAAAAAACAPwAAAEAAAAAA";
  return R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "mode": )" + std::to_string(mode) + R"(}]}],
    "buffers": [{"byteLength": 72, "uri": "data:application/octet-stream;base64,)" + data + R"("}],
    "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 72}],
    "accessors": [{"bufferView": 0, "componentType": 5126, "count": 6, "type": "VEC3",
                   "min": [0, 0, 0], "max": [1, 2, 0]}]})";
}

TEST(ModelImport, GltfStripsAndFansAreTheirTrianglesPointsAndLinesNone) {
  test::TempDir dir;
  EXPECT_EQ(load_scene(dir.write("list.gltf", gltf_of_mode(4))).triangles.size(), 2u);
  for (int mode : {5, 6}) {  // TRIANGLE_STRIP, TRIANGLE_FAN: 4 triangles of 6 vertices
    const Scene s = load_scene(dir.write("m" + std::to_string(mode) + ".gltf", gltf_of_mode(mode)));
    EXPECT_EQ(s.triangles.size(), 4u) << "mode " << mode;
    EXPECT_EQ(s.num_facets, 4) << "mode " << mode;
  }
  for (int mode : {0, 1, 3}) {  // POINTS, LINES, LINE_STRIP
    const std::string path = dir.write("p" + std::to_string(mode) + ".gltf", gltf_of_mode(mode));
    try {
      load_scene(path);
      ADD_FAILURE() << "mode " << mode << " gave facets";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("no facets"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace opsila
