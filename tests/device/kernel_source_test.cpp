// The kernel source hook (OPSILA_KERNEL_SOURCE) and the driver's compile
// cache: a broken source fails with its build log, a changed one is rebuilt.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <map>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "prepare/prepare_banks.h"
#include "device/descriptors.h"
#include "partition/pe_group.h"
#include "frame/rank_exchange.h"
#include "mpi/ranks.h"
#include "formats/image/image_io.h"
#include "opsila_shared.h"
#include "frame/renderer.h"
#include "exchange_check.h"
#include "test_scenes.h"
#include "test_device.h"
#include "test_util.h"
#include "fault_checks.h"

namespace opsila {

const std::string& kernel_source();  // the embedded kernels (generated from kernels/*.cl)

namespace {

// --------------------------------------------------- kernel source and cache

TEST(KernelSource, BrokenSourceFailsWithTheBuildLog) {
  ClRuntimeOptions o = plain_options();
  o.kernel_source = "__kernel void item_buffer(__global int *p) { p[0] = this_is_not_declared; }\n";
  o.kernel_source_origin = "broken test source";
  ClRuntime rt(test_device(), o);
  EXPECT_EQ(rt.kernel_source_origin(), "broken test source");
  try {
    rt.program();
    FAIL() << "a broken kernel source built";
  } catch (const ClError& e) {
    const std::string m = e.what();
    EXPECT_TRUE(contains(first_line(m), "clBuildProgram: CL_BUILD_PROGRAM_FAILURE")) << m;
    EXPECT_TRUE(contains(first_line(m), "broken test source")) << m;
    EXPECT_TRUE(contains(first_line(m), "build log:")) << m;
    EXPECT_TRUE(contains(m, "this_is_not_declared")) << "the compiler's message is shown:\n" << m;
  }
  // Asking again fails again (nothing half-built is kept).
  EXPECT_THROW(rt.kernel("item_buffer"), ClError);
}

// A kernel writing `value`: two sources that differ only there.
int run_probe(int value) {
  ClRuntimeOptions o = plain_options();
  o.kernel_source = "__kernel void probe(__global int *out) { out[0] = " + std::to_string(value) + "; }\n";
  ClRuntime rt(test_device(), o);
  cl::Kernel k = rt.kernel("probe");
  cl::Buffer out = upload(rt, std::vector<cl_int>{-1}, "probe output");
  k.setArg(0, out);
  cl_check(rt.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(1), cl::NDRange(1)), "probe");
  cl_int result = 0;
  cl_check(rt.queue().enqueueReadBuffer(out, CL_TRUE, 0, sizeof result, &result), "probe read");
  return result;
}

// The driver's compile cache (POCL_CACHE_DIR under ctest) is keyed by the
// source text: a changed source is compiled again, never served stale.
TEST(KernelSource, TheCompileCacheFollowsTheSource) {
  EXPECT_EQ(run_probe(1), 1);
  EXPECT_EQ(run_probe(2), 2);
  EXPECT_EQ(run_probe(1), 1);
  EXPECT_EQ(run_probe(2), 2);
}

// The renderer really runs a replacement source: doubling the fixed-point
// scale in the kernels (the host divides by its own, unchanged constant)
// doubles every pixel.
TEST(KernelSource, TheRendererRunsTheReplacementSource) {
  const std::string from = "#define OPSILA_FIXED_SHIFT 24";
  std::string source = kernel_source();
  const std::size_t at = source.find(from);
  ASSERT_NE(at, std::string::npos) << "the shared header no longer defines the shift as expected";
  source.replace(at, from.size(), "#define OPSILA_FIXED_SHIFT 25");

  Scene s = test::mirror_glass_scene(32, 3);
  RenderSettings settings;
  settings.num_pes = 4;
  RenderResult base, doubled;
  {
    ClRuntime rt(test_device(), plain_options());
    base = render(s, settings, rt);
  }
  {
    ClRuntimeOptions o = plain_options();
    o.kernel_source = source;
    o.kernel_source_origin = "doubled scale";
    ClRuntime rt(test_device(), o);
    doubled = render(s, settings, rt);
  }
  ASSERT_EQ(base.rgb.size(), doubled.rgb.size());
  double brightest = 0;
  for (std::size_t i = 0; i < base.rgb.size(); ++i) {
    brightest = std::max(brightest, double(base.rgb[i]));
    ASSERT_NEAR(doubled.rgb[i], 2.0f * base.rgb[i], 1e-5) << "value " << i;
  }
  EXPECT_GT(brightest, 0.1);
}

TEST(KernelSource, EnvironmentHookEndToEnd) {
  TempDir dir;
  // A good render first, so that the driver's cache holds the real kernels.
  RunResult good = opsila(render_args(dir.file("good.pfm")), {{"OPSILA_KERNEL_SOURCE", std::nullopt}});
  ASSERT_EQ(good.exit_code, 0) << good.err;

  const std::string broken = dir.write("broken.cl", "__kernel void item_buffer(__global int *p) { p[0] = 1 }\n");
  RunResult r = opsila(render_args(dir.file("broken.pfm")), {{"OPSILA_KERNEL_SOURCE", broken}});
  expect_one_error(r, 3, "clBuildProgram: CL_BUILD_PROGRAM_FAILURE");
  EXPECT_TRUE(contains(error_line(r), "OPSILA_KERNEL_SOURCE=" + broken)) << r.err;
  EXPECT_TRUE(contains(r.err, "build log")) << r.err;
  EXPECT_TRUE(contains(r.err, "\n    ")) << "the build log follows the error line:\n" << r.err;
  EXPECT_FALSE(test::file_exists(dir.file("broken.pfm")));

  RunResult missing = opsila(render_args(dir.file("missing.pfm")),
                             {{"OPSILA_KERNEL_SOURCE", dir.file("no-such-file.cl")}});
  expect_one_error(missing, 2, "OPSILA_KERNEL_SOURCE=");
  EXPECT_FALSE(test::file_exists(dir.file("missing.pfm")));

  // The real kernels again: the same bytes as before.
  RunResult again = opsila(render_args(dir.file("again.pfm")), {{"OPSILA_KERNEL_SOURCE", std::nullopt}});
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_EQ(test::read_file(dir.file("good.pfm")), test::read_file(dir.file("again.pfm")));
}

}  // namespace
}  // namespace opsila
