// OpenEXR output (-o OUT.exr): linear RGB as 32-bit float, or half with
// --exr-half, read back with the OpenEXR library; exrheader reads it; a
// failed write leaves nothing behind.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>

#include <cmath>
#include <cstdlib>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include <Imath/half.h>
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfStdIO.h>

#include "formats/image/image_io.h"
#include "test_util.h"

namespace opsila {
namespace {

using test::RunResult;
using test::TempDir;
using test::run_opsila;

struct ExrFile {
  int width = 0, height = 0;
  Imf::PixelType type = Imf::FLOAT;
  std::vector<std::string> channels;
  std::vector<float> rgb;  // 3 per pixel, row 0 = top, as the file holds it (half widened exactly)
};

// Reads R, G, B with the OpenEXR library, each as the file stores it.
ExrFile read_exr(const std::string& bytes) {
  Imf::StdISStream stream;
  stream.str(bytes);
  Imf::InputFile file(stream);
  ExrFile out;
  const Imath::Box2i window = file.header().dataWindow();
  out.width = window.max.x - window.min.x + 1;
  out.height = window.max.y - window.min.y + 1;
  for (auto c = file.header().channels().begin(); c != file.header().channels().end(); ++c) {
    out.channels.push_back(c.name());
    out.type = c.channel().type;
  }
  out.rgb.assign(std::size_t(out.width) * out.height * 3, 0);
  Imf::FrameBuffer frame;
  const char* names[3] = {"R", "G", "B"};
  char* base = reinterpret_cast<char*>(out.rgb.data()) -
               (std::size_t(window.min.x) + std::size_t(window.min.y) * out.width) * 3 * sizeof(float);
  for (int c = 0; c < 3; ++c)
    frame.insert(names[c], Imf::Slice(Imf::FLOAT, base + c * sizeof(float), 3 * sizeof(float),
                                      3 * sizeof(float) * out.width));
  file.setFrameBuffer(frame);
  file.readPixels(window.min.y, window.max.y);
  return out;
}

std::vector<float> ramp(int w, int h) {
  std::vector<float> v(std::size_t(w) * h * 3);
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = float(i) * 0.37f + 1e-3f;
  return v;
}

TEST(Exr, FloatRoundTripKeepsEveryValueAndRowOrder) {
  const int w = 7, h = 5;
  std::vector<float> rgb = ramp(w, h);
  rgb[0] = 1e30f;  // beyond half, kept in float
  rgb[4] = 0.0f;
  const ExrFile f = read_exr(encode_exr(w, h, rgb, false));
  EXPECT_EQ(f.width, w);
  EXPECT_EQ(f.height, h);
  EXPECT_EQ(f.channels, (std::vector<std::string>{"B", "G", "R"}));  // the library lists them by name
  EXPECT_EQ(f.type, Imf::FLOAT);
  EXPECT_EQ(f.rgb, rgb);
}

TEST(Exr, HalfStoresEachValueRoundedAndClampsToHalfsLargest) {
  const int w = 4, h = 3;
  std::vector<float> rgb = ramp(w, h);
  rgb[1] = 1e6f;  // beyond half's range: its largest finite value
  const ExrFile f = read_exr(encode_exr(w, h, rgb, true));
  EXPECT_EQ(f.type, Imf::HALF);
  ASSERT_EQ(f.rgb.size(), rgb.size());
  for (std::size_t i = 0; i < rgb.size(); ++i) {
    const float want = i == 1 ? 65504.0f : float(Imath::half(rgb[i]));
    EXPECT_EQ(f.rgb[i], want) << i;
  }
  EXPECT_NE(f.rgb[5], rgb[5]);  // half does round (0.37 * 5 is not a half)
}

TEST(Exr, NonFiniteValueIsRefused) {
  std::vector<float> rgb(3, 0.5f);
  rgb[2] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(encode_exr(1, 1, rgb, false), std::logic_error);
  rgb[2] = std::numeric_limits<float>::infinity();
  EXPECT_THROW(encode_exr(1, 1, rgb, true), std::logic_error);
  EXPECT_THROW(encode_exr(2, 1, rgb, false), std::invalid_argument);
}

const char* kScene = R"({"image": {"width": 24, "height": 18}, "lights": [{"position": [0, 5, 5], "intensity": [3, 2, 1]}],
  "ambient": 0.2, "objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1}]})";

// The render written as .exr holds exactly the values of the .pfm of the
// same render; with --exr-half, those values rounded to half.
TEST(ExrOutput, HoldsThePfmValuesInFloatOrHalf) {
  TempDir dir;
  const std::string scene = dir.write("s.json", kScene);
  for (const char* out : {"x.pfm", "x.exr"}) {
    const RunResult r = run_opsila({"render", scene, "-o", dir.file(out), "--reference", "-q"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  const RunResult r = run_opsila({"render", scene, "-o", dir.file("h.exr"), "--exr-half", "--reference", "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const FloatImage pfm = read_pfm(dir.file("x.pfm"));
  const ExrFile exr = read_exr(test::read_file(dir.file("x.exr")));
  const ExrFile half = read_exr(test::read_file(dir.file("h.exr")));
  EXPECT_EQ(exr.width, 24);
  EXPECT_EQ(exr.height, 18);
  EXPECT_EQ(exr.type, Imf::FLOAT);
  EXPECT_EQ(exr.rgb, pfm.rgb);
  EXPECT_EQ(half.type, Imf::HALF);
  ASSERT_EQ(half.rgb.size(), pfm.rgb.size());
  double hit = 0;
  for (std::size_t i = 0; i < pfm.rgb.size(); ++i) {
    EXPECT_EQ(half.rgb[i], float(Imath::half(pfm.rgb[i]))) << i;
    hit += pfm.rgb[i];
  }
  EXPECT_GT(hit, 0);  // the sphere is in the picture
  EXPECT_LT(test::read_file(dir.file("h.exr")).size(), test::read_file(dir.file("x.exr")).size());
}

// OpenEXR's own tool reads the file and sees what was written.
TEST(ExrOutput, ExrheaderReadsIt) {
  if (std::system("command -v exrheader >/dev/null 2>&1") != 0)
    GTEST_SKIP() << "exrheader is not installed (Debian package openexr)";
  TempDir dir;
  const std::string scene = dir.write("s.json", kScene);
  ASSERT_EQ(run_opsila({"render", scene, "-o", dir.file("x.exr"), "--reference", "-q"}).exit_code, 0);
  ASSERT_EQ(run_opsila({"render", scene, "-o", dir.file("h.exr"), "--reference", "-q", "--exr-half"}).exit_code, 0);
  const RunResult f = test::run_program("/bin/sh", {"-c", "exrheader " + dir.file("x.exr")});
  EXPECT_EQ(f.exit_code, 0) << f.err;
  EXPECT_NE(f.out.find("R, 32-bit floating-point"), std::string::npos) << f.out;
  EXPECT_NE(f.out.find("(0 0) - (23 17)"), std::string::npos) << f.out;
  const RunResult h = test::run_program("/bin/sh", {"-c", "exrheader " + dir.file("h.exr")});
  EXPECT_EQ(h.exit_code, 0) << h.err;
  EXPECT_NE(h.out.find("G, 16-bit floating-point"), std::string::npos) << h.out;
}

TEST(ExrOutput, BadFlagsAreOneClearError) {
  TempDir dir;
  const std::string scene = dir.write("s.json", kScene);
  const auto before = dir.entries();
  const RunResult half_png = run_opsila({"render", scene, "-o", dir.file("x.png"), "--exr-half", "--reference"});
  EXPECT_EQ(half_png.exit_code, 2);
  ASSERT_EQ(half_png.error_lines().size(), 1u) << half_png.err;
  EXPECT_NE(half_png.error_lines()[0].find("--exr-half"), std::string::npos) << half_png.err;
  const RunResult missing = run_opsila({"render", scene, "-o", dir.file("none/x.exr"), "--reference"});
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.err.find("none/x.exr: cannot write"), std::string::npos) << missing.err;
  EXPECT_EQ(dir.entries(), before);
}

// A write that fails (the file-size limit stands in for a full disk) leaves
// no .exr, no temporary file, and an older file of that name untouched.
TEST(ExrOutput, AFailedWriteLeavesNothingBehind) {
  TempDir dir;
  const std::string scene = dir.write("s.json", kScene);
  const std::string old = dir.write("x.exr", "an older file");
  const auto before = dir.entries();
  struct rlimit saved;
  ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &saved), 0);
  struct rlimit small = saved;
  small.rlim_cur = 600;  // far below the 24x18 image's bytes
  void (*old_handler)(int) = ::signal(SIGXFSZ, SIG_IGN);
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &small), 0);
  const RunResult r = run_opsila({"render", scene, "-o", old, "--reference"});
  ::setrlimit(RLIMIT_FSIZE, &saved);
  ::signal(SIGXFSZ, old_handler);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(r.error_lines().size(), 1u) << r.err;
  EXPECT_NE(r.err.find("x.exr: cannot write"), std::string::npos) << r.err;
  EXPECT_EQ(dir.entries(), before);
  EXPECT_EQ(test::read_file(old), "an older file");
}

}  // namespace
}  // namespace opsila
