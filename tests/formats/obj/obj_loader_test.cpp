// OBJ/MTL input: CONTRACT id rules, materials, and one precise message per bad
// input. No OpenCL needed.
#include <gtest/gtest.h>

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <set>
#include <string>
#include <vector>

#include "material_checks.h"
#include "test_util.h"
#include "formats/obj/obj_loader.h"
#include "scene/scene.h"

namespace opsila {
namespace {

namespace fs = std::filesystem;

const std::string kData = std::string(OPSILA_SOURCE_DIR) + "/tests/data";

using test::error_of;
using test::expect_error;

Scene from_text(const std::string& text) { return load_obj_from_string(text, "t.obj", ""); }

// facet id -> object id, for every triangle.
std::vector<std::pair<int, int>> ids(const Scene& s) {
  std::vector<std::pair<int, int>> out;
  for (const Triangle& t : s.triangles) out.emplace_back(t.facet_id, t.object_id);
  return out;
}

bool has_warning(const Scene& s, const std::string& a, const std::string& b = "") {
  for (const std::string& w : s.warnings)
    if (w.find(a) != std::string::npos && w.find(b) != std::string::npos) return true;
  return false;
}

const char* kTriVerts = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";

// ------------------------------------------------------------- ids -------

TEST(ObjIds, FacetIdsCountOnlyFacesWithThreeOrMoreVertices) {
  const Scene s = from_text(std::string(kTriVerts) +
                            "f 1 2 3\n"   // line 5: facet 0
                            "f 1 2\n"     // line 6: not a facet
                            "l 1 2 3\n"   // line 7: a polyline, ignored
                            "f 1 3 4\n"   // line 8: facet 1
                            "f 2\n"       // line 9: not a facet
                            "f 2 3 4\n"); // line 10: facet 2
  ASSERT_EQ(s.triangles.size(), 3u);
  EXPECT_EQ(s.triangles[0].facet_id, 0);
  EXPECT_EQ(s.triangles[1].facet_id, 1);
  EXPECT_EQ(s.triangles[2].facet_id, 2);
  EXPECT_EQ(s.num_facets, 3);
  EXPECT_EQ(s.num_objects, 1);
  EXPECT_TRUE(has_warning(s, "t.obj:6:", "skipped 2 face(s) with fewer than 3 vertices"));
}

TEST(ObjIds, ObjectIdsFollowOSectionsAndIgnoreGroupsThen) {
  const Scene s = from_text(std::string(kTriVerts) +
                            "o first\nf 1 2 3\ng a\nf 1 3 4\n"
                            "o second\ng b\nf 2 3 4\ng c\nf 1 2 4\n");
  EXPECT_EQ(ids(s), (std::vector<std::pair<int, int>>{{0, 0}, {1, 0}, {2, 1}, {3, 1}}));
  EXPECT_EQ(s.num_objects, 2);
}

TEST(ObjIds, GroupsGiveObjectIdsWhenThereIsNoO) {
  const Scene s = from_text(std::string(kTriVerts) +
                            "g one\nf 1 2 3\ng two\nf 1 3 4\ng three\nf 2 3 4\n");
  EXPECT_EQ(ids(s), (std::vector<std::pair<int, int>>{{0, 0}, {1, 1}, {2, 2}}));
  EXPECT_EQ(s.num_objects, 3);
}

TEST(ObjIds, NoSectionsIsOneObjectZero) {
  const Scene s = from_text(std::string(kTriVerts) + "f 1 2 3\nf 1 3 4\n");
  EXPECT_EQ(ids(s), (std::vector<std::pair<int, int>>{{0, 0}, {1, 0}}));
  EXPECT_EQ(s.num_objects, 1);
}

TEST(ObjIds, FacesBeforeTheFirstSectionJoinObjectZero) {
  const Scene s = from_text(std::string(kTriVerts) +
                            "f 1 2 3\no a\nf 1 3 4\no b\nf 2 3 4\n");
  EXPECT_EQ(ids(s), (std::vector<std::pair<int, int>>{{0, 0}, {1, 0}, {2, 1}}));
  EXPECT_EQ(s.num_objects, 2);
}

TEST(ObjIds, EmptySectionsStillTakeAnId) {
  const Scene s = from_text(std::string(kTriVerts) + "o a\no b\nf 1 2 3\no c\no d\nf 1 3 4\n");
  EXPECT_EQ(ids(s), (std::vector<std::pair<int, int>>{{0, 1}, {1, 3}}));
  EXPECT_EQ(s.num_objects, 4);
}

TEST(ObjIds, PolygonsAreFannedFromTheFirstVertexAndKeepOneId) {
  const Scene s = from_text(
      "v 0 0 0\nv 2 0 0\nv 3 1 0\nv 1 2 0\nv -1 1 0\n"
      "f 1 2 3 4 5\n"   // pentagon: 3 triangles, facet 0
      "f 1 2 3\n");     // facet 1
  ASSERT_EQ(s.triangles.size(), 4u);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(s.triangles[k].facet_id, 0);
    EXPECT_EQ(s.triangles[k].v0, (Vec3{0, 0, 0}));
  }
  EXPECT_EQ(s.triangles[0].v1, (Vec3{2, 0, 0}));
  EXPECT_EQ(s.triangles[0].v2, (Vec3{3, 1, 0}));
  EXPECT_EQ(s.triangles[2].v1, (Vec3{1, 2, 0}));
  EXPECT_EQ(s.triangles[2].v2, (Vec3{-1, 1, 0}));
  EXPECT_EQ(s.triangles[3].facet_id, 1);
  EXPECT_EQ(s.num_facets, 2);
}

TEST(ObjIds, DegenerateFacetsAreSkippedButKeepTheirIds) {
  const Scene s = from_text(
      "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\n"
      "f 1 2 4\n"     // line 5: facet 0
      "f 1 2 3\n"     // line 6: collinear, facet 1 (not rendered)
      "f 1 1 4\n"     // line 7: repeated vertex, facet 2 (not rendered)
      "f 2 3 4\n");   // line 8: facet 3
  ASSERT_EQ(s.triangles.size(), 2u);
  EXPECT_EQ(s.triangles[0].facet_id, 0);
  EXPECT_EQ(s.triangles[1].facet_id, 3);
  EXPECT_EQ(s.num_facets, 4);
  EXPECT_TRUE(has_warning(s, "t.obj:6:", "2 degenerate"));
}

TEST(ObjIds, QuadWithOneZeroAreaFanTriangleKeepsTheOther) {
  // Vertices 1, 2, 3 are collinear: the first fan triangle has no area.
  const Scene s = from_text("v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 3 4\n");
  ASSERT_EQ(s.triangles.size(), 1u);
  EXPECT_EQ(s.triangles[0].facet_id, 0);
  EXPECT_FALSE(has_warning(s, "degenerate"));
}

TEST(ObjParse, NegativeIndicesAreRelativeToTheVerticesSoFar) {
  const Scene s = from_text(
      "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n"
      "v 5 5 5\nv 6 5 5\nv 5 6 5\nf -3 -2 -1\nf 1 -2 -1\n");
  ASSERT_EQ(s.triangles.size(), 3u);
  EXPECT_EQ(s.triangles[0].v0, (Vec3{0, 0, 0}));
  EXPECT_EQ(s.triangles[0].v2, (Vec3{0, 1, 0}));
  EXPECT_EQ(s.triangles[1].v0, (Vec3{5, 5, 5}));
  EXPECT_EQ(s.triangles[2].v0, (Vec3{0, 0, 0}));
  EXPECT_EQ(s.triangles[2].v1, (Vec3{6, 5, 5}));
}

TEST(ObjParse, AllVertexReferenceFormsAndIgnoredStatements) {
  const Scene s = from_text(
      "# comment\nv 0 0 0\nv 1 0 0 1.0\nv 0 1 0 0.5 0.5 0.5\nvt 0 0\nvn 0 0 1\nvp 0.5\n"
      "s 1\nl 1 2\np 1\ncstype bezier\n"
      "f 1/1 2/1 3/1\nf 1//1 2//1 3//1\nf 1/1/1 2/1/1 3/1/1   # trailing comment\n"
      "f +1 +2 +3\n");
  EXPECT_EQ(s.triangles.size(), 4u);
  EXPECT_TRUE(s.warnings.empty()) << s.warnings.front();
}

TEST(ObjParse, VerticesMayBeDefinedAfterTheFacesThatUseThem) {
  const Scene s = from_text("f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n");
  ASSERT_EQ(s.triangles.size(), 1u);
  EXPECT_EQ(s.triangles[0].v1, (Vec3{1, 0, 0}));
}

TEST(ObjParse, NumberFormsAndTinyNumbers) {
  const Scene s = from_text("v 0 0 0\nv +1. 0e0 -0\nv 0 1E0 1e-50\nf 1 2 3\n");
  ASSERT_EQ(s.triangles.size(), 1u);
  EXPECT_EQ(s.triangles[0].v1[0], 1.0f);
  EXPECT_EQ(s.triangles[0].v2[2], 0.0f);
}

TEST(ObjParse, GeometryKeepsTheWindingAsWritten) {
  const Scene s = from_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 3 2 1\n");
  ASSERT_EQ(s.triangles.size(), 2u);
  EXPECT_EQ(s.triangles[0].v1, (Vec3{1, 0, 0}));
  EXPECT_EQ(s.triangles[1].v1, (Vec3{1, 0, 0}));
  EXPECT_EQ(s.triangles[1].v0, (Vec3{0, 1, 0}));
}

// A backslash before the line end joins the next line (Wavefront's line
// continuation), in OBJ and MTL; a statement is named by its first line,
// and the lines after it keep their numbers.
TEST(ObjParse, ABackslashAtTheEndGoesOnInTheNextLine) {
  const Scene s = from_text("v 0 0 0\nv 1 \\\n0 0\nv 0 1 0\nv 1 1 0\nf 1 2 \\\r\n3 \\\r4\nf 1\\\n\\\n 3 4\n");
  ASSERT_EQ(s.num_facets, 2);
  ASSERT_EQ(s.triangles.size(), 3u);
  EXPECT_EQ(s.triangles[0].v1, (Vec3{1, 0, 0}));
  EXPECT_EQ(s.triangles[1].v2, (Vec3{1, 1, 0}));
  try {
    from_text("v 0 0 0\nv 1 0 0\nf 1 \\\n2 \\\nx\n");
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("t.obj:3: bad vertex reference 'x'"), std::string::npos) << e.what();
  }
  try {
    from_text("v 0 \\\n0 0\nv 1 0 0\nv 0 1 \\\n0\nf 1 2 3\nv 1 y 2\n");
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("t.obj:7:"), std::string::npos) << e.what();
  }
  std::vector<std::string> warnings;
  const auto mats = parse_mtl("newmtl a\nKd 0.5 \\\n 0.25 0.125\n", "x.mtl", warnings);
  ASSERT_EQ(mats.size(), 1u);
  EXPECT_EQ(mats[0].kd, (Vec3{0.5f, 0.25f, 0.125f}));
}

