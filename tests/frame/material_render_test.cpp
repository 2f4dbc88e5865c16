// CONTRACT's material rules on real models of Debian's assimp-testmodels (NFF,
// glTF 1, IQM, SMD, HL1 MDL) and on an OBJ/MTL: the OpenCL image against the
// sequential reference, and the colours the rules give. Under the rules
// before (a name decided "no material"; a texture-only material had Kd = 0)
// these models drew default grey or black: each case checks what that would
// have failed.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>

#include "formats/json/scene_file.h"
#include "frame/renderer.h"
#include "reference/reference.h"
#include "test_device.h"
#include "test_render.h"
#include "test_util.h"

namespace opsila {
namespace {

namespace fs = std::filesystem;

const fs::path kModels = "/usr/share/assimp/models";

// What the pixels that see the model look like.
struct Look {
  double lit = 0;        // fraction that is not black (a channel above 0.02)
  double coloured = 0;   // fraction whose channels differ by more than 0.1
};

Look look_of(const ImageResult& r) {
  Look l;
  int seen = 0;
  for (std::size_t p = 0; p * 2 < r.item_buffer.size(); ++p) {
    if (r.item_buffer[2 * p] < 0) continue;
    const float* c = &r.rgb[3 * p];
    const float hi = std::max({c[0], c[1], c[2]}), lo = std::min({c[0], c[1], c[2]});
    ++seen;
    l.lit += hi > 0.02f;
    l.coloured += hi - lo > 0.1f;
  }
  if (seen > 0) l.lit /= seen, l.coloured /= seen;
  return l;
}

// A bare model as the command line shows it: framed, lit from the eye.
Scene bare_model(const std::string& path) { return test::framed_model(path, 48, 36); }

// The OpenCL image on 1 and 16 PEs agrees with the reference; returns the
// reference's look.
Look render_and_compare(const Scene& s) {
  const ImageResult ref = render_reference(s);
  for (int pes : {1, 16}) {
    SCOPED_TRACE(std::to_string(pes) + " PEs");
    const RenderResult r = test::render_on_pes(s, pes);
    test::expect_near_reference(r, ref, 0.01, 0.995);
    const Look cl = look_of(r), want = look_of(ref);
    EXPECT_NEAR(cl.lit, want.lit, 0.02);
    EXPECT_NEAR(cl.coloured, want.coloured, 0.02);
  }
  return look_of(ref);
}

struct ModelCase {
  const char* file;
  double min_lit, min_coloured;  // what the rules before could not reach
};

void PrintTo(const ModelCase& c, std::ostream* os) { *os << c.file; }

class MaterialRules : public ::testing::TestWithParam<ModelCase> {};

TEST_P(MaterialRules, ImportedModelMatchesReferenceInItsColours) {
  const fs::path path = kModels / GetParam().file;
  if (!fs::exists(path)) GTEST_SKIP() << "Debian package assimp-testmodels is not installed";
  const Look l = render_and_compare(bare_model(path.string()));
  EXPECT_GE(l.lit, GetParam().min_lit);
  EXPECT_GE(l.coloured, GetParam().min_coloured);
}

// NFF: red, green and blue materials named DefaultMaterial (were all grey:
// nothing coloured). HL1 MDL: unnamed textured materials (were grey).
// glTF 1, IQM, SMD: a texture and no diffuse colour (were black, but for
// highlights; IQM's and SMD's materials have none, so wholly black).
INSTANTIATE_TEST_SUITE_P(
    TestModels, MaterialRules,
    ::testing::Values(ModelCase{"NFF/NFF/WithCamera.nff", 0.9, 0.2}, ModelCase{"MDL/MDL (HL1)/man.mdl", 0.9, 0.5},
                      ModelCase{"glTF/CesiumMilkTruck/CesiumMilkTruck.gltf", 0.8, 0.05},
                      ModelCase{"IQM/mrfixit.iqm", 0.3, 0.0}, ModelCase{"SMD/holy_grailref.smd", 0.8, 0.1}),
    [](const ::testing::TestParamInfo<ModelCase>& p) {
      const std::string f = fs::path(p.param.file).extension().string().substr(1);
      return f == "gltf" ? std::string("glTF1") : f;
    });

// OBJ/MTL: a material with a map_Kd and no Kd is the texture's colour (it
// was black); the same map beside a stated Kd is that colour times the map.
TEST(MaterialRulesObj, MapWithoutKdIsTheTexturesColour) {
  test::TempDir dir;
  dir.write("red.tga", test::tga(2, 2, {{200, 30, 30}, {200, 30, 30}, {200, 30, 30}, {200, 30, 30}}));
  dir.write("m.mtl", "newmtl only_map\nmap_Kd red.tga\nnewmtl dim\nKd 0.25 0.25 0.25\nmap_Kd red.tga\n");
  const std::string quad = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n";
  const Scene bright = bare_model(dir.write("a.obj", quad + "usemtl only_map\nf 1/1 2/2 3/3 4/4\n"));
  const Scene dim = bare_model(dir.write("b.obj", quad + "usemtl dim\nf 1/1 2/2 3/3 4/4\n"));
  const Look l = render_and_compare(bright);
  EXPECT_GE(l.lit, 0.99);
  EXPECT_GE(l.coloured, 0.99);
  // Kd (1,1,1) x the texel: the red channel is 4x that of Kd = 0.25.
  const ImageResult a = render_reference(bright), b = render_reference(dim);
  for (std::size_t p = 0; p * 2 < a.item_buffer.size(); ++p) {
    if (a.item_buffer[2 * p] < 0) continue;
    EXPECT_GT(a.rgb[3 * p], a.rgb[3 * p + 1] * 3) << "pixel " << p;  // red, not grey
    EXPECT_NEAR(a.rgb[3 * p], 4 * b.rgb[3 * p], 1e-4f * a.rgb[3 * p] + 1e-6f) << "pixel " << p;
  }
}

}  // namespace
}  // namespace opsila
