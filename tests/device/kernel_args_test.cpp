// Kernel arguments by name (device/kernel_args.h). At compile time: a
// handle of one role is not accepted where another is expected, a plain
// buffer is accepted as none, groups count their parts at any depth. On
// the test device: the exchange's argument structs follow their kernels'
// signatures (kernel_signature.h).
#include <gtest/gtest.h>

#include <type_traits>
#include <utility>

#include "device/descriptors.h"
#include "device/kernel_args.h"
#include "kernel_signature.h"
#include "test_device.h"

namespace opsila {
namespace {

// Detection: whether binding.bind(args...) compiles.
template <class Binding, class Void, class... A>
struct CanBind : std::false_type {};
template <class Binding, class... A>
struct CanBind<Binding, std::void_t<decltype(std::declval<Binding&>().bind(std::declval<const A&>()...))>, A...>
    : std::true_type {};
template <class Binding, class... A>
constexpr bool can_bind = CanBind<Binding, void, A...>::value;

// Detection: whether T{A...} compiles (a group built from its parts in order).
template <class T, class Void, class... A>
struct CanBuild : std::false_type {};
template <class T, class... A>
struct CanBuild<T, std::void_t<decltype(T{std::declval<A>()...})>, A...> : std::true_type {};
template <class T, class... A>
constexpr bool can_build = CanBuild<T, void, A...>::value;

template <class Field, class Value>
constexpr bool can_assign = std::is_assignable_v<Field&, const Value&>;

using OneTable = KernelBinding<KeyTotals>;
static_assert(can_bind<OneTable, KeyTotals>, "a handle binds where its role is expected");
static_assert(!can_bind<OneTable, PeTotals>, "a handle of another role does not");
static_assert(!can_bind<OneTable, DescriptorRecords>, "nor the descriptors' records");
static_assert(!can_bind<OneTable, cl::Buffer>, "nor a plain buffer");
static_assert(!can_bind<OneTable, DescriptorSet>, "nor a group");
static_assert(can_bind<KernelBinding<cl::Buffer>, KeyTotals>, "a generic kernel takes any buffer");

static_assert(can_build<WorkGroupTable, GroupPes, GroupSlots>, "a group's parts in order");
static_assert(!can_build<WorkGroupTable, GroupSlots, GroupPes>, "swapped: no");
static_assert(!std::is_convertible_v<GroupSlots, GroupPes>, "nor one handle for another");
static_assert(!can_build<BankRanges, decltype(KeyRanges::count), decltype(KeyRanges::begin)>,
              "the keys' ranges are not the banks'");

using scatter_kernels::PlanArgs;
static_assert(can_assign<decltype(PlanArgs::key_total), KeyTotals>, "a field takes its role");
static_assert(!can_assign<decltype(PlanArgs::key_total), PeTotals>, "and no other");
static_assert(!can_assign<decltype(PlanArgs::banks), KeyRanges>, "nor another group");
static_assert(!can_assign<decltype(scatter_kernels::MoveEntriesArgs::hist), SourceRanks>,
              "the ranks are not the block counts");
static_assert(!can_assign<decltype(scatter_kernels::Placement::banks), BankRanges>,
              "the banks' descriptors are not their ranges");

static_assert(kernel_args_detail::count<DescriptorSet>() == 2, "records and sort keys");
static_assert(kernel_args_detail::count<KeyRanges>() == 3, "a group counts its parts");
static_assert(kernel_args_detail::count<scatter_kernels::Placement>() == 3 + 2 + 2, "groups within groups too");
static_assert(KernelBinding<int, DescriptorSet, KeyTotals>::kArgs == 4, "and a binding the sum of its parts");

TEST(KernelArgs, TheExchangesStructsFollowTheirKernels) {
  ClRuntime& rt = test::shared_runtime();
  using namespace scatter_kernels;
  test::expect_follow_signatures<CountArgs, ScanArgs, PlanArgs, MoveEntriesArgs, MoveBlocksArgs>(
      rt, KernelProgram::render,
      {"scatter_count", "scatter_scan", "scatter_plan", "scatter_move_entries", "scatter_move_blocks"});
}

// The check itself: a struct one part short, or with a value where the
// kernel takes a buffer, is told apart.
struct ScanShort {
  int num_blocks = 0;
  cl::Buffer values, total;
  auto kernel_args() const { return std::tie(num_blocks, values, total); }
};
struct ScanMisplaced {
  int num_blocks = 0;
  cl::Buffer values;
  int num_keys = 1;
  cl::Buffer total;
  auto kernel_args() const { return std::tie(num_blocks, values, num_keys, total); }
};

TEST(KernelArgs, AStructThatDoesNotFollowItsKernelIsToldApart) {
  ClRuntime& rt = test::shared_runtime();
  EXPECT_THROW(KernelBinding<ScanShort>(rt, "scatter_scan"), ClError);
  std::vector<std::string> host;
  test::host_parts<ScanMisplaced>(host);
  const auto declared = test::kernel_parts(cl::Kernel(test::described_program(rt, false), "scatter_scan"), 4);
  if (declared.empty()) GTEST_SKIP() << "the driver keeps no kernel argument information";
  ASSERT_EQ(host.size(), declared.size());
  EXPECT_NE(host[1], declared[1].first);
  EXPECT_NE(host[2], declared[2].first);
}

}  // namespace
}  // namespace opsila
