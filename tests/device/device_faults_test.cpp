// Device and driver faults (docs/RELIABILITY.md): no platform, missing
// capabilities, memory beyond the device, each one clear message and a
// non-zero exit, never a hang or a garbage image.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "prepare/prepare_banks.h"
#include "device/descriptors.h"
#include "partition/pe_group.h"
#include "frame/rank_exchange.h"
#include "mpi/ranks.h"
#include "formats/image/image_io.h"
#include "opsila_shared.h"
#include "frame/renderer.h"
#include "exchange_check.h"
#include "test_scenes.h"
#include "test_device.h"
#include "test_util.h"
#include "fault_checks.h"

namespace opsila {

const std::string& kernel_source();  // the embedded kernels (generated from kernels/*.cl)

namespace {

// -------------------------------------------------------------- no platform

TEST(DeviceFaults, NoOpenClPlatformIsOneClearError) {
  TempDir dir, empty_vendors;
  const std::map<std::string, std::optional<std::string>> env = {{"OCL_ICD_VENDORS", empty_vendors.path()}};
  std::vector<std::string> args = render_args(dir.file("out.pfm"));
  RunResult r = opsila(args, env);
  expect_one_error(r, 3, "no OpenCL platform");
  EXPECT_EQ(r.err, error_line(r) + "\n") << "nothing but the error line";
  EXPECT_FALSE(test::file_exists(dir.file("out.pfm")));
  EXPECT_TRUE(dir.entries().empty()) << "no partial output";

  RunResult devices = opsila({"devices"}, env);
  expect_one_error(devices, 3, "no OpenCL platform");

  // The sequential reference needs no OpenCL at all.
  args.insert(args.end(), "--reference");
  RunResult reference = opsila(args, env);
  EXPECT_EQ(reference.exit_code, 0) << reference.err;
  EXPECT_TRUE(test::file_exists(dir.file("out.pfm")));
}

// ------------------------------------------------------- device capabilities

DeviceCapabilities capable() {
  DeviceCapabilities c;
  c.name = "test device";
  c.version = "OpenCL 1.2 test";
  c.opencl_c_version = "OpenCL C 1.2 test";
  c.profile = "FULL_PROFILE";
  c.local_mem_size = 32768;
  c.max_work_group_size = 256;
  return c;
}

TEST(DeviceChecks, TheTestDeviceHasWhatOpsilaNeeds) {
  const DeviceEntry d = test_device();
  const std::vector<std::string> missing = missing_capabilities(query_capabilities(d.device));
  EXPECT_TRUE(missing.empty()) << d.device_name << " lacks " << (missing.empty() ? "" : missing.front());
}

TEST(DeviceChecks, EachMissingCapabilityIsNamed) {
  EXPECT_TRUE(missing_capabilities(capable()).empty());
  for (const char* v : {"OpenCL 2.0 x", "OpenCL 3.0", "OpenCL 1.2"}) {
    DeviceCapabilities c = capable();
    c.version = v;
    EXPECT_TRUE(missing_capabilities(c).empty()) << v;
  }
  struct Case {
    void (*change)(DeviceCapabilities&);
    const char* named;
  } cases[] = {
      {[](DeviceCapabilities& c) { c.version = "OpenCL 1.1 old"; }, "OpenCL 1.2 (it reports 'OpenCL 1.1 old')"},
      {[](DeviceCapabilities& c) { c.version = "garbage"; }, "OpenCL 1.2"},
      {[](DeviceCapabilities& c) { c.opencl_c_version = "OpenCL C 1.1"; }, "OpenCL C 1.2"},
      {[](DeviceCapabilities& c) { c.compiler_available = false; }, "compiler"},
      {[](DeviceCapabilities& c) { c.local_mem_size = 1024; }, "local memory"},
      {[](DeviceCapabilities& c) { c.max_work_group_size = 0; }, "CL_DEVICE_MAX_WORK_GROUP_SIZE"},
      {[](DeviceCapabilities& c) { c.available = false; }, "not available"},
      {[](DeviceCapabilities& c) { c.profile = "EMBEDDED_PROFILE"; }, "64-bit integers"},
  };
  for (const Case& k : cases) {
    DeviceCapabilities c = capable();
    k.change(c);
    const std::vector<std::string> missing = missing_capabilities(c);
    ASSERT_EQ(missing.size(), 1u) << k.named;
    EXPECT_TRUE(contains(missing[0], k.named)) << missing[0];
  }
  DeviceCapabilities embedded = capable();
  embedded.profile = "EMBEDDED_PROFILE";
  embedded.extensions = "cl_khr_byte_addressable_store cles_khr_int64";
  EXPECT_TRUE(missing_capabilities(embedded).empty());
  // The SPMD kernel's per-level stats and traffic live in local memory, and
  // the exchange plan's key totals and work-group bases: the larger counts.
  EXPECT_EQ(required_local_mem(),
            std::max<std::size_t>(std::size_t(OPSILA_MAX_DEPTH) * (OPSILA_STAT_COUNT + OPSILA_TRAFFIC_MAX_PES) * 4,
                                  std::size_t(OPSILA_SCATTER_PLAN_LOCAL_INTS) * 4));
  DeviceCapabilities all_wrong = capable();
  all_wrong.version = "OpenCL 1.0";
  all_wrong.compiler_available = false;
  all_wrong.local_mem_size = 0;
  EXPECT_EQ(missing_capabilities(all_wrong).size(), 3u);
}

// ------------------------------------------------------------ device memory

TEST(DeviceMemory, OneBufferBeyondTheLargestAllocationIsRefused) {
  ClRuntimeOptions o = plain_options();
  o.memory_limit = 1 << 20;
  ClRuntime rt(test_device(), o);
  EXPECT_EQ(rt.max_alloc(), cl_ulong(1) << 20);
  EXPECT_EQ(rt.global_mem(), cl_ulong(1) << 20);
  // "<no error>" when a buffer beyond the limit was created.
  const std::string m = test::error_of<ClError>([&] { device_buffer(rt, 3u << 20, "huge test buffer"); });
  EXPECT_TRUE(contains(m, "huge test buffer") && contains(m, "3145728") && contains(m, "1048576") &&
              contains(m, "CL_DEVICE_MAX_MEM_ALLOC_SIZE"))
      << m;
  EXPECT_NO_THROW(device_buffer(rt, 1 << 20, "buffer at the limit"));
}

TEST(DeviceMemory, TheWholeRenderIsCheckedBeforeAllocating) {
  Scene s = test::mirror_glass_scene(64, 3);  // 64x48
  RenderSettings settings;
  settings.num_pes = 4;
  RenderResult unlimited;
  int default_capacity = 0;
  {
    ClRuntime rt(test_device(), plain_options());
    unlimited = render(s, settings, rt);
    default_capacity = unlimited.stats.bank_capacity;
  }
  ASSERT_GT(default_capacity, 64);
  ClRuntimeOptions o = plain_options();
  o.memory_limit = 1 << 20;  // below what the automatic bank size plans, above what n = 1 needs
  {
    ClRuntime rt(test_device(), o);
    // An automatic bank size shrinks until the render fits; the image does not change.
    RenderResult fitted = render(s, settings, rt);
    EXPECT_LT(fitted.stats.bank_capacity, default_capacity);
    EXPECT_GE(fitted.stats.bank_capacity, 1);
    EXPECT_GE(test::clamped_psnr(fitted.rgb, unlimited.rgb), 60.0);
    EXPECT_EQ(fitted.item_buffer, unlimited.item_buffer);
    // An explicit one is refused with the numbers, before any allocation.
    RenderSettings explicit_capacity = settings;
    explicit_capacity.bank_capacity = default_capacity;
    // "<no error>" when a render beyond the device's memory started.
    const std::string m = test::error_of<ClError>([&] { render(s, explicit_capacity, rt); });
    EXPECT_TRUE(contains(m, "device memory") && contains(m, "1024.0 KiB") && contains(m, "OPSILA_DEVICE_MEMORY_LIMIT") &&
                contains(m, "--bank-capacity"))
        << m;
  }
  // An image that cannot fit even with one slot per bank.
  o.memory_limit = 64 << 10;
  ClRuntime tiny(test_device(), o);
  EXPECT_THROW(render(s, settings, tiny), ClError);
}

TEST(DeviceMemory, EnvironmentLimitEndToEnd) {
  TempDir dir;
  RunResult r = opsila(render_args(dir.file("out.pfm")), {{"OPSILA_DEVICE_MEMORY_LIMIT", "20000"}});
  expect_one_error(r, 3, "device memory");
  EXPECT_TRUE(contains(r.err, "OPSILA_DEVICE_MEMORY_LIMIT")) << r.err;
  EXPECT_FALSE(test::file_exists(dir.file("out.pfm")));

  RunResult bad = opsila(render_args(dir.file("out.pfm")), {{"OPSILA_DEVICE_MEMORY_LIMIT", "lots"}});
  expect_one_error(bad, 2, "OPSILA_DEVICE_MEMORY_LIMIT=lots");
  EXPECT_FALSE(test::file_exists(dir.file("out.pfm")));
}

// `opsila ARGS` under a shell's `ulimit LIMIT` (set in the child only).
RunResult under_ulimit(const std::string& limit, const std::vector<std::string>& args) {
  std::vector<std::string> a = {"-c", "ulimit " + limit + " && exec \"$0\" \"$@\"", OPSILA_BINARY};
  a.insert(a.end(), args.begin(), args.end());
  return test::run_program("/bin/sh", a);
}

// A CPU device maps its buffers into the process: under an address-space
// limit (ulimit -v) the plan is held to what the limit leaves. A render past
// it made PoCL fail an assertion (exit 134); now it is refused like any
// device memory shortfall, and a small render under the same limit runs.
TEST(DeviceMemory, AnAddressSpaceLimitBoundsACpuDevice) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer reserves terabytes of addresses: no run fits under ulimit -v";
#endif
  if (*test_device_spec() && std::string(test_device_spec()) != "pocl")
    GTEST_SKIP() << "checked on PoCL, whose CPU device the limit caps (" << test_device_spec() << " here)";
  TempDir dir;
  const auto capped = [&](const std::string& size) {
    std::vector<std::string> args = render_args(dir.file("out.pfm"));
    *(std::find(args.begin(), args.end(), "--size") + 1) = size;
    return under_ulimit("-v 1000000", args);
  };
  const RunResult big = capped("4096x4096");
  expect_one_error(big, 3, "device memory");
  EXPECT_TRUE(contains(big.err, "ulimit -v")) << big.err;
  EXPECT_FALSE(test::file_exists(dir.file("out.pfm")));
  const RunResult small = capped("40x30");
  EXPECT_EQ(small.exit_code, 0) << small.err;
}

// What PoCL's CPU device needs of the process, said before it crashes: a
// stack of 1 MiB for its threads (at ulimit -s 96 a render died of SIGSEGV,
// exit 139), and a POCL_CACHE_DIR that is not empty (an assertion, exit 134).
TEST(DeviceFaults, DriverLimitsAreNamedBeforeTheDriverFails) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer's frames are larger: a 200 KiB stack is not what a user's build runs on";
#endif
  if (*test_device_spec() && std::string(test_device_spec()) != "pocl")
    GTEST_SKIP() << "PoCL's needs, checked on PoCL (" << test_device_spec() << " here)";
  TempDir dir;
  const auto small_stack = [&](const std::vector<std::string>& extra) {
    return under_ulimit("-s 200", render_args(dir.file("out.pfm"), extra));
  };
  expect_one_error(small_stack({}), 2, "the stack limit (ulimit -s) is 200 KiB");
  EXPECT_FALSE(test::file_exists(dir.file("out.pfm")));
  const RunResult reference = small_stack({"--reference"});
  EXPECT_EQ(reference.exit_code, 0) << reference.err;
  expect_one_error(opsila(render_args(dir.file("cache.pfm")), {{"POCL_CACHE_DIR", ""}}), 2, "POCL_CACHE_DIR is set but empty");
  EXPECT_FALSE(test::file_exists(dir.file("cache.pfm")));
}

