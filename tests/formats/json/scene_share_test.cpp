// The dealing of a JSON scene's entries over ranks (formats/json/
// scene_share.h), from its explicit inputs: every object goes whole to one
// rank, the ranks' figures are the whole entry's, each rank's attributes
// are renumbered to the triangles it keeps, and the windows of an entry
// made in windows cover it once.
#include <gtest/gtest.h>

#include <set>
#include <vector>

#include "formats/json/scene_share.h"

namespace opsila {
namespace {

using scene_json::EntryShare;
using scene_json::ShareDealer;

// `objects` objects of two triangles each, every other triangle with
// attributes of its own (its object id in the normal's x).
Scene entry_scene(int objects) {
  Scene s;
  for (int o = 0; o < objects; ++o)
    for (int k = 0; k < 2; ++k) {
      Triangle t;
      t.v0 = {float(o), 0, 0}, t.v1 = {float(o) + 1, 0, 0}, t.v2 = {float(o), 1, float(k)};
      t.object_id = o, t.facet_id = 2 * o + k;
      if (k == 1) {
        VertexAttributes a;
        a.has_normals = true;
        a.normal[0] = {float(o), 0, 0};
        t.attributes = static_cast<int>(s.attributes.size());
        s.attributes.push_back(a);
      }
      s.triangles.push_back(t);
    }
  return s;
}

SceneShare rank_of(int r, int ranks) {
  SceneShare share;
  share.rank = r, share.ranks = ranks;
  return share;
}

TEST(ShareDealer, EveryObjectGoesWholeToOneRank) {
  const int objects = 7, R = 3;
  std::multiset<int> kept;
  for (int r = 0; r < R; ++r) {
    SCOPED_TRACE(r);
    ShareDealer dealer(rank_of(r, R));
    Scene s = entry_scene(objects);
    EntryShare entry;
    entry.planned_end = s.triangles.size();
    dealer.deal(s, entry, 0, 0, s.triangles.size());
    EXPECT_EQ(dealer.share().total_triangles, std::size_t(2 * objects));
    EXPECT_EQ(dealer.share().lo, (Vec3{0, 0, 0}));
    EXPECT_EQ(dealer.share().hi, (Vec3{float(objects), 1, 1}));
    std::set<int> mine;
    for (const Triangle& t : s.triangles) {
      mine.insert(t.object_id);
      if (t.attributes < 0) continue;
      ASSERT_LT(std::size_t(t.attributes), s.attributes.size());
      EXPECT_EQ(s.attributes[std::size_t(t.attributes)].normal[0][0], float(t.object_id));
    }
    EXPECT_EQ(s.triangles.size(), 2 * mine.size()) << "an object is cut";
    EXPECT_EQ(s.attributes.size(), mine.size());
    kept.insert(mine.begin(), mine.end());
  }
  EXPECT_EQ(kept, (std::multiset<int>{0, 1, 2, 3, 4, 5, 6}));
}

TEST(ShareDealer, TheWindowsOfAnEntryCoverItOnce) {
  const std::size_t all = 10;
  std::size_t next = 0;
  int spread = 0;
  for (int r = 0; r < 3; ++r) {
    ShareDealer dealer(rank_of(r, 3));
    EntryShare entry;
    entry.planned_end = all;
    std::size_t begin = 0, end = 0;
    dealer.window(entry, all, 5, all, begin, end);
    EXPECT_TRUE(entry.windowed);
    EXPECT_EQ(begin, next) << r;
    next = end;
    spread += static_cast<int>(dealer.share().spread.size());
  }
  EXPECT_EQ(next, all);
  EXPECT_EQ(spread, 3) << "every rank says the object is spread";
}

}  // namespace
}  // namespace opsila
