// A texture map used by facets in every bank: each bank counts its own copy
// (as the paper's banks would hold it, and as --stats reports it), but the
// banks that share a device share one copy of the texels, so device memory
// does not grow with the PEs.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "partition/partition.h"
#include "partition/pe_group.h"
#include "test_scenes.h"

namespace opsila {
namespace {

// A row of `n` small textured triangles along x, all mapped with one w x w map.
Scene textured_row(int n, int w) {
  Scene s;
  s.materials.push_back(MaterialDesc::default_material());
  MaterialDesc m = MaterialDesc::default_material();
  m.name = "mapped";
  m.map_kd = 0;
  s.materials.push_back(m);
  s.textures.push_back(test::make_texture(w, w, [](int i, int j) { return std::array<int, 3>{i % 256, j % 256, 7}; }));
  for (int i = 0; i < n; ++i) {
    Triangle t;
    t.v0 = {float(i), 0, 0};
    t.v1 = {float(i) + 0.5f, 0, 0};
    t.v2 = {float(i), 0.5f, 0};
    t.facet_id = t.object_id = i;
    t.material = 1;
    t.attributes = test::add_attributes(s, {}, {{{0, 0}, {1, 0}, {0, 1}}}, false, true);
    s.triangles.push_back(t);
  }
  s.num_facets = s.num_objects = n;
  return s;
}

TEST(TextureMemory, BanksOnOneDeviceShareOneCopyAndEachCountsItsOwn) {
  constexpr int kPes = 16, kSide = 64;
  const Scene scene = textured_row(256, kSide);
  const BankedScene bs = partition_scene(scene, kPes);
  const std::uint64_t copy = std::uint64_t(kSide) * kSide * sizeof(std::uint32_t) + sizeof(BankTexture);
  // One copy of the texels on the device, one texture entry per bank.
  EXPECT_EQ(bs.texels.size(), std::size_t(kSide) * kSide);
  ASSERT_EQ(bs.textures.size(), std::size_t(kPes));
  EXPECT_EQ(bs.texture_replicated_bytes, copy);
  for (int p = 0; p < kPes; ++p) {
    SCOPED_TRACE(p);
    ASSERT_LT(bs.pes[p].tri_begin, bs.pes[p].tri_end) << "every bank must hold mapped facets for this test";
    EXPECT_EQ(bs.texture_bytes[p], copy);  // what --stats reports: the paper's bank holds its own
    EXPECT_EQ(bs.textures[p].pe, p);
    EXPECT_EQ(bs.textures[p].texel_begin, 0);
    for (int k = bs.pes[p].tri_begin; k < bs.pes[p].tri_end; ++k) EXPECT_EQ(bs.textures[bs.attributes[k].map_kd].pe, p);
  }
  // A rank's group of banks keeps the one copy, its own entries only.
  BankedScene group = bs;
  keep_group_banks(group, pe_group(kPes, 4, 2));
  EXPECT_EQ(group.texels, bs.texels);
  ASSERT_EQ(group.textures.size(), std::size_t(kPes / 4));
  for (const BankTexture& t : group.textures) EXPECT_EQ(t.texel_begin, 0);
}

}  // namespace
}  // namespace opsila
