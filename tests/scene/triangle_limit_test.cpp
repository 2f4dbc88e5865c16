// One rank's triangle limit from its host memory: the formula, its base and
// the ids ceiling, and the words of a refusal.
#include <gtest/gtest.h>

#include <string>

#include "scene/triangle_limit.h"

namespace opsila {
namespace {

constexpr std::uint64_t kGiB = std::uint64_t(1) << 30, kMiB = std::uint64_t(1) << 20;

TEST(TriangleLimit, MemoryLessTheBaseOverBytesPerTriangle) {
  EXPECT_EQ(triangles_for_memory(0), 0u);
  EXPECT_EQ(triangles_for_memory(kPrepareHostBaseBytes), 0u) << "the base alone holds no triangle";
  EXPECT_EQ(triangles_for_memory(kPrepareHostBaseBytes + kPrepareHostBytesPerTriangle - 1), 0u);
  EXPECT_EQ(triangles_for_memory(kPrepareHostBaseBytes + kPrepareHostBytesPerTriangle), 1u);
  EXPECT_EQ(triangles_for_memory(8 * kGiB), (8 * kGiB - kPrepareHostBaseBytes) / kPrepareHostBytesPerTriangle);
  EXPECT_EQ(memory_for_triangles(1000), kPrepareHostBaseBytes + 1000 * kPrepareHostBytesPerTriangle);
  for (std::size_t n : {std::size_t(1), std::size_t(12345), std::size_t(1) << 24})
    EXPECT_EQ(triangles_for_memory(memory_for_triangles(n)), n) << "the two figures are each other's inverse";
}

TEST(TriangleLimit, TheIdsCeilingHoldsWhateverTheMemory) {
  EXPECT_EQ(kMaxTriangles, std::size_t(2147483647));
  EXPECT_EQ(triangles_for_memory(std::uint64_t(1) << 50), kMaxTriangles);
  const TriangleLimit big = TriangleLimit::of_memory(host_memory_of(std::uint64_t(1) << 50, 0, 1));
  EXPECT_EQ(big.triangles, kMaxTriangles);
  EXPECT_EQ(big.why, TriangleLimit::Why::ids);
  EXPECT_EQ(TriangleLimit().triangles, kMaxTriangles);
  EXPECT_EQ(TriangleLimit(std::size_t(1) << 40).triangles, kMaxTriangles);
}

TEST(TriangleLimit, TheFlagIsThisProcesssTheAvailableMemoryIsSharedByTheHostsRanks) {
  const HostMemory flag = host_memory_of(8 * kGiB, 64 * kGiB, 4);
  EXPECT_TRUE(flag.from_flag);
  EXPECT_EQ(flag.bytes, 8 * kGiB) << "--host-memory is per process";
  const HostMemory shared = host_memory_of(0, 64 * kGiB, 4);
  EXPECT_FALSE(shared.from_flag);
  EXPECT_EQ(shared.bytes, 16 * kGiB);
  EXPECT_EQ(host_memory_of(0, 64 * kGiB, 0).bytes, 64 * kGiB) << "at least one rank";
  const TriangleLimit limit = TriangleLimit::of_memory(shared);
  EXPECT_EQ(limit.triangles, triangles_for_memory(16 * kGiB));
  EXPECT_EQ(limit.why, TriangleLimit::Why::memory);
}

// An address-space limit (ulimit -v) below the host's share bounds the
// process too: scenes within the available memory had been built until the
// process ran out, with no key named (found by a hostile battery).
TEST(TriangleLimit, AnAddressSpaceLimitBelowTheShareBoundsTheProcess) {
  const HostMemory capped = host_memory_of(0, 64 * kGiB, 4, 3 * kGiB);
  EXPECT_EQ(capped.bytes, 3 * kGiB);
  EXPECT_EQ(capped.address_space, 3 * kGiB);
  const TriangleLimit limit = TriangleLimit::of_memory(capped);
  EXPECT_EQ(limit.triangles, triangles_for_memory(3 * kGiB));
  EXPECT_NE(limit.why_not(40000000, 1).find("(the address space ulimit -v leaves this process)"), std::string::npos);
  EXPECT_EQ(limit.memory_hint(40000000, 1).rfind("a ulimit -v above ", 0), 0u) << "--host-memory would not help";
  const HostMemory roomy = host_memory_of(0, 64 * kGiB, 4, 32 * kGiB);
  EXPECT_EQ(roomy.bytes, 16 * kGiB) << "the share is the smaller";
  EXPECT_EQ(roomy.address_space, 0u);
  EXPECT_EQ(host_memory_of(8 * kGiB, 0, 1, 1 * kGiB).bytes, 8 * kGiB) << "--host-memory is taken as given";
}

// Memory below what preparing takes before the first triangle is said so
// at once: it had been "too many triangles (more than 0)" on the first
// face of an OBJ under ulimit -v.
TEST(TriangleLimit, NoRoomForAnyTriangleIsSaidOnItsOwn) {
  EXPECT_EQ(TriangleLimit::of_memory(host_memory_of(300 * kMiB, 0, 1)).no_room(), "");
  EXPECT_EQ(TriangleLimit::of_memory(host_memory_of(100 * kMiB, 0, 1)).no_room(),
            "not enough host memory to prepare a scene: this process may use 0.10 GiB (--host-memory), less than "
            "the 0.25 GiB preparing takes before its first triangle; --host-memory 257M would do for a small scene");
  const std::string ulimit = TriangleLimit::of_memory(host_memory_of(0, 64 * kGiB, 1, kPrepareHostBaseBytes + 1)).no_room();
  EXPECT_EQ(ulimit.rfind("not enough address space to prepare a scene: ulimit -v leaves this process no room", 0), 0u)
      << ulimit;
  EXPECT_EQ(TriangleLimit(0).no_room(), "") << "a bare number has no memory to speak of";
}

TEST(TriangleLimit, ARefusalSaysWhatDoesNotFitAndWhatThisProcessMayUse) {
  const TriangleLimit flag = TriangleLimit::of_memory(host_memory_of(300 * kMiB, 0, 1));
  EXPECT_EQ(flag.why_not(1000000, 1),
            ": 1000000 triangles need about 0.36 GiB while preparing at 120 bytes a triangle, and this process "
            "may use 0.29 GiB (--host-memory)");
  EXPECT_EQ(flag.memory_hint(1000000, 1), "--host-memory 371M");
  EXPECT_EQ(flag.memory_hint(1000000, 2), "--host-memory 314M") << "each rank's half";
  const TriangleLimit shared = TriangleLimit::of_memory(host_memory_of(0, 4 * kGiB, 2));
  EXPECT_EQ(shared.why_not(40000000, 2, true),
            ": more than 40000000 triangles on 2 ranks need over 2.49 GiB a rank while preparing at 120 bytes a "
            "triangle, and each rank may use 2.00 GiB (4.00 GiB available on this host, shared by 2 ranks)");
  EXPECT_EQ(TriangleLimit(1000).why_not(2000, 1), "") << "a bare number has no memory to speak of";
  EXPECT_EQ(TriangleLimit(1000).memory_hint(2000, 1), "");
  const TriangleLimit hooked = flag.capped_for_tests(20);
  EXPECT_EQ(hooked.triangles, 20u);
  EXPECT_NE(hooked.why_not(21, 1).find("OPSILA_RANK_TRIANGLE_LIMIT"), std::string::npos);
  EXPECT_EQ(flag.capped_for_tests(std::size_t(1) << 30).triangles, flag.triangles) << "only ever lower";
}

}  // namespace
}  // namespace opsila