TEST(ObjParse, UnknownStatementsAreOneWarning) {
  const Scene s = from_text(std::string(kTriVerts) + "frobnicate 1\nf 1 2 3\nzap\n");
  EXPECT_TRUE(has_warning(s, "t.obj:5:", "ignored 2 line(s) with unknown statements"));
}

// A face naming texture coordinates or normals on some corners only is
// drawn without them, and one warning for each kind says so (it had gone
// unsaid); faces of one form each are not warned of.
TEST(ObjParse, FacesMixingCornerFormsAreOneWarningEach) {
  const std::string head = std::string(kTriVerts) + "vt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\n";
  const Scene s = from_text(head + "f 1/1 2/2 3/3\nf 1/1 3/3 4\nf 1//1 2 3\nf 1/2 3/3 4/1\nf 2//1 3//1 4//1\n");
  EXPECT_TRUE(has_warning(s, "t.obj:10:", "1 face(s) name texture coordinates on some corners only"));
  EXPECT_TRUE(has_warning(s, "t.obj:11:", "1 face(s) name normals on some corners only"));
  ASSERT_EQ(s.triangles.size(), 5u);
  int with_uv = 0, with_normals = 0;
  for (const Triangle& t : s.triangles) {
    if (t.attributes < 0) continue;
    with_uv += s.attributes[std::size_t(t.attributes)].has_uv;
    with_normals += s.attributes[std::size_t(t.attributes)].has_normals;
  }
  EXPECT_EQ(with_uv, 2);  // faces 1 and 4
  EXPECT_EQ(with_normals, 1);  // face 5
  const Scene plain = from_text(head + "f 1/1 2/2 3/3\nf 1 3 4\nf 1//1 2//1 3//1\n");
  EXPECT_FALSE(has_warning(plain, "on some corners only"));
}

