// CONTRACT's barycentric attributes on the host: OBJ vt/vn and face references,
// MTL texture maps (options, Windows paths, missing images), texture decoding
// and sampling against hand-computed texels, and where the partition puts
// attributes and texels. No OpenCL needed.
#include <gtest/gtest.h>

#include <array>
#include <cstdlib>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "formats/image/image_io.h"
#include "scene/texture.h"
#include "formats/obj/obj_loader.h"
#include "formats/json/scene_file.h"
#include "formats/image/texture_file.h"
#include "partition/partition.h"
#include "test_scenes.h"
#include "png_crc.h"
#include "test_util.h"

namespace opsila {
namespace {

Scene from_text(const std::string& text) { return load_obj_from_string(text, "t.obj", ""); }

std::string error_of(const std::string& text) {
  return test::error_of([&] { from_text(text); });
}

bool has_warning(const Scene& s, const std::string& a, const std::string& b = "") {
  for (const std::string& w : s.warnings)
    if (w.find(a) != std::string::npos && w.find(b) != std::string::npos) return true;
  return false;
}

using test::tga;

float lin(int code) { return srgb_decode_table()[code]; }

// ------------------------------------------------------------ OBJ vt / vn

TEST(ObjAttributes, FaceReferencesCarryCoordinatesAndNormalsPerFanTriangle) {
  const Scene s = from_text(
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
      "vt 0 0\nvt 1 0\nvt 1 1 0\nvt 0.5\n"
      "vn 0 0 1\nvn 0 1 0\nvn 1 0 0\nvn 0 0 2\n"
      "f 1/1/1 2/2/2 3/3/3 4/4/4\n"  // quad: two fan triangles, both attributes
      "f 1//4 2//3 3//2\n"           // normals only
      "f 1/4 3/3 4/1\n"              // coordinates only
      "f 1 2 3\n"                    // nothing
      "f 1/1 2/2/2 3\n");            // mixed corners: none complete
  ASSERT_EQ(s.triangles.size(), 6u);
  ASSERT_GE(s.triangles[0].attributes, 0);
  const VertexAttributes& a0 = s.attributes[s.triangles[0].attributes];
  const VertexAttributes& a1 = s.attributes[s.triangles[1].attributes];
  EXPECT_TRUE(a0.has_uv && a0.has_normals);
  // Fan (v1 v2 v3), (v1 v3 v4): corner k of each triangle is its own vertex.
  EXPECT_EQ(a0.normal[1], (Vec3{0, 1, 0}));
  EXPECT_EQ(a1.normal[2], (Vec3{0, 0, 2}));  // kept as written; shading normalises
  EXPECT_EQ(a1.uv[1][0], 1.0f);
  EXPECT_EQ(a1.uv[2][0], 0.5f);
  EXPECT_EQ(a1.uv[2][1], 0.0f);  // "vt u": v defaults to 0
  const VertexAttributes& a2 = s.attributes[s.triangles[2].attributes];
  EXPECT_TRUE(a2.has_normals);
  EXPECT_FALSE(a2.has_uv);
  EXPECT_EQ(a2.normal[0], (Vec3{0, 0, 2}));
  const VertexAttributes& a3 = s.attributes[s.triangles[3].attributes];
  EXPECT_TRUE(a3.has_uv);
  EXPECT_FALSE(a3.has_normals);
  EXPECT_EQ(s.triangles[4].attributes, -1);
  EXPECT_EQ(s.triangles[5].attributes, -1);
  EXPECT_EQ(s.triangles[0].facet_id, s.triangles[1].facet_id);
}

TEST(ObjAttributes, NegativeAndForwardIndicesOfCoordinatesAndNormals) {
  const Scene s = from_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0.25 0.75\nvn 0 0 1\n"
                            "f -3/-1/-1 -2/1/1 -1/2/2\nvt 0.5 0.5\nvn 1 0 0\n");
  ASSERT_EQ(s.triangles.size(), 1u);
  const VertexAttributes& a = s.attributes[s.triangles[0].attributes];
  EXPECT_EQ(a.uv[0][0], 0.25f);
  EXPECT_EQ(a.uv[2][1], 0.5f);
  EXPECT_EQ(a.normal[2], (Vec3{1, 0, 0}));
}

TEST(ObjAttributes, BadCoordinatesAndNormalsGiveOnePreciseMessage) {
  const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  EXPECT_NE(error_of(tri + "vn 0 1\n").find("t.obj:4: truncated 'vn' line"), std::string::npos);
  EXPECT_NE(error_of(tri + "vt nan 0\n").find("t.obj:4: 'vt' value 1 'nan'"), std::string::npos);
  EXPECT_NE(error_of(tri + "vt 0 0 0 0\n").find("t.obj:4: 'vt' line has more than 3 values"), std::string::npos);
  EXPECT_NE(error_of(tri + "f 1/0 2/1 3/1\n").find("t.obj:4: bad vertex reference '1/0'"), std::string::npos);
}

TEST(ObjAttributes, CoordinatesAndNormalsThatDoNotExistAreAWarning) {
  const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  const Scene a = from_text(tri + "vt 0 0\nf 1/2 2/1 3/1\nf 1/1 2/1 3/1\n");
  EXPECT_EQ(a.triangles[0].attributes, -1);
  EXPECT_GE(a.triangles[1].attributes, 0);
  EXPECT_TRUE(has_warning(a, "t.obj:5: 1 face corner(s) name texture coordinates the file does not define"));
  const Scene b = from_text(tri + "vn 0 0 1\nf 1//1 2//1 3//7\nf 1//-2 2//1 3//1\n");
  EXPECT_EQ(b.triangles[0].attributes, -1);
  EXPECT_EQ(b.triangles[1].attributes, -1);
  EXPECT_TRUE(has_warning(b, "2 face corner(s) name normals the file does not define"));
}

// --------------------------------------------------------------- MTL maps

TEST(MtlMaps, OptionsAreSkippedAndWindowsPathsResolved) {
  test::TempDir dir;
  dir.write("tex.tga", tga(1, 1, {{255, 0, 0}}));
  dir.write("sub_a.tga", tga(1, 1, {{0, 255, 0}}));
  dir.write("m.mtl",
            "newmtl a\nKd 1 1 1\nmap_Kd -s 1 1 1 -o 0 0 -bm 1 .\\tex.tga\n"
            "newmtl b\nKa 1 1 1\nmap_Ka -clamp off C:\\Users\\someone\\textures\\sub_a.tga\n"
            "newmtl c\nmap_Kd missing.png\n"
            "newmtl d\nmap_Kd m.mtl\n");
  dir.write("e.tga", tga(1, 1, {{1, 2, 3}}));
  dir.write("-dash.tga", tga(1, 1, {{4, 5, 6}}));  // a name, not an option: MTL defines none such
  dir.write("e.mtl", "newmtl e\nmap_Kd e.tga\nnewmtl f\nmap_Kd -clamp on -dash.tga\n");
  const std::string obj = dir.write("m.obj", "mtllib m.mtl e.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\n"
                                              "usemtl a\nf 1/1 2/1 3/1\nusemtl b\nf 1/1 2/1 3/1\n"
                                              "usemtl c\nf 1/1 2/1 3/1\nusemtl d\nf 1/1 2/1 3/1\n"
                                              "usemtl e\nf 1 2 3\nusemtl f\nf 1/1 2/1 3/1\n");
  const Scene s = load_obj(obj);
  ASSERT_EQ(s.materials.size(), 7u);
  ASSERT_GE(s.materials[6].map_kd, 0);
  EXPECT_EQ(s.textures.at(std::size_t(s.materials[6].map_kd)).texels[0], 0x060504u);
  EXPECT_EQ(s.materials[5].map_kd, -1);  // only faces without coordinates: never read
  ASSERT_EQ(s.textures.size(), 3u);
  EXPECT_EQ(s.materials[1].map_kd, 0);
  EXPECT_EQ(s.textures[0].texels[0], 0x0000ffu);
  EXPECT_EQ(s.materials[2].map_ka, 1);  // found beside the MTL by its base name
  EXPECT_EQ(s.textures[1].texels[0], 0x00ff00u);
  EXPECT_EQ(s.materials[3].map_kd, -1);
  EXPECT_EQ(s.materials[4].map_kd, -1);
  EXPECT_TRUE(has_warning(s, "m.mtl:3:", "-s, -o ignored"));
  EXPECT_TRUE(has_warning(s, "material 'c'", "missing.png' ignored"));
  EXPECT_TRUE(has_warning(s, "material 'd'", "not a readable PNG, JPEG, TGA or BMP image"));
  // Blender's "//sub/x.tga" is sub/x.tga beside the model, not /sub/x.tga.
  std::filesystem::create_directory(dir.file("sub"));
  dir.write("sub/x.tga", tga(1, 1, {{0, 0, 255}}));
  dir.write("b.mtl", "newmtl f\nmap_Kd //sub/x.tga\n");
  const Scene blender = load_obj(dir.write("b.obj", "mtllib b.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\n"
                                                    "usemtl f\nf 1/1 2/1 3/1\n"));
  ASSERT_EQ(blender.textures.size(), 1u);
  EXPECT_EQ(blender.textures[0].texels[0], 0xff0000u);
}

// CONTRACT: a material with a map_Kd (map_Ka) but no Kd (Ka) takes (1, 1, 1),
// in whatever order the keys come; a colour the material states is kept,
// and one it leaves out without a map is 0.
TEST(MtlMaps, MapWithoutItsColourTakesOne) {
  std::vector<std::string> warnings;
  const std::vector<MaterialDesc> m = parse_mtl(
      "newmtl only_map\nmap_Kd t.png\n"
      "newmtl map_then_kd\nmap_Kd t.png\nKd 0.5 0.25 0\n"
      "newmtl ambient_map\nmap_Ka t.png\nKd 0.2\n"
      "newmtl none\nNs 3\n"
      "newmtl empty_map\nmap_Kd\n",
      "m.mtl", warnings);
  ASSERT_EQ(m.size(), 5u);
  EXPECT_EQ(m[0].kd, (Vec3{1, 1, 1}));
  EXPECT_EQ(m[0].ka, (Vec3{0, 0, 0}));
  EXPECT_EQ(m[1].kd, (Vec3{0.5f, 0.25f, 0}));
  EXPECT_EQ(m[2].ka, (Vec3{1, 1, 1}));
  EXPECT_EQ(m[2].kd, (Vec3{0.2f, 0.2f, 0.2f}));
  EXPECT_EQ(m[3].kd, (Vec3{0, 0, 0}));
  EXPECT_EQ(m[4].kd, (Vec3{0, 0, 0}));  // a map statement without a file is no map
}

// ------------------------------------------------------ decoding, sampling

TEST(Textures, DecodeKeepsTopRowFirstAndSrgbCodes) {
  const std::string bytes = tga(2, 2, {{10, 20, 30}, {40, 50, 60}, {70, 80, 90}, {255, 128, 0}});
  Texture t;
  std::string problem;
  ASSERT_TRUE(decode_texture_memory(reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size(), "x", t,
                                    problem))
      << problem;
  ASSERT_EQ(t.width, 2);
  ASSERT_EQ(t.height, 2);
  EXPECT_EQ(t.texels[0], 10u | 20u << 8 | 30u << 16);
  EXPECT_EQ(t.texels[3], 255u | 128u << 8);
  const std::string junk = "not an image at all";
  EXPECT_FALSE(decode_texture_memory(reinterpret_cast<const unsigned char*>(junk.data()), junk.size(), "x", t,
                                     problem));
  EXPECT_NE(problem.find("not a readable"), std::string::npos);
}

// A PNG too large says its size (stb would go on to the other formats and
// say only "unknown type"); a truncated one says it is truncated.
TEST(Textures, PngTooLargeOrTruncatedSaysWhy) {
  const std::string ok = encode_png(4, 4, std::vector<float>(4 * 4 * 3, 0.5f));
  const auto problem_of = [](const std::string& bytes) {
    Texture t;
    std::string problem;
    EXPECT_FALSE(decode_texture_memory(reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size(), "x", t,
                                       problem));
    return problem;
  };
  Texture t;
  std::string problem;
  ASSERT_TRUE(decode_texture_memory(reinterpret_cast<const unsigned char*>(ok.data()), ok.size(), "x", t, problem))
      << problem;
  std::string large = ok;
  large.replace(16, 8, std::string("\x00\x00\xea\x60\x00\x00\x00\x04", 8));  // IHDR width 60000
  reseal_png_chunk(large, 8);
  EXPECT_EQ(problem_of(large), "image too large (60000x4)");
  const std::string truncated = problem_of(ok.substr(0, 45));
  EXPECT_EQ(truncated, "cannot decode the image (truncated PNG: it ends before its IEND chunk)");
}

// A 24-bit BMP of w x h pixels (given top row first); a negative height
// stores them top-down, a positive one bottom-up, as the format allows.
std::string bmp(int w, int h, const std::vector<std::array<unsigned char, 3>>& rgb) {
  const int rows = std::abs(h), pitch = (3 * w + 3) / 4 * 4;
  const auto le32 = [](std::string& s, std::int64_t v) {
    for (int i = 0; i < 4; ++i) s += char((std::uint64_t(v) >> (8 * i)) & 0xff);
  };
  std::string s = "BM";
  le32(s, 54 + std::int64_t(pitch) * rows);
  le32(s, 0);
  le32(s, 54);
  le32(s, 40), le32(s, w), le32(s, h);
  s += std::string("\x01\x00\x18\x00", 4);  // one plane, 24 bits
  for (int i = 0; i < 6; ++i) le32(s, 0);
  for (int r = 0; r < rows && !rgb.empty(); ++r) {
    const int row = h < 0 ? r : rows - 1 - r;
    std::string line(std::size_t(pitch), '\0');
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) line[std::size_t(3 * x + c)] = char(rgb[std::size_t(row * w + x)][2 - c]);
    s += line;
  }
  return s;
}

