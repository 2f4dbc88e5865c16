// Reliability (docs/RELIABILITY.md): device and driver faults each give one
// clear message and a non-zero exit, never a hang or a garbage image; the
// same inputs give the same bytes run after run; the kernel source hook and
// the driver's compile cache; the scatter on its own, small enough to run
// under Oclgrind (.ci/oclgrind.sh).
//
// End-to-end checks run the opsila binary (OPSILA_BINARY) on
// tests/oclgrind/tiny.obj; in-process checks build their own ClRuntime and
// release it before the test ends.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
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

namespace opsila {

const std::string& kernel_source();  // the embedded kernels (generated from kernels/*.cl)

namespace {

using test::RunResult;
using test::TempDir;

using test::test_device;
using test::test_device_spec;

// A runtime that ignores OPSILA_* variables of the environment.
ClRuntimeOptions plain_options() {
  ClRuntimeOptions o;
  o.read_environment = false;
  return o;
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// ------------------------------------------------------------ running opsila

RunResult opsila(const std::vector<std::string>& args, const test::EnvChanges& env = {}) {
  return test::run_program(OPSILA_BINARY, args, env);
}

// `opsila render` of the small mirror-and-glass OBJ scene into `out`.
std::vector<std::string> render_args(const std::string& out, const std::vector<std::string>& extra = {}) {
  std::vector<std::string> args = {"render", std::string(OPSILA_SOURCE_DIR) + "/tests/oclgrind/tiny.obj",
                                   "-o",     out,
                                   "--size", "40x30",
                                   "--depth", "5",
                                   "--pes",  "4",
                                   "--light", "2,5,4",
                                   "--light", "-3,4,1,0.4,0.4,0.5",
                                   "--eye",  "1.5,2.2,5",
                                   "--look-at", "0,0.8,0",
                                   "-q"};
  if (*test_device_spec()) args.insert(args.end(), {"--device", test_device_spec()});
  args.insert(args.end(), extra.begin(), extra.end());
  return args;
}

std::string first_line(const std::string& text) { return text.substr(0, text.find('\n')); }

// Exactly one "opsila: error: ..." line, naming the problem; whatever follows
// it (a build log) is indented under it. A driver may print its own lines
// before it (PoCL's compiler says "1 error generated.").
void expect_one_error(const RunResult& r, int exit_code, const std::string& must_contain) {
  EXPECT_EQ(r.exit_code, exit_code) << r.err;
  std::vector<std::string> lines;
  std::istringstream in(r.err);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  std::size_t errors = 0, at = lines.size();
  for (std::size_t i = 0; i < lines.size(); ++i)
    if (lines[i].rfind("opsila: error: ", 0) == 0) ++errors, at = std::min(at, i);
  ASSERT_EQ(errors, 1u) << r.err;
  EXPECT_TRUE(contains(lines[at], must_contain)) << "expected '" << must_contain << "' in: " << lines[at];
  for (std::size_t i = at + 1; i < lines.size(); ++i)
    EXPECT_EQ(lines[i].rfind("    ", 0), 0u) << "unindented line after the error: " << lines[i];
}

// The "opsila: error:" line itself.
std::string error_line(const RunResult& r) {
  std::istringstream in(r.err);
  for (std::string line; std::getline(in, line);)
    if (line.rfind("opsila: error: ", 0) == 0) return line;
  return "";
}

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
  // The SPMD kernel's per-level stats and traffic live in local memory.
  EXPECT_EQ(required_local_mem(), std::size_t(OPSILA_MAX_DEPTH) * (OPSILA_STAT_COUNT + OPSILA_TRAFFIC_MAX_PES) * 4);
  DeviceCapabilities all_wrong = capable();
  all_wrong.version = "OpenCL 1.0";
  all_wrong.compiler_available = false;
  all_wrong.local_mem_size = 0;
  EXPECT_EQ(missing_capabilities(all_wrong).size(), 3u);
}

// --------------------------------------------------- kernel source and cache

TEST(KernelSource, BrokenSourceFailsWithTheBuildLog) {
  ClRuntimeOptions o = plain_options();
  o.kernel_source = "__kernel void item_buffer(__global int *p) { p[0] = this_is_not_declared; }\n";
  o.kernel_source_origin = "broken test source";
  ClRuntime rt(test_device(), o);
  EXPECT_EQ(rt.kernel_source_origin(), "broken test source");
  try {
    rt.program();
    FAIL() << "a broken kernel source built";
  } catch (const ClError& e) {
    const std::string m = e.what();
    EXPECT_TRUE(contains(first_line(m), "clBuildProgram: CL_BUILD_PROGRAM_FAILURE")) << m;
    EXPECT_TRUE(contains(first_line(m), "broken test source")) << m;
    EXPECT_TRUE(contains(first_line(m), "build log:")) << m;
    EXPECT_TRUE(contains(m, "this_is_not_declared")) << "the compiler's message is shown:\n" << m;
  }
  // Asking again fails again (nothing half-built is kept).
  EXPECT_THROW(rt.kernel("item_buffer"), ClError);
}

// A kernel writing `value`: two sources that differ only there.
int run_probe(int value) {
  ClRuntimeOptions o = plain_options();
  o.kernel_source = "__kernel void probe(__global int *out) { out[0] = " + std::to_string(value) + "; }\n";
  ClRuntime rt(test_device(), o);
  cl::Kernel k = rt.kernel("probe");
  cl::Buffer out = upload(rt, std::vector<cl_int>{-1}, "probe output");
  k.setArg(0, out);
  cl_check(rt.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(1), cl::NDRange(1)), "probe");
  cl_int result = 0;
  cl_check(rt.queue().enqueueReadBuffer(out, CL_TRUE, 0, sizeof result, &result), "probe read");
  return result;
}

// The driver's compile cache (POCL_CACHE_DIR under ctest) is keyed by the
// source text: a changed source is compiled again, never served stale.
TEST(KernelSource, TheCompileCacheFollowsTheSource) {
  EXPECT_EQ(run_probe(1), 1);
  EXPECT_EQ(run_probe(2), 2);
  EXPECT_EQ(run_probe(1), 1);
  EXPECT_EQ(run_probe(2), 2);
}

// The renderer really runs a replacement source: doubling the fixed-point
// scale in the kernels (the host divides by its own, unchanged constant)
// doubles every pixel.
TEST(KernelSource, TheRendererRunsTheReplacementSource) {
  const std::string from = "#define OPSILA_FIXED_SHIFT 24";
  std::string source = kernel_source();
  const std::size_t at = source.find(from);
  ASSERT_NE(at, std::string::npos) << "the shared header no longer defines the shift as expected";
  source.replace(at, from.size(), "#define OPSILA_FIXED_SHIFT 25");

  Scene s = test::mirror_glass_scene(32, 3);
  RenderSettings settings;
  settings.num_pes = 4;
  RenderResult base, doubled;
  {
    ClRuntime rt(test_device(), plain_options());
    base = render(s, settings, rt);
  }
  {
    ClRuntimeOptions o = plain_options();
    o.kernel_source = source;
    o.kernel_source_origin = "doubled scale";
    ClRuntime rt(test_device(), o);
    doubled = render(s, settings, rt);
  }
  ASSERT_EQ(base.rgb.size(), doubled.rgb.size());
  double brightest = 0;
  for (std::size_t i = 0; i < base.rgb.size(); ++i) {
    brightest = std::max(brightest, double(base.rgb[i]));
    ASSERT_NEAR(doubled.rgb[i], 2.0f * base.rgb[i], 1e-5) << "value " << i;
  }
  EXPECT_GT(brightest, 0.1);
}

TEST(KernelSource, EnvironmentHookEndToEnd) {
  TempDir dir;
  // A good render first, so that the driver's cache holds the real kernels.
  RunResult good = opsila(render_args(dir.file("good.pfm")), {{"OPSILA_KERNEL_SOURCE", std::nullopt}});
  ASSERT_EQ(good.exit_code, 0) << good.err;

  const std::string broken = dir.write("broken.cl", "__kernel void item_buffer(__global int *p) { p[0] = 1 }\n");
  RunResult r = opsila(render_args(dir.file("broken.pfm")), {{"OPSILA_KERNEL_SOURCE", broken}});
  expect_one_error(r, 3, "clBuildProgram: CL_BUILD_PROGRAM_FAILURE");
  EXPECT_TRUE(contains(error_line(r), "OPSILA_KERNEL_SOURCE=" + broken)) << r.err;
  EXPECT_TRUE(contains(r.err, "build log")) << r.err;
  EXPECT_TRUE(contains(r.err, "\n    ")) << "the build log follows the error line:\n" << r.err;
  EXPECT_FALSE(test::file_exists(dir.file("broken.pfm")));

  RunResult missing = opsila(render_args(dir.file("missing.pfm")),
                             {{"OPSILA_KERNEL_SOURCE", dir.file("no-such-file.cl")}});
  expect_one_error(missing, 2, "OPSILA_KERNEL_SOURCE=");
  EXPECT_FALSE(test::file_exists(dir.file("missing.pfm")));

  // The real kernels again: the same bytes as before.
  RunResult again = opsila(render_args(dir.file("again.pfm")), {{"OPSILA_KERNEL_SOURCE", std::nullopt}});
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_EQ(test::read_file(dir.file("good.pfm")), test::read_file(dir.file("again.pfm")));
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

// ------------------------------------------------------------- launch faults

// scatter_plan with tiny buffers: a kernel to launch, and its counts to read.
struct PlanKernel {
  cl::Kernel kernel;
  cl::Buffer key_totals, pe_total, bank_begin, bank_count, key_begin, key_count, key_base, group_pe, group_first,
      counts;
  explicit PlanKernel(ClRuntime& rt) {
    kernel = rt.kernel("scatter_plan");
    key_totals = upload(rt, std::vector<cl_int>{0, 3}, "key totals");  // one PE: 3 rays that spawn more
    pe_total = upload(rt, std::vector<cl_int>{0}, "PE totals");
    bank_begin = upload(rt, std::vector<cl_int>{0}, "bank begin");
    bank_count = upload(rt, std::vector<cl_int>{0}, "bank count");
    key_begin = upload(rt, std::vector<cl_int>{0, 0}, "key begin");
    key_count = upload(rt, std::vector<cl_int>{0, 0}, "key count");
    key_base = upload(rt, std::vector<cl_int>{0, 0}, "key base");
    group_pe = upload(rt, std::vector<cl_int>{0, 0}, "group PEs");
    group_first = upload(rt, std::vector<cl_int>{0, 0}, "group slots");
    counts = upload(rt, std::vector<cl_int>{-1, -1, -1}, "counts");
    int a = 0;
    kernel.setArg(a++, 1);  // PEs
    kernel.setArg(a++, 0);  // this device's PEs: [0, 1)
    kernel.setArg(a++, 1);
    kernel.setArg(a++, 2);  // slots
    kernel.setArg(a++, 2);  // cap
    kernel.setArg(a++, 1);  // work-group size
    kernel.setArg(a++, 0);  // not throttled
    for (cl::Buffer* b : {&key_totals, &pe_total, &bank_begin, &bank_count, &key_begin, &key_count, &key_base,
                          &group_pe, &group_first, &counts})
      kernel.setArg(a++, *b);
  }
};

TEST(LaunchFaults, CleanLaunchesPassAndErrorsNameTheLastKernel) {
  ClRuntime rt(test_device(), plain_options());
  PlanKernel plan(rt);
  std::vector<LaunchRecord> records;
  Launcher launch(rt, records);
  launch.run(plan.kernel, "scatter_plan", 1, 1, 4);
  cl_int counts[3] = {0, 0, 0};
  EXPECT_NO_THROW(
      launch.check(rt.queue().enqueueReadBuffer(plan.counts, CL_TRUE, 0, sizeof counts, counts), "read"));
  EXPECT_EQ(counts[0], 1);  // 3 entries for one PE of 2 slots: one waits
  EXPECT_EQ(counts[1], 2);
  try {
    launch.check(CL_OUT_OF_RESOURCES, "clFinish");
    FAIL() << "an error code passed";
  } catch (const ClError& e) {
    EXPECT_STREQ(e.what(), "clFinish: CL_OUT_OF_RESOURCES (-5) after kernel scatter_plan (round 4)");
  }
  launch.harvest();
  ASSERT_EQ(records.size(), 1u);
  EXPECT_EQ(records[0].name, "scatter_plan");
}

// An endless render launches without end: past its cap the launcher folds
// each kernel's later launches into one record, their count and seconds.
TEST(LaunchRecords, PastTheCapEachKernelsLaunchesAreFolded) {
  ClRuntime rt(test_device(), plain_options());
  PlanKernel plan(rt);
  std::vector<LaunchRecord> records;
  Launcher launch(rt, records, 3);
  for (int i = 0; i < 10; ++i) launch.run(plan.kernel, i % 2 ? "odd" : "even", 1, 1, i);
  launch.check(rt.queue().finish(), "clFinish");
  launch.harvest();
  ASSERT_EQ(records.size(), 5u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(records[i].round, i);
    EXPECT_EQ(records[i].launches, 1u);
  }
  EXPECT_EQ(records[3].name, "odd");  // rounds 3, 5, 7, 9
  EXPECT_EQ(records[3].round, LaunchRecord::kFoldedRound);
  EXPECT_EQ(records[3].launches, 4u);
  EXPECT_EQ(records[4].name, "even");  // rounds 4, 6, 8
  EXPECT_EQ(records[4].round, LaunchRecord::kFoldedRound);
  EXPECT_EQ(records[4].launches, 3u);
  EXPECT_GE(records[3].seconds, 0.0);
}

// The rank exchange's per-round figures: kept one by one up to the cap,
// then added into the last row, so every sum over the rounds stays exact.
TEST(ExchangeRecords, PastTheCapRoundsAreAddedIntoTheLastRow) {
  std::vector<std::vector<std::uint64_t>> rows;
  std::vector<double> seconds;
  std::vector<std::uint64_t> total(3, 0);
  double total_seconds = 0;
  for (std::uint64_t k = 0; k < 10; ++k) {
    const std::vector<std::uint64_t> row = {k, 10 * k, 100 * k};
    keep_round(rows, row, 3);
    keep_round(seconds, 0.5 * double(k), 3);
    for (int i = 0; i < 3; ++i) total[i] += row[i];
    total_seconds += 0.5 * double(k);
  }
  ASSERT_EQ(rows.size(), 3u);
  ASSERT_EQ(seconds.size(), 3u);
  EXPECT_EQ(rows[0], (std::vector<std::uint64_t>{0, 0, 0}));
  EXPECT_EQ(rows[1], (std::vector<std::uint64_t>{1, 10, 100}));
  EXPECT_EQ(rows[2], (std::vector<std::uint64_t>{44, 440, 4400}));  // rounds 2 .. 9
  std::vector<std::uint64_t> sum(3, 0);
  for (const auto& r : rows)
    for (int i = 0; i < 3; ++i) sum[i] += r[i];
  EXPECT_EQ(sum, total);
  EXPECT_DOUBLE_EQ(seconds[0] + seconds[1] + seconds[2], total_seconds);
}

// A rank exchange run for more rounds than its cap holds that many rows,
// its four per-round tables alike.
TEST(ExchangeRecords, AnExchangeKeepsAtMostItsCapOfRounds) {
  ClRuntime rt(test_device(), plain_options());
  const int pes = 4;
  PeGroup one;
  one.begin = 0;
  one.end = pes;
  RankExchange x(rt, Ranks::world(), one, pes, 5, 3);
  cl::Buffer totals = device_buffer(rt, pes * sizeof(cl_int), "test totals");
  const std::vector<cl_int> none(pes, 0);
  cl_check(rt.queue().enqueueWriteBuffer(totals, CL_TRUE, 0, pes * sizeof(cl_int), none.data()), "write totals");
  DescriptorSet next, into;
  next.allocate(rt, 16, "test next");
  for (int round = 0; round < 10; ++round) {
    x.start(totals, next, 0);
    x.exchange();
    x.finish(next, into, 1);
  }
  EXPECT_EQ(x.sent.size(), 3u);
  EXPECT_EQ(x.received.size(), 3u);
  EXPECT_EQ(x.staging_seconds.size(), 3u);
  EXPECT_EQ(x.mpi_seconds.size(), 3u);
  x.reset();
  EXPECT_TRUE(x.sent.empty());
}

TEST(LaunchFaults, AnEnqueueThatFailsNamesTheKernel) {
  ClRuntime rt(test_device(), plain_options());
  cl::Kernel k = rt.kernel("scatter_plan");  // no arguments set
  std::vector<LaunchRecord> records;
  Launcher launch(rt, records);
  try {
    launch.run(k, "scatter_plan", 1, 1, 0);
    FAIL() << "a kernel without arguments was enqueued";
  } catch (const ClError& e) {
    EXPECT_TRUE(contains(e.what(), "clEnqueueNDRangeKernel(scatter_plan)")) << e.what();
  }
}

// A command can fail on the device after its enqueue succeeded (what a GPU
// reports as CL_OUT_OF_RESOURCES, or a watchdog reset). A user event set to
// an error stands in for the fault: the kernel waiting on it fails. Some
// drivers then answer a blocking read with CL_SUCCESS, so check() must look
// at the launches' own status.
TEST(LaunchFaults, AKernelThatFailsOnTheDeviceIsNamed) {
  ClRuntime rt(test_device(), plain_options());
  PlanKernel plan(rt);
  std::vector<LaunchRecord> records;
  Launcher launch(rt, records);
  cl_int err = CL_SUCCESS;
  cl::UserEvent fault(rt.context(), &err);
  cl_check(err, "clCreateUserEvent");
  const std::vector<cl::Event> wait = {fault};
  launch.run(plan.kernel, "scatter_plan", 1, 1, 7, &wait);
  cl_check(fault.setStatus(CL_OUT_OF_RESOURCES), "clSetUserEventStatus");
  cl_int counts[3] = {0, 0, 0};
  const cl_int read = rt.queue().enqueueReadBuffer(plan.counts, CL_TRUE, 0, sizeof counts, counts);
  if (read == CL_SUCCESS && counts[0] == 1 && counts[1] == 2)
    GTEST_SKIP() << rt.device().device_name << " ran a command whose wait list failed";
  try {
    launch.check(read, "clEnqueueReadBuffer(counts)");
    FAIL() << "a failed launch went unnoticed (the read returned " << read << ")";
  } catch (const ClError& e) {
    const std::string m = e.what();
    EXPECT_TRUE(contains(m, "scatter_plan (round 7)")) << m;
  }
}

// ---------------------------------------------------------------- determinism

TEST(Determinism, SameInputsGiveTheSameBytesRunToRun) {
  TempDir dir;
  RunResult a = opsila(render_args(dir.file("a.pfm"), {"--item-buffer", dir.file("a.npy")}));
  RunResult b = opsila(render_args(dir.file("b.pfm"), {"--item-buffer", dir.file("b.npy")}));
  ASSERT_EQ(a.exit_code, 0) << a.err;
  ASSERT_EQ(b.exit_code, 0) << b.err;
  const std::string pa = test::read_file(dir.file("a.pfm")), pb = test::read_file(dir.file("b.pfm"));
  ASSERT_GT(pa.size(), 40u * 30u * 12u);
  EXPECT_TRUE(pa == pb) << "two runs of the same render differ";
  EXPECT_TRUE(test::read_file(dir.file("a.npy")) == test::read_file(dir.file("b.npy")));
}

TEST(Determinism, BankCapacityDownToOneGivesTheSameImage) {
  TempDir dir;
  RunResult base = opsila(render_args(dir.file("auto.pfm")));
  ASSERT_EQ(base.exit_code, 0) << base.err;
  const FloatImage reference = read_pfm(dir.file("auto.pfm"));
  for (const char* capacity : {"1", "2", "5", "64"}) {
    const std::string out = dir.file(std::string("n") + capacity + ".pfm");
    RunResult r = opsila(render_args(out, {"--bank-capacity", capacity}));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const FloatImage img = read_pfm(out);
    EXPECT_GE(test::clamped_psnr(img.rgb, reference.rgb), 60.0) << "--bank-capacity " << capacity;
  }
}

// The item buffer is launched in tiles (bounded work per launch): the tile
// size changes the launches, never the image.
TEST(Determinism, ItemBufferTilesDoNotChangeTheImage) {
  ClRuntime rt(test_device(), plain_options());
  Scene s = test::mirror_glass_scene(40, 3);  // 40x30
  RenderSettings settings;
  settings.num_pes = 4;
  RenderResult whole = render(s, settings, rt);
  settings.item_buffer_tile = 97;
  RenderResult tiled = render(s, settings, rt);
  ASSERT_EQ(whole.rgb.size(), tiled.rgb.size());
  EXPECT_EQ(0, std::memcmp(whole.rgb.data(), tiled.rgb.data(), whole.rgb.size() * sizeof(float)));
  EXPECT_EQ(whole.item_buffer, tiled.item_buffer);
  const auto item_launches = std::count_if(tiled.stats.launches.begin(), tiled.stats.launches.end(),
                                           [](const LaunchRecord& l) { return l.name == "item_buffer"; });
  // Bounded work: no launch covers more than item_buffer_tile pixels.
  EXPECT_GE(item_launches, (40 * 30 + 96) / 97);
}

// -------------------------------------------- the scatter on its own (small)

// The exchange on its own, small enough for Oclgrind: a pool with holes,
// SPMD output places (used and stale), banks that overflow
// (tests/exchange_check.h checks every lane of every record).
void small_scatter(int pes, int slots, int S, int pool_len, unsigned seed) {
  test::ExchangeCase c;
  c.pes = pes;
  c.slots = slots;
  c.spawn_slots = S;
  c.pool_len = pool_len;
  c.out_groups = 2;
  c.group_size = 2;
  c.seed = seed;
  for (int by_block : {0, 1})  // both moves under Oclgrind, throttled or not
    for (bool throttle : {false, true}) {
      // A runtime each: with four exchanges on one runtime, Oclgrind 21.10's
      // uninitialized-value check reported reads of values that the
      // exchange's own kernels had just written (the scan's totals, the
      // count's ranks), in buffers made after an earlier exchange's were
      // released. The values read were the ones written, on PoCL and under
      // Oclgrind alike (printed from the kernels), and zero-filling one such
      // buffer only moved the report to the next.
      ClRuntime rt(test_device(), plain_options());
      c.move_by_block = by_block;
      c.throttle = throttle;
      test::check_exchange(rt, c);
    }
}

TEST(SmallScatter, OutputSlotsAndQueueWithOverflow) {
  small_scatter(3, 2, 3, 7, 11);    // most entries wait
  small_scatter(4, 24, 4, 5, 12);   // most entries fit
  small_scatter(1, 1, 2, 3, 13);    // one PE, one slot
}

}  // namespace
}  // namespace opsila
