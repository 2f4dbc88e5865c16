// Work-groups as a GPU driver might take them (ClRuntimeOptions::group_size,
// OPSILA_GROUP_SIZE): 256 work-items render the image of the default 64,
// byte for byte; a size that is not a power of two up to 1024 is refused.
#include <gtest/gtest.h>

#include <algorithm>

#include "prepare/prepare_banks.h"
#include "frame/renderer.h"
#include "test_device.h"
#include "test_scenes.h"
#include "test_util.h"

namespace opsila {
namespace {

TEST(GroupSize, GpuSizedGroupsRenderTheSameImage) {
  const Scene s = test::mirror_glass_scene(40, 4);
  RenderSettings rs;
  rs.num_pes = 16;
  const RenderResult usual = render(s, rs, test::shared_runtime());
  ClRuntimeOptions options;
  options.group_size = 256;
  options.read_environment = false;
  ClRuntime wide(test::test_device(), options);
  const RenderResult r = render(s, rs, wide);
  EXPECT_LE(usual.stats.work_group_size, 64u);
  std::size_t allowed = 0;
  ASSERT_EQ(wide.kernel("spmd_phase").getWorkGroupInfo(wide.device().device, CL_KERNEL_WORK_GROUP_SIZE, &allowed),
            CL_SUCCESS);
  if (allowed >= 256) EXPECT_EQ(r.stats.work_group_size, 256u);
  EXPECT_EQ(r.rgb, usual.rgb);
  EXPECT_EQ(r.item_buffer, usual.item_buffer);
  EXPECT_EQ(r.stats.descriptors_spawned, r.stats.descriptors_finished);
}

TEST(GroupSize, OnlyAPowerOfTwoUpTo1024) {
  test::TempDir dir;
  const std::string obj = dir.write("t.obj", "v -1 -1 0\nv 1 -1 0\nv 0 1 0\nf 1 2 3\n");
  for (const char* bad : {"100", "0", "2048", "-64", "sixty-four"}) {
    const test::RunResult r = test::run_program(OPSILA_BINARY, {"render", obj, "-o", dir.file("x.png"), "--size", "4x4"},
                                                {{"OPSILA_GROUP_SIZE", std::string(bad)}});
    EXPECT_EQ(r.exit_code, 2) << bad << ": " << r.err;
    ASSERT_EQ(r.error_lines().size(), 1u) << bad << ": " << r.err;
    EXPECT_NE(r.err.find(std::string("OPSILA_GROUP_SIZE=") + bad), std::string::npos) << r.err;
    EXPECT_FALSE(test::file_exists(dir.file("x.png")));
  }
}

}  // namespace
}  // namespace opsila
