// The preparation's steps that share their work among the host threads
// (terrain heights, scene bounds, the cluster cuts, the bank filling, the
// bank BVHs) give the same bytes whatever the number of threads, on a scene
// large enough for each of them to split its work.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <vector>

#include "formats/json/primitives.h"
#include "partition/partition.h"
#include "test_scenes.h"

namespace opsila {
namespace {

template <class F>
auto with_threads(const char* threads, F f) {
  ::setenv("OPSILA_THREADS", threads, 1);
  auto result = f();
  ::unsetenv("OPSILA_THREADS");
  return result;
}

template <class T, class A>
std::vector<unsigned char> bytes(const std::vector<T, A>& v) {
  const auto* p = reinterpret_cast<const unsigned char*>(v.data());
  return std::vector<unsigned char>(p, p + v.size() * sizeof(T));
}

// A terrain of 540 x 540 quads (583,200 facets: past every size at which a
// step splits its work) and a sphere, as a second object.
Scene big_scene() {
  Scene s;
  const int ground = test::add_material(s, {0.5f, 0.5f, 0.5f}, {0.5f, 0.5f, 0.5f}, {0, 0, 0}, 1, {0, 0, 0}, 1, 2);
  TerrainDesc t;
  t.size_x = t.size_z = 40;
  t.quads_x = t.quads_z = 540;
  t.height = 5;
  s.num_facets = add_terrain(s.triangles, t, 0, ground, ground, 0);
  test::add_sphere(s, {0, 8, 0}, 3, 3, 1, ground);
  s.num_objects = 2;
  return s;
}

TEST(PrepareThreads, TheSameBytesWhateverTheThreads) {
  const Scene one = with_threads("1", big_scene), many = with_threads("5", big_scene);
  ASSERT_GT(one.triangles.size(), std::size_t(1) << 19);
  EXPECT_EQ(bytes(one.triangles), bytes(many.triangles));  // the terrain's heights
  const auto banks = [&](const char* threads) { 
    PartitionUse use;
    use.pilot_maps = true;  // source and tri_cluster too
    return with_threads(threads, [&] { return partition_scene(one, 16, false, nullptr, nullptr, use); });
  };
  const BankedScene a = banks("1"), b = banks("5");
  EXPECT_EQ(bytes(a.triangles), bytes(b.triangles));
  EXPECT_EQ(bytes(a.nodes), bytes(b.nodes));
  EXPECT_EQ(bytes(a.clusters), bytes(b.clusters));
  EXPECT_EQ(bytes(a.route_nodes), bytes(b.route_nodes));
  EXPECT_EQ(bytes(a.pes), bytes(b.pes));
  ASSERT_EQ(a.source.size(), a.triangles.size());
  EXPECT_EQ(a.source, b.source);
  EXPECT_EQ(a.tri_cluster, b.tri_cluster);
}

// Bounds scanned in chunks, joined in order: a tie between -0 and +0 keeps
// the first met, as one scan does, whichever comes first.
TEST(PrepareThreads, SceneBoundsKeepTheFirstOfEqualValues) {
  for (const bool negative_first : {false, true}) {
    Scene s;
    const std::size_t n = std::size_t(3) << 18;
    s.triangles.assign(n, Triangle{{1, 1, 1}, {2, 1, 1}, {1, 2, 1}});
    s.triangles.front().v0[0] = negative_first ? -0.0f : 0.0f;
    s.triangles.back().v0[0] = negative_first ? 0.0f : -0.0f;
    for (const char* threads : {"1", "4"}) {
      Vec3 lo, hi;
      with_threads(threads, [&] {
        s.bounds(lo, hi);
        return 0;
      });
      EXPECT_EQ(lo[0], 0.0f);
      EXPECT_EQ(std::signbit(lo[0]), negative_first) << threads << " threads";
      EXPECT_EQ(hi[0], 2.0f);
    }
  }
}

}  // namespace
}  // namespace opsila