// Open files and threads, which PoCL needs before it runs a kernel: a hard
// open-files limit of 10 aborted its compiler (exit 134), a soft one is
// raised; a thread limit it cannot start its workers under aborted it too.
TEST(DeviceFaults, OpenFileAndThreadLimitsAreNamedBeforeTheDriverFails) {
  TempDir dir;
  const std::vector<std::string> args = render_args(dir.file("out.pfm"));
  expect_one_error(under_ulimit("-n 10", args), 2, "the open-files limit (ulimit -n) is 10");
  EXPECT_FALSE(test::file_exists(dir.file("out.pfm")));
  const RunResult soft = under_ulimit("-Sn 10", args);
  EXPECT_EQ(soft.exit_code, 0) << soft.err;
  std::remove(dir.file("out.pfm").c_str());
  // RLIMIT_NPROC binds a user without privileges: as root, the check runs as nobody.
  if (::geteuid() != 0) GTEST_SKIP() << "the thread limit is checked by root running opsila as nobody";
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "LeakSanitizer's check at exit starts a thread, which the thread limit refuses";
#endif
  // nobody runs a copy of the program, its libraries and the scene, so that
  // the rights on the checkout's folders do not matter.
  ASSERT_EQ(::chmod(dir.path().c_str(), 0777), 0);
  namespace fs = std::filesystem;
  const fs::path program(OPSILA_BINARY), scene_dir = fs::path(OPSILA_SOURCE_DIR) / "tests" / "oclgrind";
  for (const fs::directory_entry& e : fs::directory_iterator(program.parent_path())) {
    const std::string name = e.path().filename().string();
    if (e.path() == program || (name.rfind("lib", 0) == 0 && e.path().extension() == ".so"))
      fs::copy_file(e.path(), dir.file(name));
  }
  for (const char* name : {"tiny.obj", "tiny.mtl"}) fs::copy_file(scene_dir / name, dir.file(name));
  std::vector<std::string> limited = {"--reuid=nobody", "--regid=nogroup", "--clear-groups",
                                      "env", "LD_LIBRARY_PATH=" + dir.path(), "POCL_CACHE_DIR=" + dir.file("cache"),
                                      "prlimit", "--nproc=1",
                                      dir.file(program.filename().string())};
  std::vector<std::string> copied_args = args;
  std::replace(copied_args.begin(), copied_args.end(), args[1], dir.file("tiny.obj"));
  limited.insert(limited.end(), copied_args.begin(), copied_args.end());
  std::vector<std::string> version(limited.begin(), limited.end() - std::ptrdiff_t(copied_args.size()));
  version.push_back("--version");
  if (test::run_program("/usr/bin/setpriv", version).exit_code != 0)
    GTEST_SKIP() << "nobody cannot run a copy of " << OPSILA_BINARY << " (setpriv or prlimit missing?)";
  expect_one_error(test::run_program("/usr/bin/setpriv", limited), 2, "the thread limit (ulimit -u) is 1");
  EXPECT_FALSE(test::file_exists(dir.file("out.pfm")));
}