TEST(Textures, TopDownBmpDecodesAndSaysItsSize) {
  const std::vector<std::array<unsigned char, 3>> px = {{10, 20, 30}, {40, 50, 60}, {70, 80, 90}, {255, 128, 0}};
  for (int h : {2, -2}) {
    const std::string bytes = bmp(2, h, px);
    Texture t;
    std::string problem;
    ASSERT_TRUE(decode_texture_memory(reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size(), "x", t,
                                      problem))
        << h << ": " << problem;
    ASSERT_EQ(t.height, 2);
    EXPECT_EQ(t.texels[0], 10u | 20u << 8 | 30u << 16) << h;
    EXPECT_EQ(t.texels[3], 255u | 128u << 8) << h;
  }
  const std::string huge = bmp(20000, -20000, {});
  Texture t;
  std::string problem;
  EXPECT_FALSE(decode_texture_memory(reinterpret_cast<const unsigned char*>(huge.data()), huge.size(), "x", t, problem));
  EXPECT_EQ(problem, "image too large (20000x20000)");
}

// A BMP or TGA shorter than its header says is refused (stb would decode
// the missing pixels as zeros: a few bytes claiming 16384 x 4096 were half
// a gigabyte of black); run-length TGA is bounded by its packets.
TEST(Textures, TruncatedBmpAndTgaSayWhy) {
  const auto problem_of = [](const std::string& bytes) {
    Texture t;
    std::string problem;
    decode_texture_memory(reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size(), "x", t, problem);
    return problem;
  };
  const std::string whole = bmp(2, 2, {{1, 2, 3}, {4, 5, 6}, {7, 8, 9}, {10, 11, 12}});
  EXPECT_EQ(problem_of(whole), "");
  EXPECT_EQ(problem_of(whole.substr(0, whole.size() - 1)),
            "cannot decode the image (truncated BMP: 2x2 needs at least 70 bytes, the file has 69)");
  // TGA: 18-byte header, type 2 (true colour) or 10 (its run-length form), 4 x 4, 24 bits.
  const auto tga = [](char type, const std::string& body) {
    return std::string("\0\0", 2) + type + std::string(9, '\0') + std::string("\x04\0\x04\0\x18\0", 6) + body;
  };
  EXPECT_EQ(problem_of(tga(2, std::string(48, '\x40'))), "");
  EXPECT_EQ(problem_of(tga(2, std::string(47, '\x40'))),
            "cannot decode the image (truncated TGA: 4x4 needs at least 66 bytes, the file has 65)");
  EXPECT_EQ(problem_of(tga(10, "\x8f\x01\x02\x03")), "") << "one packet of 16 pixels";
  EXPECT_NE(problem_of(tga(10, "")).find("truncated TGA"), std::string::npos);
}

