// A user's first render on a device: the driver compiles the kernels (PoCL
// partly at each kernel's first launch). The wait is said on stderr while
// it lasts and kept out of the frame's reported time.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <nlohmann/json.hpp>

#include "test_util.h"

namespace opsila {
namespace {

using test::RunResult;
using test::TempDir;

const char* kScene = R"({"image": {"width": 64, "height": 48}, "lights": [{"position": [0, 5, 5]}],
  "objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1}]})";

std::vector<std::string> render_args(const TempDir& dir, const std::string& scene) {
  std::vector<std::string> args = {"render", scene, "-o", dir.file("o.png"), "--stats", dir.file("o.json")};
  if (const char* device = std::getenv("OPSILA_TEST_DEVICE")) args.insert(args.end(), {"--device", device});
  return args;
}

TEST(FirstRun, KernelCompileIsSaidAndKeptOutOfTheRenderTime) {
  TempDir dir;
  const std::string scene = dir.write("s.json", kScene);
  const std::string cache = dir.file("pocl-cache");  // empty: PoCL compiles everything
  ASSERT_EQ(::mkdir(cache.c_str(), 0777), 0);
  // OPSILA_PROGRESS_AFTER=0: the note shows however fast the build is.
  const RunResult cold = test::run_program(OPSILA_BINARY, render_args(dir, scene),
                                           {{"POCL_CACHE_DIR", cache}, {"OPSILA_PROGRESS_AFTER", "0"}});
  ASSERT_EQ(cold.exit_code, 0) << cold.err;
  EXPECT_NE(cold.err.find("opsila: note: compiling the OpenCL kernels for "), std::string::npos) << cold.err;
  const nlohmann::json stats = nlohmann::json::parse(test::read_file(dir.file("o.json")));
  ASSERT_TRUE(stats.contains("kernel_compile_seconds")) << stats.dump();
  const double compile = stats["kernel_compile_seconds"], frame = stats["render_seconds"];
  EXPECT_GT(compile, 0.0);
  // A 64x48 frame takes milliseconds; compiling takes far longer, and PoCL
  // compiles inside the first frame's launches: none of that is the frame's.
  EXPECT_LT(frame, compile) << cold.err;
  if (compile >= 0.5)
    EXPECT_NE(cold.err.find("s; kernel compile "), std::string::npos) << "the summary line says it:\n" << cold.err;

  // From the cache: no note, no compile in the summary.
  const RunResult warm = test::run_program(OPSILA_BINARY, render_args(dir, scene), {{"POCL_CACHE_DIR", cache}});
  ASSERT_EQ(warm.exit_code, 0) << warm.err;
  EXPECT_EQ(warm.err.find("compiling the OpenCL kernels"), std::string::npos) << warm.err;
  EXPECT_EQ(warm.err.find("kernel compile"), std::string::npos) << warm.err;
  // -q: silent, even where the note is due at once.
  std::vector<std::string> quiet = render_args(dir, scene);
  quiet.push_back("-q");
  const RunResult silent =
      test::run_program(OPSILA_BINARY, quiet, {{"POCL_CACHE_DIR", cache}, {"OPSILA_PROGRESS_AFTER", "0"}});
  ASSERT_EQ(silent.exit_code, 0) << silent.err;
  EXPECT_EQ(silent.err, "");
}

// A file-size limit below the driver's kernel cache files (PoCL writes
// over a megabyte of preprocessed source into POCL_CACHE_DIR while it
// builds) killed the process with SIGXFSZ (exit 153, no message). The write
// now fails as on a full disk: the build fails, or the driver's compiler
// ends the process, with a line that says why (exit 3, nothing written);
// or the driver goes on without its cache.
TEST(FirstRun, AFileSizeLimitWhileTheDriverCachesIsReported) {
  TempDir dir;
  const std::string scene = dir.write("s.json", kScene);
  const std::string cache = dir.file("pocl-cache");
  ASSERT_EQ(::mkdir(cache.c_str(), 0777), 0);
  std::vector<std::string> args = {"-c", "ulimit -f 1000 && exec \"$0\" \"$@\"", OPSILA_BINARY};
  for (const std::string& a : render_args(dir, scene)) args.push_back(a);
  const RunResult r = test::run_program("/bin/sh", args, {{"POCL_CACHE_DIR", cache}});
  ASSERT_TRUE(r.exit_code == 0 || r.exit_code == 3) << "exit " << r.exit_code << "\n" << r.err;
  if (r.exit_code == 3) {
    // Said by opsila after a failed build, or after the driver's compiler
    // ended the process itself (LLVM's "IO failure on output stream").
    const bool said = r.err.find("file-size limit") != std::string::npos;
    EXPECT_TRUE(said) << r.err;
    EXPECT_FALSE(test::file_exists(dir.file("o.png")));
  }
}

}  // namespace
}  // namespace opsila