TEST(ObjParse, BareObjFramesItselfAndAsksForNoLightsOrCamera) {
  const Scene s = from_text(std::string(kTriVerts) + "f 1 2 3\n");
  EXPECT_FALSE(s.has_camera);
  EXPECT_FALSE(s.has_lights);
  EXPECT_NEAR(s.camera.look_at[0], 0.5f, 1e-6);
  EXPECT_NEAR(s.camera.look_at[1], 0.5f, 1e-6);
  EXPECT_GT(s.camera.eye[2], 1.0f);
}

// ------------------------------------------------------------ materials --

TEST(ObjMaterials, MtlValuesDefaultsAndLibraryAfterUsemtl) {
  const Scene s = load_obj(kData + "/cube.obj");
  EXPECT_EQ(s.num_objects, 2);
  EXPECT_EQ(s.num_facets, 6);
  ASSERT_EQ(s.triangles.size(), 12u);
  ASSERT_EQ(s.materials.size(), 4u);  // default + red, green, partial
  const MaterialDesc& def = s.materials[0];
  EXPECT_EQ(def.illum, 2);
  EXPECT_NEAR(def.kd[1], 0.8f, 1e-6);
  EXPECT_NEAR(def.ka[2], 0.8f, 1e-6);

  const MaterialDesc& red = s.materials[1];
  EXPECT_EQ(red.name, "red");
  EXPECT_NEAR(red.ka[0], 0.1f, 1e-6);
  EXPECT_NEAR(red.kd[1], 0.1f, 1e-6);
  EXPECT_NEAR(red.ks[2], 0.5f, 1e-6);  // "Ks 0.5" means grey 0.5
  EXPECT_NEAR(red.ns, 20.0f, 1e-5);
  EXPECT_NEAR(red.ni, 1.5f, 1e-6);
  EXPECT_NEAR(red.tf[2], 0.4f, 1e-6);
  EXPECT_EQ(red.illum, 7);
  EXPECT_NEAR(red.kt()[1], 0.3f, 1e-6);

  const MaterialDesc& partial = s.materials[3];
  EXPECT_EQ(partial.name, "partial");
  test::expect_optics(partial, {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}, 1.0f, 1.0f, 0});  // the MTL defaults

  // usemtl red came before mtllib: still found.
  EXPECT_EQ(s.triangles[0].material, 1);
  EXPECT_EQ(s.triangles[0].object_id, 0);
  EXPECT_EQ(s.triangles[4].material, 2);
  EXPECT_EQ(s.triangles[4].object_id, 1);
  EXPECT_EQ(s.triangles[8].material, 3);
  EXPECT_EQ(s.triangles[10].facet_id, 5);  // f -4 -3 -2 -1
  EXPECT_EQ(s.triangles[10].v0, (Vec3{0, 0, 1}));
  EXPECT_TRUE(s.warnings.empty()) << s.warnings.front();
}

