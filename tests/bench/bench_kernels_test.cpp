// The baselines' kernel argument structs (bench/bench_kernels.h) follow
// their kernels' signatures on the test device (kernel_signature.h).
#include <gtest/gtest.h>

#include "bench/bench_kernels.h"
#include "kernel_signature.h"
#include "test_device.h"

namespace opsila {
namespace {

TEST(BenchKernels, EveryStructFollowsItsKernel) {
  ClRuntime& rt = test::shared_runtime();
  for (KernelProgram p : {KernelProgram::baselines, KernelProgram::baselines_uncounted}) {
    SCOPED_TRACE(static_cast<int>(p));
    test::expect_follow_signatures<MegaArgs, MegaRaysArgs>(rt, p, {"megakernel", "megakernel_rays"});
  }
  test::expect_follow_signatures<TraversalArgs, TraversalArgs, SixVectorsArgs, OneRecordArgs, CopyArgs>(
      rt, KernelProgram::baselines,
      {"traversal_nearest", "traversal_any", "scatter_six_vectors", "scatter_one_record", "copy_float4"});
}

}  // namespace
}  // namespace opsila
