// A material read from a file against the values the contract gives it
// (docs/CONTRACT.md "Materials"), field by field so a failure names it.
#pragma once

#include <gtest/gtest.h>

#include "scene/scene.h"

namespace opsila::test {

struct Optics {
  Vec3 ka, ks, tf;
  float ns = 1, ni = 1;
  int illum = 0;
};

inline void expect_optics(const MaterialDesc& m, const Optics& want) {
  EXPECT_EQ(m.ka, want.ka) << m.name;
  EXPECT_EQ(m.ks, want.ks) << m.name;
  EXPECT_EQ(m.tf, want.tf) << m.name;
  EXPECT_EQ(m.ns, want.ns) << m.name;
  EXPECT_EQ(m.ni, want.ni) << m.name;
  EXPECT_EQ(m.illum, want.illum) << m.name;
}

}  // namespace opsila::test
