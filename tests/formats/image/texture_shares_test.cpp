// Texture maps whose images are read later (MapImages::later,
// formats/image/texture_file.h): add_texture_file lists the map and a
// MapRequest where its warning would go; the requests keep their places as
// warnings are joined; settling them gives one process's warnings in one
// process's places, and its texture table.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "formats/image/texture_file.h"
#include "scene/scene.h"
#include "test_util.h"

namespace opsila {
namespace {

using test::TempDir;

// A scene as a reader makes it: a warning, a map of `image`, another
// warning, the same map again, then a map of `other`.
Scene read_maps(const std::string& image, const std::string& other, MapImages images) {
  Scene s;
  s.warnings.push_back("first");
  MaterialDesc m;
  m.map_kd = add_texture_file(s, image, "a.mtl: material 'a': ", images);
  s.warnings.push_back("second");
  m.map_ka = add_texture_file(s, image, "b.mtl: material 'b': ", images);
  s.materials = {MaterialDesc::default_material(), m};
  MaterialDesc n;
  n.map_kd = add_texture_file(s, other, "c.mtl: material 'c': ", images);
  s.materials.push_back(n);
  return s;
}

TEST(TextureShares, ListedMapsSettleAsOneProcessReadsThem) {
  TempDir dir;
  const std::string good = dir.write("good.tga", test::tga(2, 1, {{255, 0, 0}, {0, 255, 0}}));
  const std::string bad = dir.write("bad.tga", "not an image");
  const Scene now = read_maps(bad, good, MapImages::now);
  Scene later = read_maps(bad, good, MapImages::later);
  EXPECT_TRUE(now.map_requests.empty());
  ASSERT_EQ(later.map_requests.size(), 3u);
  EXPECT_EQ(later.map_requests[0].warning, 1u);
  EXPECT_EQ(later.map_requests[2].warning, 2u);
  EXPECT_EQ(later.warnings, (std::vector<std::string>{"first", "second"})) << "no warning is decided yet";
  EXPECT_EQ(maps_to_check(later), (std::vector<std::string>{bad, good}));
  std::vector<MapCheck> checks;
  for (const std::string& path : maps_to_check(later)) checks.push_back(check_texture_map(path, true));
  settle_texture_maps(later, checks);
  EXPECT_EQ(later.warnings, now.warnings);
  EXPECT_TRUE(later.map_requests.empty());
  ASSERT_EQ(later.textures.size(), now.textures.size());
  EXPECT_EQ(later.textures[0].texels, now.textures[0].texels);
  EXPECT_EQ(later.materials[1].map_kd, now.materials[1].map_kd);
  EXPECT_EQ(later.materials[2].map_kd, now.materials[2].map_kd);
}

// A map listed again under another name of its file (a link) is the one
// listed first: one texture (each name is still checked, so that a bad
// image warns under the names one process would give).
TEST(TextureShares, AMapListedUnderALinkIsListedOnce) {
  TempDir dir;
  const std::string good = dir.write("good.tga", test::tga(2, 1, {{255, 0, 0}, {0, 255, 0}}));
  std::filesystem::create_symlink("good.tga", dir.file("link.tga"));
  for (const MapImages images : {MapImages::now, MapImages::later}) {
    const Scene s = read_maps(good, dir.file("link.tga"), images);
    ASSERT_EQ(s.textures.size(), 1u);
    EXPECT_EQ(s.materials[2].map_kd, 0);
  }
}

// A model's warnings joined after a scene's, or a reader's own put first:
// each request keeps its place among them.
TEST(TextureShares, RequestsKeepTheirPlacesWhenWarningsAreJoined) {
  TempDir dir;
  const std::string missing = dir.file("missing.png");
  Scene model = read_maps(missing, missing, MapImages::later);
  put_warnings_first(model, {"parser"});
  Scene scene;
  scene.warnings = {"scene"};
  append_warnings(scene, model);
  settle_map_warnings(scene);
  const std::string ignored = "texture map '" + missing + "' ignored: ";
  ASSERT_EQ(scene.warnings.size(), 7u);
  EXPECT_EQ(scene.warnings[0], "scene");
  EXPECT_EQ(scene.warnings[1], "parser");
  EXPECT_EQ(scene.warnings[2], "first");
  EXPECT_EQ(scene.warnings[3].rfind("a.mtl: material 'a': " + ignored, 0), 0u) << scene.warnings[3];
  EXPECT_EQ(scene.warnings[4], "second");
  EXPECT_EQ(scene.warnings[5].rfind("b.mtl: material 'b': " + ignored, 0), 0u) << scene.warnings[5];
  EXPECT_EQ(scene.warnings[6].rfind("c.mtl: material 'c': " + ignored, 0), 0u) << scene.warnings[6];
}

}  // namespace
}  // namespace opsila
