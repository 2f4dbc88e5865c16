// Faces that name a vertex past their mesh's list, in formats whose readers
// trust the index: ASE and DirectX .x dropped the face or made it a line,
// AC3D dropped the surface, 3DS put the last vertex in its place, each with
// exit 0 and a changed model; COLLADA's reader faulted, grew past 1 GiB or
// wrapped on words that are no count or index. Each is refused, naming the
// line where the format has lines. No OpenCL needed.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "core/errors.h"
#include "formats/json/scene_file.h"
#include "test_util.h"

namespace opsila {
namespace {

using test::TempDir;

std::string error_loading(const std::string& path) {
  return test::error_of([&] { load_scene(path); });
}

// Two triangles over four vertices; the second's last corner is `index`.
std::string ase(const std::string& index) {
  return "*3DSMAX_ASCIIEXPORT 200\n*GEOMOBJECT {\n *NODE_NAME \"t\"\n *MESH {\n  *MESH_NUMVERTEX 4\n"
         "  *MESH_NUMFACES 2\n  *MESH_VERTEX_LIST {\n   *MESH_VERTEX 0 0.0 0.0 0.0\n"
         "   *MESH_VERTEX 1 1.0 0.0 0.0\n   *MESH_VERTEX 2 0.0 1.0 0.0\n   *MESH_VERTEX 3 1.0 1.0 0.0\n  }\n"
         "  *MESH_FACE_LIST {\n   *MESH_FACE 0: A: 0 B: 1 C: 2\n   *MESH_FACE 1: A: 1 B: 3 C: " + index +
         "\n  }\n }\n}\n";
}

std::string ac3d(const std::string& index, const std::string& mat) {
  return "AC3Db\nMATERIAL \"m\" rgb 1 1 1  amb 0.2 0.2 0.2  emis 0 0 0  spec 0 0 0  shi 10  trans 0\n"
         "OBJECT world\nkids 1\nOBJECT poly\nname \"t\"\nnumvert 4\n0 0 0\n1 0 0\n0 1 0\n1 1 0\nnumsurf 2\n"
         "SURF 0x10\nmat 0\nrefs 3\n0 0 0\n1 0 0\n2 0 0\nSURF 0x10\nmat " + mat + "\nrefs 3\n1 0 0\n3 0 0\n" +
         index + " 0 0\nkids 0\n";
}

std::string x_text(const std::string& index) {
  return "xof 0303txt 0032\n// two faces\nMesh m {\n 4;\n 0.0;0.0;0.0;,\n 1.0;0.0;0.0;,\n 0.0;1.0;0.0;,\n"
         " 1.0;1.0;0.0;;\n 2;\n 3;0,1,2;,\n 3;1,3," + index + ";;\n}\n";
}

// A 3DS file of one mesh: its vertices, then faces of three indices (and
// flags), chunk by chunk (id, then length including the 6-byte header).
std::string chunk(std::uint16_t id, const std::string& body) {
  std::string c(6, '\0');
  const std::uint32_t length = std::uint32_t(6 + body.size());
  std::memcpy(&c[0], &id, 2);
  std::memcpy(&c[2], &length, 4);
  return c + body;
}

std::string three_ds(std::uint16_t index) {
  const float vertices[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  const std::uint16_t faces[2][4] = {{0, 1, 2, 0}, {1, 3, index, 0}};
  std::string v(2, '\0'), f(2, '\0');
  const std::uint16_t nv = 4, nf = 2;
  std::memcpy(&v[0], &nv, 2);
  std::memcpy(&f[0], &nf, 2);
  v.append(reinterpret_cast<const char*>(vertices), sizeof vertices);
  f.append(reinterpret_cast<const char*>(faces), sizeof faces);
  const std::string version = chunk(0x0002, std::string("\x03\0\0\0", 4));
  const std::string mesh = chunk(0x4100, chunk(0x4110, v) + chunk(0x4120, f));
  return chunk(0x4D4D, version + chunk(0x3D3D, chunk(0x4000, std::string("t\0", 2) + mesh)));
}

// One triangle; `transform` is placed in its node.
std::string dae(const std::string& count, const std::string& p, const std::string& transform) {
  return "<?xml version=\"1.0\"?>\n<COLLADA xmlns=\"http://www.collada.org/2005/11/COLLADASchema\" "
         "version=\"1.4.1\">\n<library_geometries><geometry id=\"g\"><mesh>\n<source id=\"p\">"
         "<float_array id=\"pa\" count=\"" + count + "\">0 0 0 1 0 0 0 1 0</float_array>\n<technique_common>"
         "<accessor source=\"#pa\" count=\"3\" stride=\"3\"><param name=\"X\" type=\"float\"/><param "
         "name=\"Y\" type=\"float\"/><param name=\"Z\" type=\"float\"/></accessor></technique_common>"
         "</source>\n<vertices id=\"v\"><input semantic=\"POSITION\" source=\"#p\"/></vertices>\n"
         "<triangles count=\"1\"><input semantic=\"VERTEX\" source=\"#v\" offset=\"0\"/><p>" + p +
         "</p></triangles>\n</mesh></geometry></library_geometries>\n<library_visual_scenes><visual_scene "
         "id=\"s\"><node id=\"n\">" + transform + "<instance_geometry url=\"#g\"/></node></visual_scene>"
         "</library_visual_scenes>\n<scene><instance_visual_scene url=\"#s\"/></scene></COLLADA>\n";
}

TEST(FaceIndices, ColladaCountsAndIndicesAreWholeNumbers) {
  TempDir dir;
  EXPECT_EQ(load_scene(dir.write("t.dae", dae("9", "0 1 2", "<!-- <skew> --> "))).num_facets, 1);
  const struct {
    std::string bytes, what;
  } cases[] = {
      {dae("-1", "0 1 2", ""), ":4: COLLADA count='-1' is not a whole number of at most 32 bits"},
      {[] {
         std::string d = dae("9", "0 1 2", "");
         return d.replace(d.find("offset=\"0\""), 10, "offset=\"-1\"");
       }(),
       ":7: COLLADA offset='-1' is not a whole number"},
      {[] {
         std::string d = dae("9", "0 1 2", "");
         return d.replace(d.find("stride=\"3\""), 10, "stride=\"0\"");
       }(),
       ":5: COLLADA stride='0' is not a whole number of at least 1"},
      {dae("9", "0 1 1.5", ""), ":7: COLLADA <p> index '1.5' is not an index"},
      {dae("9", "0 -1 2", ""), ":7: COLLADA <p> index '-1' is not an index"},
      {dae("9", "0 1 4294967297", ""), ":7: COLLADA <p> index '4294967297' is not an index"},
      {dae("9", "0 1 2", "<skew>45 0 1 0 1 0 0</skew>"), ":9: COLLADA <skew> (a shear) is a transform the importer"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.what);
    const std::string e = error_loading(dir.write("t.dae", c.bytes));
    EXPECT_NE(e.find(dir.file("t.dae") + c.what), std::string::npos) << e;
  }
}

TEST(FaceIndices, AFacePastItsVerticesIsNamedWithItsLine) {
  TempDir dir;
  struct Case {
    std::string file, good, bad, what;
  };
  const Case cases[] = {
      {"t.ase", ase("2"), ase("9"), ":15: ASE *MESH_FACE 1: corner C names vertex '9', past *MESH_NUMVERTEX 4"},
      {"t.ac", ac3d("2", "0"), ac3d("9", "0"), ":24: AC3D surface reference names vertex '9', past its OBJECT's "
                                               "numvert 4 (indices 0 to 3)"},
      {"t.ac", ac3d("2", "0"), ac3d("2", "7"), ":20: AC3D surface's mat names material '7', past the 1 MATERIAL"},
      {"t.x", x_text("2"), x_text("9"), ":11: DirectX Mesh face 2 of 2 names vertex '9', past the Mesh's 4 vertices"},
      {"t.x", x_text("2"), x_text("-1"), ":11: DirectX Mesh face 2 of 2 names vertex '-1', which is not an index"},
      {"t.3ds", three_ds(2), three_ds(9), ": a 3DS face names a vertex past its mesh's vertex list"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    EXPECT_EQ(load_scene(dir.write(c.file, c.good)).num_facets, 2);
    const std::string e = error_loading(dir.write(c.file, c.bad));
    EXPECT_NE(e.find(dir.file(c.file) + c.what), std::string::npos) << e;
  }
}

// A binary FBX object the importer cannot read (an index past the
// vertices, an array that does not inflate) was left out with its mesh,
// exit 0 where another mesh remained; its error is heard and the file
// refused, quoting the object's byte. A damaged array is named before the
// import, with its node and byte.
TEST(FaceIndices, FbxObjectsTheImporterCannotReadAreRefused) {
  const std::string box = "/usr/share/assimp/models/FBX/box.fbx", cube = "/usr/share/assimp/models/FBX/phong_cube.fbx";
  if (!std::filesystem::exists(box) || !std::filesystem::exists(cube))
    GTEST_SKIP() << "Debian package assimp-testmodels is not installed";
  TempDir dir;
  // box.fbx stores its indices plainly: 'i', count, encoding 0, bytes, values.
  std::string index = test::read_file(box);
  const std::size_t at = index.find("PolygonVertexIndex") + 18 + 1 + 12;
  const std::int32_t past = 100000;
  std::memcpy(&index[at], &past, 4);
  // phong_cube.fbx deflates its vertices: 'd', count, encoding 1, bytes, zlib.
  std::string deflated = test::read_file(cube);
  const std::size_t z = deflated.find("Vertices") + 8 + 1 + 12;
  for (std::size_t k = 10; k < 20; ++k) deflated[z + k] = char(~deflated[z + k]);
  EXPECT_GT(load_scene(dir.write("box.fbx", test::read_file(box))).num_facets, 0);
  std::string e = error_loading(dir.write("box.fbx", index));
  EXPECT_NE(e.find(dir.file("box.fbx") + ": an FBX object the importer cannot read (it would leave it and the mesh "
                                         "that uses it out) (the importer: FBX-DOM (TOK_KEY, offset 0x"),
            std::string::npos) << e;
  e = error_loading(dir.write("cube.fbx", deflated));
  EXPECT_NE(e.find(dir.file("cube.fbx") + ": FBX array Vertices at byte " + std::to_string(z - 13) +
                   ": its compressed data is not a valid zlib stream ("),
            std::string::npos)
      << e;
}

// A compressed array whose count says more than its stream holds was read
// with zeros for the rest (vertices at the origin), exit 0; one that says
// less, refused in words naming no array. Both name the array and its byte.
TEST(FaceIndices, FbxArraysInflateToWhatTheirCountsSay) {
  const std::string cube = "/usr/share/assimp/models/FBX/phong_cube.fbx";
  if (!std::filesystem::exists(cube)) GTEST_SKIP() << "Debian package assimp-testmodels is not installed";
  TempDir dir;
  const std::string good = test::read_file(cube);
  const std::size_t type = good.find("Vertices") + 8;  // 'd', count, encoding 1, bytes, zlib
  ASSERT_EQ(good[type], 'd');
  std::int32_t count;
  std::memcpy(&count, &good[type + 1], 4);
  const auto with_count = [&](std::int32_t n) {
    std::string bytes = good;
    std::memcpy(&bytes[type + 1], &n, 4);
    return bytes;
  };
  EXPECT_GT(load_scene(dir.write("cube.fbx", good)).num_facets, 0);
  const std::string at = ": FBX array Vertices at byte " + std::to_string(type) + ": its compressed data inflates to ";
  const std::string all = std::to_string(8 * count);
  std::string e = error_loading(dir.write("more.fbx", with_count(count + 3)));
  EXPECT_NE(e.find(dir.file("more.fbx") + at + all + " of the " + std::to_string(8 * (count + 3)) +
                   " bytes its count gives (damaged or cut short: the model importer would read zeros for the rest)"),
            std::string::npos) << e;
  e = error_loading(dir.write("less.fbx", with_count(count - 3)));
  EXPECT_NE(e.find(dir.file("less.fbx") + at + "more than the " + std::to_string(8 * (count - 3)) + " bytes"),
            std::string::npos) << e;
  // A stream that is not zlib's, and one whose byte length cuts it short.
  const std::string array = ": FBX array Vertices at byte " + std::to_string(type) + ": its compressed data ";
  std::string bad = good;
  bad[type + 13] = 0;  // the zlib header's first byte
  e = error_loading(dir.write("bad.fbx", bad));
  EXPECT_NE(e.find(dir.file("bad.fbx") + array + "is not a valid zlib stream ("), std::string::npos) << e;
  std::string cut = good;
  std::int32_t length;
  std::memcpy(&length, &cut[type + 9], 4);
  length /= 2;
  std::memcpy(&cut[type + 9], &length, 4);
  e = error_loading(dir.write("cut.fbx", cut));
  EXPECT_NE(e.find(dir.file("cut.fbx") + array + "ends before its zlib stream does"), std::string::npos) << e;
}

// Counts the importer allocated for before reading a value (past 1 GiB, or
// out of memory): one the file cannot hold is named with its line.
TEST(FaceIndices, CountsTheFileCannotHoldAreNamed) {
  TempDir dir;
  std::string big_ase = ase("2");
  big_ase.replace(big_ase.find("*MESH_NUMVERTEX 4"), 17, "*MESH_NUMVERTEX 400000000");
  std::string big_ac = ac3d("2", "0");
  big_ac.replace(big_ac.find("kids 1"), 6, "kids 1000000000");
  std::string big_x = x_text("2");
  big_x.replace(big_x.find(" 2;\n"), 4, " 400000000;\n");
  const struct {
    std::string file, bytes, what;
  } cases[] = {
      {"t.ase", big_ase, ":5: ASE *MESH_NUMVERTEX 400000000 is more than a file of "},
      {"t.ac", big_ac, ":4: AC3D kids 1000000000 is more than a file of "},
      {"t.x", big_x, ":9: DirectX Mesh face count 400000000 is more than a file of "},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.what);
    const std::string e = error_loading(dir.write(c.file, c.bytes));
    EXPECT_NE(e.find(dir.file(c.file) + c.what), std::string::npos) << e;
  }
}

}  // namespace
}  // namespace opsila