TEST(Textures, SrgbDecodeTable) {
  EXPECT_EQ(lin(0), 0.0f);
  EXPECT_EQ(lin(255), 1.0f);
  EXPECT_NEAR(lin(10), 10 / 255.0 / 12.92, 1e-7);  // linear segment
  EXPECT_NEAR(lin(128), 0.2158605, 1e-6);
  EXPECT_NEAR(lin(188), 0.5028865, 1e-6);
}

TEST(Textures, TexelCentresBilinearAndRepeat) {
  // 4 x 2 texels; red code = 60 i + 10, green code = 100 j + 50.
  const Texture t = test::make_texture(4, 2, [](int i, int j) { return std::array<int, 3>{60 * i + 10, 100 * j + 50, 7}; });
  const auto red = [&](int i) { return lin(60 * i + 10); };
  const auto green = [&](int j) { return lin(100 * j + 50); };
  // Texel (i, j)'s centre: u = (i + 0.5) / 4, v = 1 - (j + 0.5) / 2.
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 4; ++i) {
      const Vec3 c = sample_texture(t, (i + 0.5f) / 4, 1.0f - (j + 0.5f) / 2);
      EXPECT_FLOAT_EQ(c[0], red(i)) << i << "," << j;
      EXPECT_FLOAT_EQ(c[1], green(j)) << i << "," << j;
      EXPECT_FLOAT_EQ(c[2], lin(7));
    }
  // Halfway between texel centres: the mean of the decoded (linear) values.
  const Vec3 mid = sample_texture(t, 0.25f, 0.75f);  // between i = 0, 1 on row j = 0
  EXPECT_NEAR(mid[0], 0.5f * (red(0) + red(1)), 1e-6);
  const Vec3 quarter = sample_texture(t, 0.125f + 0.0625f, 0.5f);  // i: 0 -> 1 at 1/4, j: 0 -> 1 at 1/2
  EXPECT_NEAR(quarter[0], 0.75f * red(0) + 0.25f * red(1), 1e-6);
  EXPECT_NEAR(quarter[1], 0.5f * (green(0) + green(1)), 1e-6);
  // Repeat: whole periods do not change the value; u = 0 blends the last and
  // the first column, v = 1 the last and first rows.
  const Vec3 a = sample_texture(t, 0.3f, 0.6f);
  for (float du : {-2.0f, -1.0f, 1.0f, 3.0f}) {
    const Vec3 b = sample_texture(t, 0.3f + du, 0.6f - du);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(a[k], b[k], 1e-5) << du;
  }
  const Vec3 edge = sample_texture(t, 0.0f, 1.0f);
  EXPECT_NEAR(edge[0], 0.5f * (red(3) + red(0)), 1e-6);
  EXPECT_NEAR(edge[1], 0.5f * (green(1) + green(0)), 1e-6);
  // Not finite: read as 0.
  const Vec3 nan = sample_texture(t, NAN, INFINITY);
  const Vec3 zero = sample_texture(t, 0.0f, 0.0f);
  EXPECT_EQ(nan, zero);
}

