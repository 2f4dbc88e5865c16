// The frame's kernel argument structs (frame/frame_kernels.h): at compile
// time, a buffer of one role is not accepted where another is expected; on
// the test device, every struct follows its kernel's signature in each
// program that has it (kernel_signature.h).
#include <gtest/gtest.h>

#include <type_traits>

#include "frame/frame_kernels.h"
#include "kernel_signature.h"
#include "test_device.h"

namespace opsila {
namespace {

using frame_kernels::SpmdArgs;
template <class Field, class Value>
constexpr bool can_assign = std::is_assignable_v<Field&, const Value&>;

static_assert(can_assign<decltype(BankGeometry::tris), BankFacets>, "the facets go where the facets go");
static_assert(!can_assign<decltype(BankGeometry::tris), BankNodes>, "the nodes do not");
static_assert(!can_assign<decltype(BankGeometry::tris), DescriptorRecords>, "nor the descriptors");
static_assert(!can_assign<decltype(BankGeometry::tris), cl::Buffer>, "nor a plain buffer");
static_assert(!can_assign<decltype(SpmdArgs::accum), StatCounters>, "sums and counters apart");
static_assert(!can_assign<decltype(SpmdArgs::stats), TrafficCounters>, "counters apart");
static_assert(!can_assign<decltype(SpmdArgs::out_count), GroupPes>, "outputs and work-groups apart");
static_assert(!can_assign<decltype(SpmdArgs::routing), BankGeometry>, "groups apart");
static_assert(!can_assign<decltype(frame_kernels::PrimaryBuildArgs::hits), ItemDistances>, "hits and distances apart");
static_assert(!can_assign<decltype(frame_kernels::ListHitsArgs::list), HitBlocks>, "the list and its blocks apart");

TEST(FrameKernels, EveryStructFollowsItsKernelInEveryProgram) {
  ClRuntime& rt = test::shared_runtime();
  using namespace frame_kernels;
  for (KernelProgram p : {KernelProgram::render, KernelProgram::render_uncounted, KernelProgram::measure}) {
    SCOPED_TRACE(static_cast<int>(p));
    test::expect_follow_signatures<ItemBufferArgs, CountHitsArgs, ListHitsArgs, PrimaryArgs, SpmdArgs>(
        rt, p, {"item_buffer", "count_hits", "list_hits", "build_primary", "spmd_phase"});
  }
}

}  // namespace
}  // namespace opsila
