// Image files stb_image would have decoded into pixels they never held, or
// spent minutes on (formats/image/image_checks.h): refused, with the reason.
#include "formats/image/image_checks.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "formats/image/texture_file.h"
#include "formats/image/image_io.h"
#include "png_crc.h"

namespace opsila {
namespace {

void put_be(std::string& s, std::uint32_t v, int bytes) {
  for (int k = bytes - 1; k >= 0; --k) s.push_back(static_cast<char>((v >> (8 * k)) & 0xFFu));
}

// A PNG chunk with its checksum.
std::string chunk(const std::string& type, const std::string& data) {
  std::string c;
  put_be(c, static_cast<std::uint32_t>(data.size()), 4);
  c += type + data;
  put_be(c, png_crc_bitwise(type + data), 4);
  return c;
}

// An 8-bit palette PNG of w x 1 pixels with the given indices, its
// scanline stored in one uncompressed deflate block.
std::string palette_png(const std::string& palette, const std::string& indices) {
  std::string ihdr;
  put_be(ihdr, static_cast<std::uint32_t>(indices.size()), 4);
  put_be(ihdr, 1, 4);
  ihdr += std::string("\x08\x03\x00\x00\x00", 5);
  const std::string raw = std::string(1, '\0') + indices;  // filter 0
  std::string z = "\x78\x01\x01";
  z.push_back(static_cast<char>(raw.size() & 0xFF)), z.push_back(static_cast<char>(raw.size() >> 8));
  z.push_back(static_cast<char>(~raw.size() & 0xFF)), z.push_back(static_cast<char>((~raw.size() >> 8) & 0xFF));
  std::uint32_t a = 1, b = 0;  // Adler-32
  for (unsigned char c : raw) a = (a + c) % 65521, b = (b + a) % 65521;
  z += raw;
  put_be(z, b << 16 | a, 4);
  return std::string("\x89PNG\r\n\x1a\n", 8) + chunk("IHDR", ihdr) + chunk("PLTE", palette) + chunk("IDAT", z) +
         chunk("IEND", "");
}

// A greyscale JPEG's headers: one quantisation table, w x h, Huffman
// tables of one 1-bit code each (DC difference 0, end of block).
std::string jpeg_head(int w, int h, unsigned char sof) {
  const auto seg = [](unsigned char m, const std::string& d) {
    std::string s = {'\xff', static_cast<char>(m)};
    put_be(s, static_cast<std::uint32_t>(d.size() + 2), 2);
    return s + d;
  };
  std::string frame = "\x08";
  put_be(frame, static_cast<std::uint32_t>(h), 2);
  put_be(frame, static_cast<std::uint32_t>(w), 2);
  frame += std::string("\x01\x01\x11\x00", 4);
  const std::string counts = std::string("\x01", 1) + std::string(15, '\0') + std::string(1, '\0');
  return std::string("\xff\xd8", 2) + seg(0xDB, std::string(1, '\0') + std::string(64, '\x01')) + seg(sof, frame) +
         seg(0xC4, std::string(1, '\0') + counts) + seg(0xC4, "\x10" + counts);
}

std::string jpeg_scan(const std::string& coded) {
  return std::string("\xff\xda\x00\x08\x01\x01\x00\x00\x3f\x00", 10) + coded;
}

std::string decode_problem(const std::string& bytes) {
  Texture t;
  std::string problem;
  const bool ok = decode_texture_memory(reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size(), "x", t,
                                        problem);
  EXPECT_EQ(ok, problem.empty());
  return problem;
}

TEST(ImageChecks, APaletteIndexPastThePaletteIsRefusedNotReadFromMemory) {
  const std::string two = std::string("\xff\x00\x00\x00\x00\xff", 6);  // red, blue
  Texture t;
  std::string problem;
  const std::string good = palette_png(two, std::string("\x00\x01\x01", 3));
  ASSERT_TRUE(decode_texture_memory(reinterpret_cast<const unsigned char*>(good.data()), good.size(), "x", t, problem))
      << problem;
  ASSERT_EQ(t.texels.size(), 3u);
  EXPECT_EQ(t.texels[0], 0x0000FFu);
  EXPECT_EQ(t.texels[2], 0xFF0000u);
  EXPECT_EQ(decode_problem(palette_png(two, std::string("\x00\xc8\x01", 3))),
            "cannot decode the image (a pixel indexes past the PNG palette of 2)");
  // The sentinel colour is one the palette does not hold, whatever it holds.
  std::string taken;
  for (int r = 0; r < 8; ++r) taken += std::string{static_cast<char>(r), '\x5a', '\xa5'};
  EXPECT_EQ(decode_problem(palette_png(taken, std::string("\x07\x06", 2))), "");
  EXPECT_NE(decode_problem(palette_png(taken, std::string("\x07\x08", 2))).find("past the PNG palette of 8"),
            std::string::npos);
  // A full palette leaves nothing to guard; two palettes are refused.
  PaddedPalette padded;
  const std::string full = palette_png(std::string(768, '\x10'), std::string("\xff", 1));
  EXPECT_EQ(pad_png_palette(reinterpret_cast<const unsigned char*>(full.data()), full.size(), padded), "");
  EXPECT_TRUE(padded.bytes.empty());
  std::string twice = good;
  const std::size_t idat = twice.find("IDAT") - 4;
  twice.insert(idat, chunk("PLTE", two));
  EXPECT_EQ(decode_problem(twice), "cannot decode the image (PNG with 2 PLTE chunks, where a PNG has one palette)");
}

// A damaged image chunk is refused, naming it (stb reads no checksum: a
// changed byte had become other pixels); a damaged ancillary chunk is
// ignored, as other PNG readers ignore it.
TEST(ImageChecks, APngWhoseImageChunkFailsItsChecksumIsRefused) {
  const std::string png = encode_png(4, 4, std::vector<float>(4 * 4 * 3, 0.5f));
  ASSERT_EQ(decode_problem(png), "");
  std::string idat = png;
  const std::size_t at = idat.find("IDAT") - 4;
  idat[at + 10] = static_cast<char>(idat[at + 10] ^ 0x01);
  EXPECT_EQ(decode_problem(idat), "damaged PNG: its IDAT chunk at byte " + std::to_string(at) + " fails its CRC check");
  std::string text = png;
  text.insert(at, chunk("tEXt", std::string("Comment\0ok", 10)));
  EXPECT_EQ(decode_problem(text), "");
  text[at + 9] = 'O';
  EXPECT_EQ(decode_problem(text), "");
  std::string ihdr = png;
  ihdr[19] = static_cast<char>(ihdr[19] ^ 0x02);  // width 4 -> 6
  EXPECT_EQ(decode_problem(ihdr), "damaged PNG: its IHDR chunk at byte 8 fails its CRC check");
  reseal_png_chunk(ihdr, 8);
  EXPECT_NE(decode_problem(ihdr), "damaged PNG: its IHDR chunk at byte 8 fails its CRC check");
}

TEST(ImageChecks, AJpegWithoutItsCodedDataOrWithEndlessScansIsRefused) {
  const std::string eoi = "\xff\xd9";
  // 64 x 64: 64 blocks of two 1-bit codes each, 16 bytes of zeros.
  EXPECT_EQ(decode_problem(jpeg_head(64, 64, 0xC0) + jpeg_scan(std::string(16, '\0')) + eoi), "");
  EXPECT_EQ(decode_problem(jpeg_head(4096, 4096, 0xC0) + jpeg_scan("") + eoi),
            "cannot decode the image (JPEG data ends early: 4096x4096 needs at least 8192 bytes of coded data, the "
            "file has 0)");
  // A frame header and no scan: stb had decoded it into invented texels.
  EXPECT_EQ(decode_problem(jpeg_head(4, 4, 0xC0) + eoi),
            "cannot decode the image (JPEG without image data: its markers end before any scan)");
  std::string scans = jpeg_head(64, 64, 0xC2);
  for (int s = 0; s < kMaxJpegScans + 1; ++s) scans += jpeg_scan(std::string(16, '\0'));
  EXPECT_EQ(decode_problem(scans + eoi), "cannot decode the image (JPEG with more than 64 scans, more than encoders write)");
}

}  // namespace
}  // namespace opsila