// ---------------------------------------------------------------- banks --

TEST(BankAttributes, TexelsLiveInEveryBankThatUsesThem) {
  const Scene s = test::textured_smooth_scene(64, true);
  for (int pes : {1, 4, 16}) {
    SCOPED_TRACE(pes);
    const BankedScene bs = partition_scene(s, pes);
    ASSERT_EQ(bs.attributes.size(), bs.triangles.size());
    ASSERT_EQ(bs.texture_bytes.size(), std::size_t(pes));
    std::uint64_t once = 0;
    for (const Texture& t : s.textures) once += t.texels.size() * 4 + sizeof(BankTexture);
    EXPECT_EQ(bs.texture_replicated_bytes, once);
    std::uint64_t sum = 0;
    for (int p = 0; p < pes; ++p) {
      const PeInfo& pe = bs.pes[p];
      std::uint64_t expect = 0;
      std::vector<int> seen;
      for (int k = pe.tri_begin; k < pe.tri_end; ++k) {
        const BankAttributes& a = bs.attributes[k];
        for (int map : {a.map_kd, a.map_ka}) {
          if (map < 0) continue;
          EXPECT_EQ(bs.textures[map].pe, p) << "a facet reads a texture copy of another bank";
          if (std::find(seen.begin(), seen.end(), map) == seen.end()) {
            seen.push_back(map);
            expect += std::uint64_t(bs.textures[map].width) * bs.textures[map].height * 4 + sizeof(BankTexture);
          }
        }
      }
      EXPECT_EQ(bs.texture_bytes[p], expect);
      sum += bs.texture_bytes[p];
    }
    EXPECT_GE(sum, once);  // shared maps are copied into each bank using them
    EXPECT_EQ(frame_params(s, bs, 1).has_attributes, 1);
  }
}

