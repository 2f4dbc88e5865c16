// Scenes over what this process's memory holds, through the real binary:
// one error line naming the file, the triangles and the memory, no output;
// the same scene with more --host-memory renders. The memory given is the
// flag's, never this machine's.
#include <gtest/gtest.h>

#include <cstdint>
#include <sstream>
#include <string>
#include <vector>

#include "core/host_memory.h"
#include "test_util.h"

namespace opsila {
namespace {

using test::RunResult;
using test::TempDir;
using test::run_opsila;

const std::string kMillion = std::string(OPSILA_SOURCE_DIR) + "/scenes/million.json";

bool has(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// The refusal begins with the file's name and says every one of `parts`.
void expect_says(const std::string& e, const std::string& file, const std::vector<std::string>& parts) {
  EXPECT_EQ(e.rfind("opsila: error: " + file + ":", 0), 0u) << e;
  for (const std::string& part : parts) EXPECT_TRUE(has(e, part)) << part << "\n" << e;
}

// One "opsila: error:" line, exit `code`, nothing written in `dir`.
std::string refusal(const RunResult& r, const TempDir& dir, int code = 2) {
  EXPECT_EQ(r.exit_code, code) << r.err;
  const std::vector<std::string> errors = r.error_lines();
  EXPECT_EQ(errors.size(), 1u) << r.err;
  EXPECT_TRUE(dir.entries().empty()) << "an output was written";
  return errors.empty() ? std::string() : errors[0];
}

TEST(SceneLimitsCli, AJsonSceneOverTheMemoryIsRefusedBeforeItIsBuilt) {
  TempDir dir;
  const RunResult r = run_opsila({"render", kMillion, "--host-memory", "300M", "-o", dir.file("x.png")});
  const std::string e = refusal(r, dir);
  expect_says(e, kMillion,
              {"objects[0]", "1002528 triangles need about 0.36 GiB while preparing at 120 bytes a triangle",
               "this process may use 0.29 GiB (--host-memory)", "--host-memory 371M"});
#ifdef OPSILA_HAVE_MPI
  EXPECT_TRUE(has(e, "at least 3 MPI ranks (mpirun -n 3 opsila render ...)")) << e;
#endif
}

TEST(SceneLimitsCli, TheSameSceneRendersWithMoreHostMemory) {
  TempDir dir;
  const RunResult r =
      run_opsila({"render", kMillion, "--host-memory", "1G", "--size", "32x24", "--depth", "1", "-q", "-o",
                  dir.file("x.png")});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(test::file_exists(dir.file("x.png")));
}

// More than the machine has is taken as given (the flag decides which
// scenes are admitted), with a warning that loading may still run out.
TEST(SceneLimitsCli, MoreHostMemoryThanTheMachineHasIsWarnedOf) {
  TempDir dir;
  const std::string whitted = std::string(OPSILA_SOURCE_DIR) + "/scenes/whitted.json";
  const std::uint64_t machine = physical_memory();
  if (machine == 0) GTEST_SKIP() << "the system does not say how much memory it has";
  for (const std::uint64_t bytes : {2 * machine, machine / 2}) {
    const RunResult r = run_opsila({"render", whitted, "--host-memory", std::to_string(bytes), "--size", "16x12",
                                    "-o", dir.file("x.png")});
    EXPECT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(has(r.err, "opsila: warning: --host-memory "), bytes > machine) << r.err;
    EXPECT_EQ(has(r.err, "GiB is more than this machine's "), bytes > machine) << r.err;
  }
}

TEST(SceneLimitsCli, BadSizesNameTheFlag) {
  TempDir dir;
  for (const char* bad : {"0", "12X", "-1G", ""}) {
    for (const char* command : {"render", "bench"}) {
      const RunResult r = run_opsila({command, kMillion, "--host-memory", bad});
      const std::string e = refusal(r, dir);
      EXPECT_TRUE(has(e, "--host-memory")) << command << ": " << e;
    }
  }
}

TEST(SceneLimitsCli, AStreamedObjIsRefusedAsItPassesTheLimit) {
  // 257 MiB leave 1 MiB over the base: 8738 triangles at 120 bytes.
  TempDir dir;
  std::ostringstream obj;
  for (int i = 0; i <= 100; ++i)
    for (int j = 0; j < 2; ++j) obj << "v " << i << " " << j << " 0\n";
  for (int k = 0; k < 50; ++k)
    for (int i = 0; i < 100; ++i) obj << "f " << 2 * i + 1 << " " << 2 * i + 2 << " " << 2 * i + 4 << " " << 2 * i + 3 << "\n";
  const std::string path = dir.write("strip.obj", obj.str());
  TempDir out;
  const RunResult r = run_opsila({"render", path, "--host-memory", "257M", "-o", out.file("x.png")});
  expect_says(refusal(r, out), path,
              {"too many triangles (more than 8738", "more than 8738 triangles need over 0.25 GiB while preparing",
               "this process may use 0.25 GiB (--host-memory)"});
  const RunResult fits = run_opsila({"render", path, "--host-memory", "258M", "--size", "16x12", "-q", "-o", out.file("x.png")});
  EXPECT_EQ(fits.exit_code, 0) << fits.err;
}

// Each small object is a cluster of its own: 3 M one-triangle groups of a
// 30 MB OBJ peaked at 2.65 GB under --host-memory 700M, which counted their
// triangles alone. Objects count too now (768 bytes each).
TEST(SceneLimitsCli, ManySmallObjectsCountAgainstTheMemory) {
  TempDir dir;
  std::ostringstream obj;
  for (int i = 0; i < 20000; ++i)
    obj << "g o" << i << "\nv " << i << " 0 0\nv " << i << ".5 0 0\nv " << i << " 0.5 0\nf -3 -2 -1\n";
  const std::string path = dir.write("groups.obj", obj.str());
  TempDir out;
  // 256 MiB + 20000 x (120 + 768) bytes: 16.9 MiB over the base.
  const RunResult r = run_opsila({"render", path, "--host-memory", "270M", "-o", out.file("x.png")});
  expect_says(refusal(r, out), path,
              {"20000 objects and 20000 triangles need about 0.27 GiB while preparing at 768 bytes an object and 120 "
               "a triangle", "this process may use 0.26 GiB (--host-memory); --host-memory 273M would do"});
  const RunResult fits = run_opsila({"render", path, "--host-memory", "273M", "--size", "16x12", "-q", "-o", out.file("x.png")});
  EXPECT_EQ(fits.exit_code, 0) << fits.err;
  const RunResult reference =
      run_opsila({"render", path, "--host-memory", "270M", "--reference", "--size", "16x12", "-q", "-o", out.file("r.png")});
  EXPECT_EQ(reference.exit_code, 0) << "no clusters to build: " << reference.err;
}

// Decoded texture maps count too: a 1024 x 1024 map is 4 MiB of texels.
TEST(SceneLimitsCli, TextureMapsCountAgainstTheMemory) {
  TempDir dir;
  // An uncompressed 24-bit TGA: an 18-byte header, then the pixels.
  std::string tga("\0\0\x02", 3);
  tga += std::string(9, '\0') + std::string("\0\x04\0\x04\x18\0", 6) + std::string(std::size_t(3) << 20, '\x60');
  dir.write("map.tga", tga);
  dir.write("m.mtl", "newmtl m\nKd 1 1 1\nmap_Kd map.tga\n");
  const std::string path =
      dir.write("mapped.obj", "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl m\nf 1/1 2/2 3/3\n");
  TempDir out;
  // 256 MiB + 4 MiB of texels + one triangle and object: over 260 MiB.
  const RunResult r = run_opsila({"render", path, "--host-memory", "259M", "-o", out.file("x.png")});
  expect_says(refusal(r, out), path, {"1 objects, 4 MiB of texture maps and 1 triangles need about 0.25 GiB",
                                      "--host-memory 261M would do"});
  const RunResult fits = run_opsila({"render", path, "--host-memory", "261M", "--size", "16x12", "-q", "-o", out.file("x.png")});
  EXPECT_EQ(fits.exit_code, 0) << fits.err;
}

TEST(SceneLimitsCli, AShareTooLargeForTheDeviceIsRefusedBeforeThePartition) {
  TempDir dir;
  const RunResult r = test::run_program(OPSILA_BINARY, {"render", kMillion, "-o", dir.file("x.png")},
                                        {{"OPSILA_DEVICE_MEMORY_LIMIT", "20000000"}});
  const std::string e = refusal(r, dir, 3);
  EXPECT_TRUE(has(e, kMillion + ": 1084448 triangles need about 99.3 MiB of device memory at 96 bytes a triangle")) << e;
  EXPECT_TRUE(has(e, "as lowered by OPSILA_DEVICE_MEMORY_LIMIT")) << e;
#ifdef OPSILA_HAVE_MPI
  EXPECT_TRUE(has(e, "at least 6 MPI ranks")) << e;
#endif
}

}  // namespace
}  // namespace opsila
