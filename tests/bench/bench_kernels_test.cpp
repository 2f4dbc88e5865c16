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
    test::expect_follows_signature<MegaArgs>(rt, "megakernel", p);
    test::expect_follows_signature<MegaRaysArgs>(rt, "megakernel_rays", p);
  }
  const KernelProgram p = KernelProgram::baselines;
  test::expect_follows_signature<TraversalArgs>(rt, "traversal_nearest", p);
  test::expect_follows_signature<TraversalArgs>(rt, "traversal_any", p);
  test::expect_follows_signature<SixVectorsArgs>(rt, "scatter_six_vectors", p);
  test::expect_follows_signature<OneRecordArgs>(rt, "scatter_one_record", p);
  test::expect_follows_signature<CopyArgs>(rt, "copy_float4", p);
}

}  // namespace
}  // namespace opsila