TEST(ObjMaterials, NoMaterialUnknownNameAndUnsupportedTfForms) {
  const Scene s = load_obj(kData + "/materials.obj");
  ASSERT_EQ(s.triangles.size(), 4u);
  EXPECT_EQ(s.triangles[0].material, 0);  // before any usemtl
  const MaterialDesc& spectral = s.materials[s.triangles[1].material];
  EXPECT_EQ(spectral.name, "spectral_tf");
  EXPECT_EQ(spectral.tf, (Vec3{0, 0, 0}));
  EXPECT_NEAR(spectral.kd[2], 0.6f, 1e-6);
  EXPECT_TRUE(has_warning(s, "materials.mtl:3:", "Tf spectral"));
  EXPECT_EQ(s.triangles[2].material, 0);  // unknown name -> default
  EXPECT_TRUE(has_warning(s, "materials.obj:8:", "no_such_material"));
  const MaterialDesc& mirror = s.materials[s.triangles[3].material];
  EXPECT_EQ(mirror.name, "mirror");
  EXPECT_NEAR(mirror.kr()[0], 0.9f, 1e-6);
  EXPECT_EQ(mirror.kt(), (Vec3{0, 0, 0}));
}

TEST(ObjMaterials, MissingMtlIsAWarningNotAnError) {
  Scene s;
  ASSERT_NO_THROW(s = load_obj(kData + "/missing_mtl.obj"));
  EXPECT_TRUE(has_warning(s, "missing_mtl.obj:1:", "does_not_exist.mtl"));
  EXPECT_TRUE(has_warning(s, "missing_mtl.obj:5:", "anything"));
  ASSERT_EQ(s.triangles.size(), 1u);
  EXPECT_EQ(s.triangles[0].material, 0);
  EXPECT_EQ(s.materials[0].illum, 2);
  EXPECT_TRUE(has_warning(s, "missing_mtl.obj:1:", "'does_not_exist.mtl' not found"));
  // Something there that is no file says what it is.
  test::TempDir dir;
  fs::create_directory(dir.file("lib.mtl"));
  const Scene f = load_obj(dir.write("folder.obj", "mtllib lib.mtl\n" + std::string(kTriVerts) + "f 1 2 3\n"));
  EXPECT_TRUE(has_warning(f, "folder.obj:1:", "material library 'lib.mtl' is a folder, not a file"));
  const Scene d = load_obj(dir.write("device.obj", "mtllib /dev/null\n" + std::string(kTriVerts) + "f 1 2 3\n"));
  EXPECT_TRUE(has_warning(d, "device.obj:1:", "material library '/dev/null' is not a regular file"));
  // The OBJ itself had been read as its own material library, unsaid.
  const Scene self = load_obj(dir.write("self.obj", "mtllib ./self.obj\n" + std::string(kTriVerts) + "f 1 2 3\n"));
  EXPECT_TRUE(has_warning(self, "self.obj:1:", "material library './self.obj' is this OBJ file itself (ignored)"));
}