TEST(BankAttributes, NormalsOnlyWhenSmoothAndCoordinatesOnlyWithAMap) {
  Scene s = test::textured_smooth_scene(64, false);
  const BankedScene flat = partition_scene(s, 4);
  for (std::size_t k = 0; k < flat.attributes.size(); ++k)
    EXPECT_EQ(flat.attributes[k].flags & OPSILA_ATTR_NORMALS, 0);
  // Without maps and without smooth shading nothing is stored at all.
  for (MaterialDesc& m : s.materials) m.map_kd = m.map_ka = -1;
  const BankedScene none = partition_scene(s, 4);
  EXPECT_TRUE(none.attributes.empty());
  EXPECT_TRUE(none.texels.empty());
  EXPECT_EQ(frame_params(s, none, 1).has_attributes, 0);
  for (std::uint64_t b : none.texture_bytes) EXPECT_EQ(b, 0u);
}

// ------------------------------------------------------------ scene file

// A textured model included three times holds its map once: each include's
// materials name the one copy (twelve includes of a map of 8192 x 8192
// held twelve copies, 3 GB beyond one).
TEST(SceneIncludes, AMapSeveralIncludesNameIsHeldOnce) {
  test::TempDir dir;
  dir.write("t.png", encode_png(4, 4, std::vector<float>(4 * 4 * 3, 0.5f)));
  dir.write("t.mtl", "newmtl m\nKd 1 1 1\nmap_Kd t.png\nnewmtl n\nKd 1 1 1\nmap_Ka t.png\n");
  dir.write("t.obj", "mtllib t.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl m\nf 1/1 2/2 3/3\n"
                     "usemtl n\nf 1/1 3/3 2/2\n");
  std::string objects;
  for (int k = 0; k < 3; ++k)
    objects += std::string(k ? "," : "") + R"({"type": "obj", "file": "t.obj", "transform": {"translate": [)" +
               std::to_string(2 * k) + ", 0, 0]}}";
  const Scene s = load_scene(dir.write("s.json", "{\"objects\": [" + objects + "]}"));
  ASSERT_EQ(s.textures.size(), 1u);
  EXPECT_EQ(s.textures[0].width, 4);
  ASSERT_EQ(s.materials.size(), 7u);  // the default, then m and n of each include
  for (std::size_t k = 1; k < s.materials.size(); ++k)
    EXPECT_EQ(k % 2 ? s.materials[k].map_kd : s.materials[k].map_ka, 0) << k;
}

