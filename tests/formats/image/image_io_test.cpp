// Output formats: PFM, NPY, PNG, sRGB, atomic writes.
#include "formats/image/image_io.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "scene/scene.h"
#include "test_util.h"

namespace opsila {
namespace {

using test::TempDir;

std::uint32_t be32(const std::string& s, std::size_t at) {
  const auto b = [&](std::size_t i) { return static_cast<std::uint32_t>(static_cast<unsigned char>(s[at + i])); };
  return (b(0) << 24) | (b(1) << 16) | (b(2) << 8) | b(3);
}

float le_float(const std::string& s, std::size_t at) {
  unsigned char b[4];
  std::memcpy(b, s.data() + at, 4);
  const std::uint32_t bits = b[0] | (b[1] << 8) | (b[2] << 16) | (static_cast<std::uint32_t>(b[3]) << 24);
  float f;
  std::memcpy(&f, &bits, 4);
  return f;
}

TEST(Srgb, PiecewiseCurveValues) {
  EXPECT_NEAR(srgb_encode(0.0f), 0.0f, 1e-7f);
  EXPECT_NEAR(srgb_encode(1.0f), 1.0f, 1e-6f);
  EXPECT_NEAR(srgb_encode(0.002f), 12.92f * 0.002f, 1e-7f);  // linear segment
  EXPECT_NEAR(srgb_encode(0.5f), 0.735356983f, 1e-5f);       // 1.055 * 0.5^(1/2.4) - 0.055
  EXPECT_NEAR(srgb_encode(0.18f), 0.461356129f, 1e-5f);
  // Both pieces meet at the threshold.
  EXPECT_NEAR(srgb_encode(0.0031308f), 0.04045f, 1e-5f);
  EXPECT_NEAR(srgb_encode(0.0031309f), 0.04045f, 1e-5f);
  // Clamped to [0,1]; NaN counts as 0.
  EXPECT_NEAR(srgb_encode(-3.0f), 0.0f, 1e-7f);
  EXPECT_NEAR(srgb_encode(7.0f), 1.0f, 1e-7f);
  EXPECT_NEAR(srgb_encode(std::nanf("")), 0.0f, 1e-7f);
}

TEST(Srgb, EightBitRounding) {
  EXPECT_EQ(to_srgb8(0.0f), 0);
  EXPECT_EQ(to_srgb8(1.0f), 255);
  EXPECT_EQ(to_srgb8(2.0f), 255);
  EXPECT_EQ(to_srgb8(0.5f), 188);   // 0.7354 * 255 = 187.5 -> 188
  EXPECT_EQ(to_srgb8(0.18f), 118);  // 117.6 -> 118
  const std::vector<std::uint8_t> v = to_srgb8(std::vector<float>{0.0f, 1.0f, -1.0f});
  EXPECT_EQ(v, (std::vector<std::uint8_t>{0, 255, 0}));
}

TEST(Pfm, RoundTripKeepsRowOrderAndValues) {
  TempDir dir;
  // 3x2, every value distinct; unclamped values survive.
  const int w = 3, h = 2;
  std::vector<float> rgb(w * h * 3);
  for (std::size_t i = 0; i < rgb.size(); ++i) rgb[i] = 0.25f * static_cast<float>(i) - 1.0f;
  rgb[5] = 1e6f;
  const std::string path = dir.file("a.pfm");
  write_pfm(path, w, h, rgb);

  const std::string bytes = test::read_file(path);
  const std::string header = "PF\n3 2\n-1.0\n";
  ASSERT_EQ(bytes.size(), header.size() + rgb.size() * 4);
  EXPECT_EQ(bytes.substr(0, header.size()), header);
  // The file stores the bottom row (y = 1) first, little-endian.
  EXPECT_FLOAT_EQ(le_float(bytes, header.size()), rgb[3 * w]);
  EXPECT_FLOAT_EQ(le_float(bytes, header.size() + 4 * 3 * w), rgb[0]);

  const FloatImage back = read_pfm(path);
  EXPECT_EQ(back.width, w);
  EXPECT_EQ(back.height, h);
  ASSERT_EQ(back.rgb.size(), rgb.size());
  for (std::size_t i = 0; i < rgb.size(); ++i) EXPECT_FLOAT_EQ(back.rgb[i], rgb[i]) << i;
}

TEST(Pfm, ReadsBigEndianAndGrey) {
  TempDir dir;
  std::string data = "Pf\n2 1\n1.0\n";
  const float values[2] = {0.5f, 2.0f};
  for (float v : values) {
    std::uint32_t bits;
    std::memcpy(&bits, &v, 4);
    for (int shift = 24; shift >= 0; shift -= 8) data.push_back(static_cast<char>((bits >> shift) & 0xff));
  }
  const std::string path = dir.write("g.pfm", data);
  const FloatImage img = read_pfm(path);
  ASSERT_EQ(img.rgb.size(), 6u);
  EXPECT_FLOAT_EQ(img.rgb[0], 0.5f);
  EXPECT_FLOAT_EQ(img.rgb[2], 0.5f);
  EXPECT_FLOAT_EQ(img.rgb[5], 2.0f);
}

TEST(Pfm, MalformedInputIsAnInputError) {
  TempDir dir;
  EXPECT_THROW(read_pfm(dir.write("bad.pfm", "P6\n1 1\n255\n...")), InputError);
  EXPECT_THROW(read_pfm(dir.write("short.pfm", "PF\n2 2\n-1.0\nabc")), InputError);
  EXPECT_THROW(read_pfm(dir.file("missing.pfm")), InputError);
}

TEST(Npy, HeaderShapeAndRoundTrip) {
  TempDir dir;
  const int h = 2, w = 3;
  std::vector<std::int32_t> items;
  for (int i = 0; i < h * w; ++i) {
    items.push_back(i == 4 ? -1 : i / 2);
    items.push_back(i == 4 ? -1 : 100 + i);
  }
  const std::string path = dir.file("items.npy");
  write_npy_item_buffer(path, h, w, items);

  const std::string bytes = test::read_file(path);
  ASSERT_GE(bytes.size(), 10u);
  EXPECT_EQ(bytes.substr(0, 6), std::string("\x93NUMPY", 6));
  EXPECT_EQ(bytes[6], 1);
  EXPECT_EQ(bytes[7], 0);
  const std::size_t header_len = static_cast<unsigned char>(bytes[8]) | (static_cast<unsigned char>(bytes[9]) << 8);
  EXPECT_EQ((10 + header_len) % 64, 0u);
  const std::string header = bytes.substr(10, header_len);
  EXPECT_EQ(header.back(), '\n');
  EXPECT_NE(header.find("'descr': '<i4'"), std::string::npos);
  EXPECT_NE(header.find("'fortran_order': False"), std::string::npos);
  EXPECT_NE(header.find("'shape': (2, 3, 2)"), std::string::npos);
  EXPECT_EQ(bytes.size(), 10 + header_len + items.size() * 4);

  const ItemBufferFile back = read_npy_item_buffer(path);
  EXPECT_EQ(back.height, h);
  EXPECT_EQ(back.width, w);
  EXPECT_EQ(back.items, items);
}

TEST(Png, WrittenWithTheRightSize) {
  TempDir dir;
  const int w = 5, h = 3;
  std::vector<float> rgb(w * h * 3, 0.5f);
  rgb[0] = 4.0f;  // out of range values are clamped, not an error
  const std::string path = dir.file("x.png");
  write_png(path, w, h, rgb);
  const std::string bytes = test::read_file(path);
  ASSERT_GT(bytes.size(), 33u);
  EXPECT_EQ(bytes.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  EXPECT_EQ(bytes.substr(12, 4), "IHDR");
  EXPECT_EQ(be32(bytes, 16), 5u);
  EXPECT_EQ(be32(bytes, 20), 3u);
  EXPECT_EQ(static_cast<unsigned char>(bytes[24]), 8u);  // bit depth
  EXPECT_EQ(static_cast<unsigned char>(bytes[25]), 2u);  // colour type RGB
}

TEST(AtomicWrite, MissingFolderIsAnErrorAndLeavesNothing) {
  TempDir dir;
  const std::string path = dir.file("no/such/folder/x.png");
  try {
    write_png(path, 1, 1, {0, 0, 0});
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path + ": cannot write ("), std::string::npos) << e.what();
  }
  EXPECT_THROW(write_pfm(dir.file("missing/x.pfm"), 1, 1, {0, 0, 0}), InputError);
  EXPECT_THROW(write_npy_item_buffer(dir.file("missing/x.npy"), 1, 1, {-1, -1}), InputError);
  EXPECT_THROW(write_text_file(dir.file("missing/x.json"), "{}"), InputError);
  EXPECT_TRUE(dir.entries().empty());
}

TEST(AtomicWrite, FolderAsOutputIsAnError) {
  TempDir dir;
  EXPECT_THROW(write_text_file(dir.path(), "x"), InputError);
  EXPECT_THROW(check_output_path(dir.path() + "/"), InputError);
  EXPECT_NO_THROW(check_output_path(dir.file("fine.png")));
  // A regular file where the folder should be (fails for root too).
  const std::string plain = dir.write("plain", "x");
  EXPECT_THROW(write_png(plain + "/x.png", 1, 1, {0, 0, 0}), InputError);
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"plain"});
}

