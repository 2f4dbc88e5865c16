// The memory plan against the device memory the renderer really asks for:
// every buffer a frame allocates, up to the end of its first frame, fits
// in what the plan counted (the plan sizes n; a plan below the real need
// would let a frame fail on a device the plan said it fits).
#include <gtest/gtest.h>

#include "machine/prepare_banks.h"
#include "machine/renderer.h"
#include "test_device.h"
#include "test_scenes.h"

namespace opsila {
namespace {

TEST(MemoryPlan, CoversEveryAllocationOfTheFirstFrame) {
  const Scene s = test::mirror_glass_scene(32, 4);
  for (int pes : {1, 4, 16, 100}) {
    ClRuntime rt(test::test_device());
    RenderSettings rs;
    rs.num_pes = pes;
    PreparedBanks banks = prepare_banks(s, rs, rt);
    const std::uint64_t before = rt.allocated_bytes();
    Renderer r(s, std::move(banks), rs, rt);
    const std::uint64_t prepared = rt.allocated_bytes() - before;
    r.render();
    const std::uint64_t first_frame = rt.allocated_bytes() - before;
    const std::uint64_t plan = r.planned_device_bytes();
    EXPECT_LE(first_frame, plan) << pes << " PEs: the plan misses buffers";
    EXPECT_GE(double(prepared), 0.8 * double(plan)) << pes << " PEs: the plan counts far more than is allocated";
  }
}

}  // namespace
}  // namespace opsila