// One image file under other names (a symbolic link, a hard link) is one
// map, in one OBJ's materials and across includes: each name held another
// copy of its texels (a 200 KB PNG of 8192 x 8192 is 256 MiB of them).
TEST(SceneIncludes, AMapUnderOtherNamesIsHeldOnce) {
  test::TempDir dir;
  const std::string png = dir.write("t.png", encode_png(4, 4, std::vector<float>(4 * 4 * 3, 0.5f)));
  std::filesystem::create_symlink("t.png", dir.file("soft.png"));
  std::filesystem::create_hard_link(png, dir.file("hard.png"));
  dir.write("t.mtl", "newmtl m\nKd 1 1 1\nmap_Kd t.png\nnewmtl n\nKd 1 1 1\nmap_Kd soft.png\n");
  dir.write("u.mtl", "newmtl h\nKd 1 1 1\nmap_Kd hard.png\n");
  const std::string face = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n";
  const std::string t = dir.write("t.obj", "mtllib t.mtl\n" + face + "usemtl m\nf 1/1 2/2 3/3\nusemtl n\nf 1/1 3/3 2/2\n");
  dir.write("u.obj", "mtllib u.mtl\n" + face + "usemtl h\nf 1/1 2/2 3/3\n");
  const Scene alone = load_obj(t);
  ASSERT_EQ(alone.textures.size(), 1u);
  EXPECT_EQ(alone.materials.at(1).map_kd, 0);
  EXPECT_EQ(alone.materials.at(2).map_kd, 0);
  const Scene s = load_scene(dir.write("s.json", R"({"objects": [{"type": "obj", "file": "t.obj"},
    {"type": "obj", "file": "u.obj", "transform": {"translate": [2, 0, 0]}}]})"));
  ASSERT_EQ(s.textures.size(), 1u);
  ASSERT_EQ(s.materials.size(), 4u);
  for (std::size_t k = 1; k < s.materials.size(); ++k) EXPECT_EQ(s.materials[k].map_kd, 0) << k;
}