TEST(ObjMaterials, FromMemoryWithoutAFolderReadsNoMtl) {
  const Scene s = load_obj_from_string("mtllib cube.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
                                       "mem.obj", "");
  EXPECT_TRUE(has_warning(s, "mem.obj:1:", "mtllib"));
  EXPECT_EQ(s.materials.size(), 1u);
}

TEST(ObjMaterials, ParseMtlDirectly) {
  std::vector<std::string> warnings;
  const auto mats = parse_mtl("Kd 1 1 1\nnewmtl a\nKa 0.25\nillum 4\nNi 1.33\n", "x.mtl", warnings);
  ASSERT_EQ(mats.size(), 1u);
  EXPECT_EQ(mats[0].ka, (Vec3{0.25f, 0.25f, 0.25f}));
  EXPECT_EQ(mats[0].illum, 4);
  EXPECT_NEAR(mats[0].ni, 1.33f, 1e-6);
  ASSERT_EQ(warnings.size(), 1u);  // the key before newmtl
  EXPECT_NE(warnings[0].find("x.mtl:1:"), std::string::npos);
}

// ------------------------------------------------------------ bad input --

struct BadCase {
  const char* file;
  const char* line;      // "FILE:LINE:" fragment, or just the file
  const char* keyword;   // names the problem
};

