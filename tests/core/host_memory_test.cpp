// Sizes as --host-memory takes them, and the memory the host says it has.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <vector>

#include "core/host_memory.h"
#include "core/parallel.h"
#include "reference/reference.h"
#include "test_scenes.h"

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

// Threads the system will not start (ulimit -v, -u): the work is done by
// the threads there are. With the address space capped a little above what
// is mapped, no new thread gets its stack; the parallel loop and the
// reference's bands had left a vector of running threads to std::terminate
// (exit 134). In a child process, whose limit dies with it.
TEST(HostMemory, ThreadsThatCannotStartLeaveTheWorkToTheOthers) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer reserves terabytes of addresses: no address-space cap fits";
#endif
  const Scene scene = test::mirror_glass_scene(24, 3);
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    struct rlimit rl {};
    std::uint64_t pages = 0;
    if (std::FILE* f = std::fopen("/proc/self/statm", "r")) {
      if (std::fscanf(f, "%lu", reinterpret_cast<unsigned long*>(&pages)) != 1) ::_exit(3);
      std::fclose(f);
    }
    rl.rlim_cur = rl.rlim_max = pages * std::uint64_t(::sysconf(_SC_PAGESIZE)) + (std::uint64_t(6) << 20);  // under one thread's stack
    if (::setrlimit(RLIMIT_AS, &rl) != 0) ::_exit(4);
    std::vector<std::atomic<int>> done(64);
    parallel_for(done.size(), [&](std::size_t i) { ++done[i]; }, 8);
    for (const auto& d : done)
      if (d != 1) ::_exit(5);
    const ImageResult image = render_reference(scene, 4);
    ::_exit(image.rays.total() > 0 ? 0 : 6);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status)) << "killed by signal " << WTERMSIG(status);
  EXPECT_EQ(WEXITSTATUS(status), 0);
}

}  // namespace
}  // namespace opsila
