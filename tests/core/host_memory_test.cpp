// Sizes as --host-memory takes them, and the memory the host says it has.
#include <gtest/gtest.h>

#include "core/host_memory.h"

namespace opsila {
namespace {

TEST(HostMemory, SizesWithBinaryUnitsFractionsOrPlainBytes) {
  EXPECT_EQ(parse_memory_size("8G"), std::uint64_t(8) << 30);
  EXPECT_EQ(parse_memory_size("512M"), std::uint64_t(512) << 20);
  EXPECT_EQ(parse_memory_size("1.5G"), std::uint64_t(3) << 29);
  EXPECT_EQ(parse_memory_size("64k"), std::uint64_t(64) << 10);
  EXPECT_EQ(parse_memory_size("2T"), std::uint64_t(2) << 40);
  EXPECT_EQ(parse_memory_size("8GB"), std::uint64_t(8) << 30);
  EXPECT_EQ(parse_memory_size("8GiB"), std::uint64_t(8) << 30);
  EXPECT_EQ(parse_memory_size("123456789"), std::uint64_t(123456789));
  EXPECT_EQ(parse_memory_size("4096B"), std::uint64_t(4096));
}

TEST(HostMemory, AnythingElseIsRefused) {
  for (const char* bad : {"", "G", "0", "0G", "0.0001", "-1G", "1.2.3G", "8X", "8 G", " 8G", "8GG", "8Gb2", ".", "1e9",
                          "nan", "inf", "99999999T"})
    EXPECT_FALSE(parse_memory_size(bad)) << "'" << bad << "'";
}

TEST(HostMemory, TheHostSaysWhatItHas) {
  EXPECT_GT(physical_memory(), 0u);
  EXPECT_GT(available_host_memory(), 0u);
  EXPECT_LE(available_host_memory(), physical_memory() + (std::uint64_t(1) << 30));
}

}  // namespace
}  // namespace opsila