TEST(ObjErrors, EveryBrokenFileGivesOnePreciseMessage) {
  const BadCase cases[] = {
      {"empty.obj", "empty.obj", "no facets"},
      {"comments_only.obj", "comments_only.obj", "no facets"},
      {"short_faces_only.obj", "short_faces_only.obj", "no facets"},
      {"all_degenerate.obj", "all_degenerate.obj", "degenerate"},
      {"tiny.obj", "tiny.obj", "no facets"},
      {"truncated_vertex.obj", "truncated_vertex.obj:2:", "truncated 'v'"},
      {"truncated_face_ref.obj", "truncated_face_ref.obj:4:", "'3/'"},
      {"nul_bytes.obj", "nul_bytes.obj:5:", "NUL"},
      {"binary_statement.obj", "binary_statement.obj:3:", "invalid statement"},
      {"control_char.obj", "control_char.obj:4:", "control character"},
      {"not_a_number.obj", "not_a_number.obj:3:", "'one' is not a number"},
      {"nan.obj", "nan.obj:4:", "not finite"},
      {"infinite.obj", "infinite.obj:4:", "not finite"},
      {"too_large.obj", "too_large.obj:4:", "too large for float"},
      {"hex_index.obj", "hex_index.obj:4:", "'0x3'"},
      {"float_index.obj", "float_index.obj:4:", "'2.5'"},
      {"zero_index.obj", "zero_index.obj:4:", "vertex index 0"},
      {"index_out_of_range.obj", "index_out_of_range.obj:5:",
       "vertex index 40 out of range (file has 3 vertices)"},
      {"negative_out_of_range.obj", "negative_out_of_range.obj:4:", "vertex index -4 out of range"},
      {"zero_texture_index.obj", "zero_texture_index.obj:5:", "'1/0'"},
      {"too_many_values.obj", "too_many_values.obj:1:", "8 values"},
      {"extent_overflow.obj", "extent_overflow.obj", "extent overflows float"},
      {"extent_too_large.obj", "extent_too_large.obj", "extent too large"},
      {"facet_overflow.obj", "facet_overflow.obj:4:", "overflow"},
      {"utf16.obj", "utf16.obj:1:", "UTF-16"},
      {"crlf_line5.obj", "crlf_line5.obj:5:", "bad vertex reference 'x'"},
      {"cr_only_line5.obj", "cr_only_line5.obj:5:", "vertex index 9"},
      {"bad_mtl_number.obj", "bad_number.mtl:3:", "'Kd' value 'zero'"},
      {"bad_mtl_illum.obj", "bad_illum.mtl:2:", "illum"},
  };
  for (const BadCase& c : cases) {
    SCOPED_TRACE(c.file);
    const std::string path = kData + "/bad/" + c.file;
    ASSERT_TRUE(fs::exists(path)) << path;
    expect_error([&] { load_obj(path); }, {c.line, c.keyword});
  }
  // Every file of the battery is covered by the table.
  std::set<std::string> listed;
  for (const BadCase& c : cases) listed.insert(c.file);
  for (const auto& entry : fs::directory_iterator(kData + "/bad")) {
    const std::string name = entry.path().filename().string();
    if (entry.path().extension() == ".obj") EXPECT_TRUE(listed.count(name)) << name;
  }
}