TEST(AtomicWrite, ReplacesWholeFileAndLeavesNoTemporary) {
  TempDir dir;
  const std::string path = dir.file("t.txt");
  write_text_file(path, "first version, longer");
  write_text_file(path, "second");
  EXPECT_EQ(test::read_file(path), "second");
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"t.txt"});
}

TEST(AtomicWrite, UnwritableFolderIsAnError) {
  if (::geteuid() == 0) GTEST_SKIP() << "root can write anywhere";
  TempDir dir;
  const std::string locked = dir.file("locked");
  ASSERT_EQ(::mkdir(locked.c_str(), 0555), 0);
  EXPECT_THROW(write_text_file(locked + "/x.txt", "x"), InputError);
  EXPECT_TRUE(TempDir::list(locked).empty());
  ::chmod(locked.c_str(), 0755);
}

TEST(Psnr, KnownValues) {
  const std::vector<float> a{0, 0, 0, 0}, b{0.1f, 0.1f, 0.1f, 0.1f};
  EXPECT_NEAR(psnr(a, b, 1.0), 20.0, 1e-4);  // MSE 0.01
  EXPECT_TRUE(std::isinf(psnr(a, a, 1.0)));
  EXPECT_THROW(psnr(a, {0.0f}, 1.0), std::invalid_argument);
  EXPECT_NEAR(test::fraction_off(std::vector<float>{0, 0, 0, 1, 1, 1}, std::vector<float>{0, 0, 0, 0.5f, 1, 1}, 2),
              0.5, 1e-9);
}

}  // namespace
}  // namespace opsila