// PoCL lists no device when it cannot make its kernel cache: the error says so.
TEST(DeviceFaults, AnUnusablePoclCacheIsNamed) {
  if (*test_device_spec() && std::string(test_device_spec()) != "pocl")
    GTEST_SKIP() << "PoCL's cache, checked on PoCL (" << test_device_spec() << " here)";
  TempDir dir;
  std::ofstream(dir.file("file")) << "not a folder";
  const RunResult r = opsila({"devices"}, {{"POCL_CACHE_DIR", dir.file("file") + "/cache"}});
  expect_one_error(r, 3, "PoCL lists no device when it cannot create its kernel cache");
  EXPECT_TRUE(contains(r.err, dir.file("file") + "/cache")) << r.err;
  // A file, not a folder: PoCL failed every build, its own lines first.
  for (const std::string& cache : {dir.file("file"), std::string("/dev/null")}) {
    const RunResult f = opsila(render_args(dir.file("out.pfm")), {{"POCL_CACHE_DIR", cache}});
    expect_one_error(f, 2, "POCL_CACHE_DIR=" + cache + ": not a folder");
    EXPECT_FALSE(test::file_exists(dir.file("out.pfm")));
  }
}

// PoCL's thread count, which it reads with atoi: a negative value or one
// past the int range crashed its first call (SIGSEGV), a value too large to
// start aborted it. Refused before any driver call; 0 is PoCL's default.
TEST(DeviceFaults, APoclThreadCountPoclCannotTakeIsRefused) {
  TempDir dir;
  for (const char* bad : {"-1", "-2", "65536", "4294967295", "99999999999"}) {
    SCOPED_TRACE(bad);
    const RunResult r = opsila({"devices"}, {{"POCL_MAX_PTHREAD_COUNT", bad}});
    expect_one_error(r, 2, std::string("POCL_MAX_PTHREAD_COUNT=") + bad + ": PoCL's thread count must be 1 to 4096");
  }
  for (const char* good : {"0", "1", "2"}) {
    SCOPED_TRACE(good);
    const RunResult r = opsila(render_args(dir.file("out.pfm")), {{"POCL_MAX_PTHREAD_COUNT", good}});
    EXPECT_EQ(r.exit_code, 0) << r.err;
  }
}