TEST(ObjMaterials, ManyUnknownMaterialNamesAreSummedUp) {
  std::string text = kTriVerts;
  for (int k = 0; k < 20; ++k) text += "usemtl m" + std::to_string(k) + "\nf 1 2 3\n";
  const Scene s = from_text(text);
  EXPECT_EQ(s.warnings.size(), 9u);  // eight named, then one summary
  EXPECT_TRUE(has_warning(s, "t.obj:", "12 more unknown material names"));
}

TEST(ObjErrors, StringInputErrorsNameTheGivenName) {
  expect_error([] { load_obj_from_string("v 1 2 3\nf 1 1 1 junk\n", "model.obj", ""); },
               {"model.obj:2:", "'junk'"});
  expect_error([] { load_obj_from_string("v 1 2\n", "model.obj", ""); },
               {"model.obj:1:", "truncated"});
  expect_error([] { load_obj_from_string(std::string("v 1 2 3\0", 8), "model.obj", ""); },
               {"model.obj:1:", "NUL"});
  expect_error([] { load_obj_from_string("v 1 2 3\nf 1 1 -9223372036854775808\n", "model.obj", ""); },
               {"model.obj:2:", "out of range"});
  expect_error([] { load_obj_from_string("v 1 2 3\nf 1 1 99999999999999999999\n", "model.obj", ""); },
               {"model.obj:2:", "99999999999999999999"});
}

TEST(ObjErrors, PathProblems) {
  expect_error([] { load_obj(kData + "/no_such_file.obj"); }, {"no_such_file.obj", "cannot open"});
  expect_error([] { load_obj(kData); }, {kData, "directory"});
  expect_error([] { load_obj("/dev/null"); }, {"/dev/null", "not a regular file"});
}

TEST(ObjErrors, UnreadableFile) {
  if (geteuid() == 0) GTEST_SKIP() << "running as root: permissions do not stop reading";
  const fs::path p = fs::temp_directory_path() / "opsila_unreadable.obj";
  { std::ofstream(p) << "v 0 0 0\n"; }
  fs::permissions(p, fs::perms::none);
  expect_error([&] { load_obj(p.string()); }, {p.string(), "cannot"});
  fs::remove(p);
}

