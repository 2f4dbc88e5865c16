// host/core/vec.h: the box and the one slab test the host uses (the
// reference's BVH, the partition's ray-sample crossings).
#include <gtest/gtest.h>

#include <cmath>

#include "core/vec.h"

namespace opsila {
namespace {

Box unit_box() {
  Box b;
  b.grow(Vec3{0, 0, 0});
  b.grow(Vec3{1, 1, 1});
  return b;
}

TEST(Vec, AnEmptyBoxChangesNothingItGrows) {
  Box b = unit_box(), empty;
  EXPECT_TRUE(empty.empty());
  b.grow(empty);
  EXPECT_EQ(b.lo, (Vec3{0, 0, 0}));
  EXPECT_EQ(b.hi, (Vec3{1, 1, 1}));
  EXPECT_FLOAT_EQ(b.area(), 6.0f);
  EXPECT_FLOAT_EQ(empty.area(), 0.0f);
  empty.grow(b);
  EXPECT_EQ(empty.lo, b.lo);
  EXPECT_EQ(empty.hi, b.hi);
}

TEST(Vec, SlabTestMeetsAndMissesWithinTheSegment) {
  const Box b = unit_box();
  EXPECT_TRUE(slab_test(b, {-1, 0.5f, 0.5f}, {1, 0, 0}, 0, INFINITY));
  EXPECT_FALSE(slab_test(b, {-1, 0.5f, 0.5f}, {1, 0, 0}, 0, 0.5f)) << "the box starts at t = 1";
  EXPECT_FALSE(slab_test(b, {-1, 0.5f, 0.5f}, {-1, 0, 0}, 0, INFINITY)) << "pointing away";
  EXPECT_TRUE(slab_test(b, {0.5f, 0.5f, 0.5f}, {0, 0, 1}, 0, INFINITY)) << "from inside";
  EXPECT_TRUE(slab_test(b, {-1, -1, -1}, normalize({1, 1, 1}), 0, INFINITY)) << "through the corners";
}

// A zero direction component keeps the ray in its slab or out of it, for
// an unbounded segment too (no 0 x infinity).
TEST(Vec, SlabTestWithAZeroDirectionComponent) {
  const Box b = unit_box();
  EXPECT_TRUE(slab_test(b, {-1, 0.5f, 0.5f}, {1, 0, 0}, 0, INFINITY));
  EXPECT_TRUE(slab_test(b, {-1, 1.0f, 0.5f}, {1, 0, 0}, 0, INFINITY)) << "along a face: closed box";
  EXPECT_FALSE(slab_test(b, {-1, 2.0f, 0.5f}, {1, 0, 0}, 0, INFINITY)) << "beside the slab";
  EXPECT_FALSE(slab_test(b, {-1, 2.0f, 0.5f}, {1, -0.0f, 0}, 0, INFINITY)) << "negative zero";
}

// The slack widens each exit by a fraction of its distance: a box just
// before the segment's start is met with it, not without.
TEST(Vec, SlabSlackWidensTheExit) {
  const Box b = unit_box();
  const float start = 2.0f * (1 + 1e-6f);  // past the exit at t = 2 by two parts in a million
  EXPECT_FALSE(slab_test(b, {-1, 0.5f, 0.5f}, {1, 0, 0}, start, INFINITY));
  EXPECT_TRUE(slab_test(b, {-1, 0.5f, 0.5f}, {1, 0, 0}, start, INFINITY, 4e-6f));
}

}  // namespace
}  // namespace opsila