TEST(SceneSmooth, KeyAndIncludedObjNormalsFollowTheTransform) {
  test::TempDir dir;
  dir.write("n.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvn 1 0 0\nvn 0 1 0\nf 1//1 2//2 3//3\n");
  const std::string scene = dir.write(
      "s.json", R"({"smooth": true, "objects": [{"type": "box", "min": [0,0,0], "max": [1,1,1]},
        {"type": "obj", "file": "n.obj", "transform": {"rotate": [0, 90, 0], "scale": [2, 1, 1]}}]})");
  const Scene s = load_scene(scene);
  EXPECT_TRUE(s.smooth);
  ASSERT_EQ(s.attributes.size(), 1u);
  const Triangle& t = s.triangles.back();
  ASSERT_EQ(t.attributes, 0);
  const VertexAttributes& a = s.attributes[0];
  // Rotating (0, 0, 1) by 90 degrees about y gives (1, 0, 0); (1, 0, 0) is
  // scaled by 1/2 first, then rotated to (0, 0, -0.5).
  EXPECT_NEAR(a.normal[0][0], 1.0f, 1e-6);
  EXPECT_NEAR(a.normal[1][2], -0.5f, 1e-6);
  EXPECT_NEAR(a.normal[2][1], 1.0f, 1e-6);
  const std::string bad = dir.write("b.json", R"({"smooth": 1, "objects": [{"type": "box", "min": [0,0,0], "max": [1,1,1]}]})");
  try {
    load_scene(bad);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("smooth: expected true or false"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace opsila