// An MTL file that is there but cannot be read (too large, binary,
// unreadable) is named from the OBJ line that asks for it.
TEST(ObjErrors, AnUnreadableMaterialLibraryIsNamedFromItsLine) {
  const fs::path dir = fs::temp_directory_path() / "opsila_binary_mtl";
  fs::create_directories(dir);
  { std::ofstream(dir / "t.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nmtllib bin.mtl\nf 1 2 3\n"; }
  { std::ofstream(dir / "bin.mtl", std::ios::binary) << std::string("newmtl a\n\0\1", 11); }
  expect_error([&] { load_obj((dir / "t.obj").string()); }, {"t.obj:4: mtllib 'bin.mtl': ", "bin.mtl:2: NUL byte"});
  fs::remove_all(dir);
}

// ------------------------------------------------------ real-world files --

fs::path assimp_obj_dir() {
  for (const char* d : {"/usr/share/assimp/models/OBJ", "/usr/share/assimp-testmodels/models/OBJ",
                        "/usr/share/doc/assimp-testmodels/models/OBJ"})
    if (fs::is_directory(d)) return d;
  return {};
}

TEST(ObjRealModels, AssimpTestModelsLoadAndFrame) {
  const fs::path dir = assimp_obj_dir();
  if (dir.empty()) GTEST_SKIP() << "Debian package assimp-testmodels is not installed";
  const char* good[] = {"box.obj",         "spider.obj",        "WusonOBJ.obj",
                        "regr01.obj",      "cube_usemtl.obj",   "concave_polygon.obj",
                        "empty_mat.obj",   "box_mat_with_spaces.obj", "cube_with_vertexcolors.obj",
                        "multiple_spaces.obj", "testmixed.obj", "box_without_lineending.obj",
                        "regr_3429812.obj"};
  for (const char* f : good) {
    SCOPED_TRACE(f);
    Scene s;
    ASSERT_NO_THROW(s = load_obj((dir / f).string()));
    EXPECT_GT(s.num_facets, 0);
    EXPECT_FALSE(s.triangles.empty());
    Vec3 lo, hi;
    s.bounds(lo, hi);
    const CameraDesc cam = frame_bounds(lo, hi, 45.0f, 4.0f / 3.0f);
    for (int a = 0; a < 3; ++a) {
      EXPECT_TRUE(std::isfinite(cam.eye[a]));
      EXPECT_TRUE(std::isfinite(cam.look_at[a]));
    }
    EXPECT_GT(cam.eye[2], hi[2]);  // outside the model, looking at it
    EXPECT_GT(s.epsilon(), 0.0f);
  }
  // Spot checks against what the files say.
  const Scene box = load_obj((dir / "box.obj").string());
  EXPECT_EQ(box.num_facets, 6);
  EXPECT_EQ(box.triangles.size(), 12u);
  const Scene spider = load_obj((dir / "spider.obj").string());
  EXPECT_EQ(spider.num_objects, 19);  // 19 'g' groups, no 'o'
  EXPECT_GT(spider.materials.size(), 1u);
  const Scene mixed = load_obj((dir / "testmixed.obj").string());
  EXPECT_EQ(mixed.num_facets, 6);  // 'l' and 'p' lines are not facets
}

TEST(ObjRealModels, AssimpBrokenModelsAreRefusedClearly) {
  const fs::path dir = assimp_obj_dir();
  if (dir.empty()) GTEST_SKIP() << "Debian package assimp-testmodels is not installed";
  expect_error([&] { load_obj((dir / "number_formats.obj").string()); },
               {"number_formats.obj:11:", "'3.1+e2' is not a number"});
  expect_error([&] { load_obj((dir / "box_UTF16BE.obj").string()); }, {"box_UTF16BE.obj:1:", "UTF-16"});
  expect_error([&] { load_obj((dir / "point_cloud.obj").string()); }, {"point_cloud.obj", "no facets"});
  const fs::path invalid = dir.parent_path() / "invalid" / "malformed.obj";
  if (fs::exists(invalid))
    expect_error([&] { load_obj(invalid.string()); }, {"malformed.obj:", "vertex index"});
}

// ---------------------------------------------------------------- speed --

TEST(ObjSpeed, AMillionFacetsLoadInSeconds) {
  const int n = 708;  // 708 x 708 quads, two triangles each
  std::string text;
  text.reserve(size_t(64) << 20);
  char buf[96];
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      std::snprintf(buf, sizeof buf, "v %d.25 %d.5 %d.125\n", i, (i * 7 + j * 3) % 5, j);
      text += buf;
    }
  const int w = n + 1;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * w + i + 1, b = a + 1, d = a + w, c = d + 1;
      std::snprintf(buf, sizeof buf, "f %d %d %d\nf %d/%d %d//%d %d/%d/%d\n", a, d, c, a, a, c, c, b, b, b);
      text += buf;
    }
  const auto t0 = std::chrono::steady_clock::now();
  const Scene s = load_obj_from_string(text, "big.obj", "");
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(s.num_facets, 2 * n * n);
  EXPECT_EQ(s.triangles.size(), size_t(2) * n * n);
  EXPECT_EQ(s.triangles.back().facet_id, 2 * n * n - 1);
  EXPECT_LT(seconds, 10.0);  // about 0.2 s on a laptop core; generous for sanitizers
}

}  // namespace
}  // namespace opsila
