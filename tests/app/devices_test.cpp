// Device choice with several OpenCL implementations installed: PoCL,
// Mesa's Rusticl (its llvmpipe device listed only with RUSTICL_ENABLE) and
// Mesa's Clover (a platform with no device without a GPU). `opsila devices`
// lists every device once, names the empty platforms, marks one default;
// --device by name and by index picks the device asked for, and both
// implementations render the same image.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <regex>
#include <string>
#include <vector>

#include "formats/image/image_io.h"
#include "core/util.h"
#include "device/cl_runtime.h"
#include "test_util.h"

namespace opsila {
namespace {

// Rusticl lists its llvmpipe device only when asked to.
const test::EnvChanges kRusticlOn = {{"RUSTICL_ENABLE", std::string("llvmpipe")}};

// The names of the installed platforms, empty ones included.
std::vector<std::string> platform_names() {
  std::vector<cl::Platform> platforms;
  if (cl::Platform::get(&platforms) != CL_SUCCESS) return {};
  std::vector<std::string> names;
  for (const cl::Platform& p : platforms) names.push_back(lower(p.getInfo<CL_PLATFORM_NAME>()));
  return names;
}

bool has_platform(const std::string& fragment) {
  const std::vector<std::string> names = platform_names();
  return std::any_of(names.begin(), names.end(),
                     [&](const std::string& n) { return n.find(fragment) != std::string::npos; });
}

// One listed device: "* [flat] platform:device  name".
struct Listed {
  int flat = -1;
  bool is_default = false;
  std::string name, platform;
};

std::vector<Listed> parse_listing(const std::string& out) {
  std::vector<Listed> listed;
  const std::regex device_line(R"(^([* ]) \[(\d+)\] (\d+):(\d+)  (.*?)(  \(default\))?$)");
  const std::regex platform_line(R"(^      platform: (.*)$)");
  std::smatch m;
  std::size_t begin = 0;
  while (begin < out.size()) {
    std::size_t end = out.find('\n', begin);
    if (end == std::string::npos) end = out.size();
    const std::string line = out.substr(begin, end - begin);
    begin = end + 1;
    if (std::regex_match(line, m, device_line))
      listed.push_back({std::stoi(m[2]), m[1] == "*", m[5], ""});
    else if (std::regex_match(line, m, platform_line) && !listed.empty())
      listed.back().platform = m[1];
  }
  return listed;
}

TEST(DeviceChoice, ListsEveryDeviceOnceAndNamesEmptyPlatforms) {
  if (platform_names().empty()) GTEST_SKIP() << "no OpenCL platform installed";
  const test::RunResult r = test::run_program(OPSILA_BINARY, {"devices"}, kRusticlOn);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");
  const std::vector<Listed> listed = parse_listing(r.out);
  ASSERT_FALSE(listed.empty()) << r.out;
  int defaults = 0;
  for (std::size_t i = 0; i < listed.size(); ++i) {
    EXPECT_EQ(listed[i].flat, static_cast<int>(i)) << r.out;  // indices 0, 1, 2... in order
    EXPECT_FALSE(listed[i].platform.empty()) << r.out;
    defaults += listed[i].is_default;
  }
  EXPECT_EQ(defaults, 1) << r.out;
  auto listed_on = [&](const std::string& platform) {
    return std::any_of(listed.begin(), listed.end(), [&](const Listed& l) { return lower(l.platform) == platform; });
  };
  if (has_platform("portable computing language")) EXPECT_TRUE(listed_on("portable computing language")) << r.out;
  if (has_platform("rusticl")) EXPECT_TRUE(listed_on("rusticl")) << r.out;
  if (has_platform("clover")) {
    EXPECT_FALSE(listed_on("clover")) << r.out;
    EXPECT_NE(r.out.find("platform Clover: no devices"), std::string::npos) << r.out;
  }
}

TEST(DeviceChoice, AnEmptyPlatformIsNamedWithWhatToDo) {
  if (!has_platform("rusticl")) GTEST_SKIP() << "needs Mesa's Rusticl (Debian's mesa-opencl-icd)";
  test::TempDir dir;
  const std::string obj = dir.write("t.obj", "v -1 -1 0\nv 1 -1 0\nv 0 1 0\nf 1 2 3\n");
  // Without RUSTICL_ENABLE, Rusticl's platform is there and lists nothing.
  const test::RunResult r = test::run_program(
      OPSILA_BINARY, {"render", obj, "-o", dir.file("x.png"), "--size", "4x4", "--device", "rusticl"},
      {{"RUSTICL_ENABLE", std::nullopt}});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
  EXPECT_NE(r.err.find("--device rusticl: platform 'rusticl' has no devices"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("RUSTICL_ENABLE=llvmpipe"), std::string::npos) << r.err;
  EXPECT_FALSE(test::file_exists(dir.file("x.png")));
}

// --device NAME and --device INDEX pick that device (the render says which
// on stderr); Rusticl's and PoCL's images agree (compilers may differ in the
// last bit of a float, so not byte for byte).
TEST(DeviceChoice, ByNameAndByIndexOnPoclAndRusticl) {
  if (!has_platform("portable computing language") || !has_platform("rusticl"))
    GTEST_SKIP() << "needs PoCL and Mesa's Rusticl (Debian's pocl-opencl-icd and mesa-opencl-icd)";
  const std::vector<Listed> listed =
      parse_listing(test::run_program(OPSILA_BINARY, {"devices"}, kRusticlOn).out);
  const auto rusticl = std::find_if(listed.begin(), listed.end(), [](const Listed& l) { return l.platform == "rusticl"; });
  ASSERT_NE(rusticl, listed.end());
  test::TempDir dir;
  const std::string scene = std::string(OPSILA_SOURCE_DIR) + "/tests/oclgrind/tiny.obj";
  auto render_on = [&](const std::string& spec, const std::string& expect_name) {
    const std::string out = dir.file("on-" + spec + ".pfm");
    const test::RunResult r = test::run_program(
        OPSILA_BINARY, {"render", scene, "-o", out, "--size", "12x8", "--depth", "3", "--device", spec}, kRusticlOn);
    EXPECT_EQ(r.exit_code, 0) << spec << ": " << r.err;
    EXPECT_NE(r.err.find("opsila: device: " + expect_name), std::string::npos) << spec << ": " << r.err;
    return read_pfm(out).rgb;
  };
  const std::vector<float> by_name = render_on("rusticl", rusticl->name);
  const std::vector<float> by_index = render_on(std::to_string(rusticl->flat), rusticl->name);
  const auto pocl = std::find_if(listed.begin(), listed.end(),
                                 [](const Listed& l) { return l.platform == "Portable Computing Language"; });
  ASSERT_NE(pocl, listed.end());
  const std::vector<float> on_pocl = render_on("pocl", pocl->name);
  EXPECT_EQ(by_name, by_index);  // one device, one image
  ASSERT_EQ(by_name.size(), on_pocl.size());
  EXPECT_GE(test::clamped_psnr(by_name, on_pocl), 60.0);
}

// The kernels compute dot products, cross products, lengths and unit
// vectors as the host does, operation by operation, not with the built-ins,
// which Rusticl rounds otherwise than PoCL: a bounce off the Cornell box's
// walls then changed pixels by up to 0.059 (104 of 3,072). The two agree
// to float rounding now (here, to the bit; not asked for: another compiler
// may still differ in a last bit).
TEST(DeviceChoice, PoclAndRusticlAgreeBeyondABounce) {
  if (!has_platform("portable computing language") || !has_platform("rusticl"))
    GTEST_SKIP() << "needs PoCL and Mesa's Rusticl (Debian's pocl-opencl-icd and mesa-opencl-icd)";
  test::TempDir dir;
  const std::string scene = std::string(OPSILA_SOURCE_DIR) + "/scenes/cornell.json";
  auto render_on = [&](const std::string& spec) {
    const std::string out = dir.file(spec + ".pfm");
    const test::RunResult r = test::run_program(
        OPSILA_BINARY, {"render", scene, "-o", out, "--size", "64x48", "--device", spec, "-q"}, kRusticlOn);
    EXPECT_EQ(r.exit_code, 0) << spec << ": " << r.err;
    return read_pfm(out).rgb;
  };
  const std::vector<float> pocl = render_on("pocl"), rusticl = render_on("rusticl");
  ASSERT_EQ(pocl.size(), rusticl.size());
  float worst = 0;
  for (std::size_t i = 0; i < pocl.size(); ++i) worst = std::max(worst, std::fabs(pocl[i] - rusticl[i]));
  EXPECT_LT(worst, 1e-4f);
}

}  // namespace
}  // namespace opsila