// OPSILA_WAITING_LIMIT: a whole number, or one clear error before anything
// is written.
TEST(WaitingLimit, ABadValueIsAnInputError) {
  TempDir dir;
  RunResult bad = opsila(render_args(dir.file("out.pfm")), {{"OPSILA_WAITING_LIMIT", "lots"}});
  expect_one_error(bad, 2, "OPSILA_WAITING_LIMIT=lots");
  EXPECT_FALSE(test::file_exists(dir.file("out.pfm")));
  RunResult tight = opsila(render_args(dir.file("out.pfm")), {{"OPSILA_WAITING_LIMIT", "1"}});
  EXPECT_EQ(tight.exit_code, 0) << tight.err;
  EXPECT_TRUE(test::file_exists(dir.file("out.pfm")));
}

// OPSILA_PRIMARY_AHEAD: 0 or 1, or one clear error before anything is
// written; 0 gives the same image with a build_primary launch a round.
TEST(PrimaryAhead, ABadValueIsAnInputErrorAndZeroGivesTheSameImage) {
  TempDir dir;
  RunResult bad = opsila(render_args(dir.file("out.pfm")), {{"OPSILA_PRIMARY_AHEAD", "yes"}});
  expect_one_error(bad, 2, "OPSILA_PRIMARY_AHEAD=yes");
  EXPECT_FALSE(test::file_exists(dir.file("out.pfm")));
  RunResult ahead = opsila(render_args(dir.file("ahead.pfm")), {{"OPSILA_PRIMARY_AHEAD", "1"}});
  RunResult own = opsila(render_args(dir.file("own.pfm")), {{"OPSILA_PRIMARY_AHEAD", "0"}});
  ASSERT_EQ(ahead.exit_code, 0) << ahead.err;
  ASSERT_EQ(own.exit_code, 0) << own.err;
  EXPECT_TRUE(test::read_file(dir.file("ahead.pfm")) == test::read_file(dir.file("own.pfm")));
}

}  // namespace
}  // namespace opsila
