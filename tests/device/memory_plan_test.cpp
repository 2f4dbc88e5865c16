// The memory plan against the device memory the renderer really asks for:
// the plan is the sum of the frame's buffer table, and every buffer the
// machine allocates, up to the end of its first frame, is a row of that
// table with the bytes it planned (a plan below the real need would let a
// frame fail on a device the plan said it fits; one above would shrink n
// for nothing).
#include <gtest/gtest.h>

#include <map>
#include <string>

#include "device/device_buffers.h"
#include "prepare/prepare_banks.h"
#include "frame/renderer.h"
#include "test_device.h"
#include "test_scenes.h"

namespace opsila {
namespace {

std::map<std::string, std::uint64_t> since(const std::map<std::string, std::uint64_t>& now,
                                           const std::map<std::string, std::uint64_t>& before) {
  std::map<std::string, std::uint64_t> d;
  for (const auto& [name, bytes] : now) {
    const auto b = before.find(name);
    const std::uint64_t grown = bytes - (b == before.end() ? 0 : b->second);
    if (grown) d[name] = grown;
  }
  return d;
}

TEST(MemoryPlan, IsEveryAllocationOfTheFirstFrame) {
  const Scene s = test::mirror_glass_scene(32, 4);
  for (int pes : {1, 4, 16, 100}) {
    ClRuntime rt(test::test_device());
    RenderSettings rs;
    rs.num_pes = pes;
    PreparedBanks banks = prepare_banks(s, rs, rt);
    const std::uint64_t before = rt.allocated_bytes();
    const std::map<std::string, std::uint64_t> names_before = rt.allocations();
    Renderer r(s, std::move(banks), rs, rt);
    r.render();
    const std::uint64_t first_frame = rt.allocated_bytes() - before;
    EXPECT_EQ(first_frame, r.planned_device_bytes()) << pes << " PEs";
    const std::map<std::string, std::uint64_t> planned = r.planned_buffers(),
                                               allocated = since(rt.allocations(), names_before);
    for (const auto& [name, bytes] : allocated) {
      const auto p = planned.find(name);
      ASSERT_NE(p, planned.end()) << pes << " PEs: '" << name << "' is allocated but not in the buffer table";
      EXPECT_EQ(bytes, p->second) << pes << " PEs: '" << name << "'";
    }
    for (const auto& [name, bytes] : planned)
      EXPECT_TRUE(allocated.count(name)) << pes << " PEs: '" << name << "' is planned but never allocated";
  }
}

// Where the device shares host memory (PoCL on a CPU), the bank arrays are
// read in place: the facets alone are more than the uploads' other bytes.
TEST(MemoryPlan, BankArraysInPlaceOnHostMemory) {
  ClRuntime rt(test::test_device());
  if (!host_sharing(rt).in_place) GTEST_SKIP() << "the device does not share host memory (copies are right there)";
  const Scene s = test::mirror_glass_scene(32, 4);
  RenderSettings rs;
  rs.num_pes = 4;
  PreparedBanks banks = prepare_banks(s, rs, rt);
  const std::uint64_t facets = banks.scene.triangles.size() * sizeof(BankTriangle);
  Renderer r(s, std::move(banks), rs, rt);
  EXPECT_GE(r.in_place_bytes(), facets);
}

}  // namespace
}  // namespace opsila
