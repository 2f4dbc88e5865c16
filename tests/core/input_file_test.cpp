// Every file a run reads is bounded: the loaders' files, and those an
// environment hook or a flag names (OPSILA_KERNEL_SOURCE, bench --compare).
// /dev/zero never ends; a sparse file is large without taking disk space.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include "core/errors.h"
#include "core/input_file.h"
#include "test_util.h"

namespace opsila {
namespace {

using test::RunResult;
using test::TempDir;

std::string sparse_file(const TempDir& dir, const std::string& name, off_t bytes) {
  const std::string path = dir.file(name);
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  EXPECT_GE(fd, 0);
  EXPECT_EQ(::ftruncate(fd, bytes), 0);
  ::close(fd);
  return path;
}

TEST(InputFiles, ANamedFileIsBoundedAndItsMessageNamesTheOrigin) {
  TempDir dir;
  test::expect_error([] { read_named_file("OPSILA_KERNEL_SOURCE=", "/dev/zero", 1 << 20); },
                     {"OPSILA_KERNEL_SOURCE=/dev/zero: ", "not a regular file"});
  const std::string big = sparse_file(dir, "big.cl", (1 << 20) + 1);
  test::expect_error([&] { read_named_file("--compare ", big, 1 << 20); },
                     {"--compare " + big + ": file too large", "limit is 1048576"});
  const std::string fits = dir.write("fits.cl", "kernel");
  EXPECT_EQ(read_named_file("X=", fits, 6), "kernel");
}

// The program itself, under a 4 GiB address-space cap so that an unbounded
// read fails fast instead of taking the machine's memory (not under
// AddressSanitizer, whose shadow memory alone reserves terabytes of
// addresses: the same checks, uncapped).
#if defined(__SANITIZE_ADDRESS__)
constexpr const char* kCapped = "exec \"$0\" \"$@\"";
#else
constexpr const char* kCapped = "ulimit -v 4194304 && exec \"$0\" \"$@\"";
#endif

TEST(InputFiles, AKernelSourceThatNeverEndsOrIsTooLargeIsOneError) {
  TempDir dir;
  const std::string scene = dir.write("s.json", R"({"image": {"width": 8, "height": 6},
    "objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1}]})");
  const std::string big = sparse_file(dir, "big.cl", off_t(17) << 20);  // the limit is 16 MiB
  const auto before = dir.entries();
  for (const std::string& source : {std::string("/dev/zero"), big}) {
    SCOPED_TRACE(source);
    const RunResult r = test::run_program(
        "/bin/sh", {"-c", kCapped, OPSILA_BINARY, "render", scene, "-o",
                    dir.file("o.png")},
        {{"OPSILA_KERNEL_SOURCE", source}});
    EXPECT_EQ(r.exit_code, 2) << r.err;
    ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
    EXPECT_NE(r.error_lines()[0].find("OPSILA_KERNEL_SOURCE=" + source + ": "), std::string::npos) << r.err;
    EXPECT_EQ(dir.entries(), before);
  }
}

}  // namespace
}  // namespace opsila
