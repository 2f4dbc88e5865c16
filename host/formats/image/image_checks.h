// What stb_image does not check in a file before it decodes it, so that a
// texture map is refused with a reason instead of becoming pixels the file
// never held (zeros, or memory left by earlier work) or minutes of decoding.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace opsila {

bool is_png(const unsigned char* data, std::size_t size);

// A PNG whose first chunk (IHDR) states a side past max_side: stb refuses
// it, then tries the other formats, and its last reason ("unknown type")
// would hide why. "" when not.
std::string png_side_problem(const unsigned char* data, std::size_t size, int max_side);

// An uncompressed BMP, or a TGA, shorter than its w x h pixels need: stb
// decodes the missing pixels as zeros. "" when long enough, or not one of
// these (stb then judges it).
std::string short_bmp_or_tga(const unsigned char* data, std::size_t size, long long w, long long h);

// A JPEG with more scans than any encoder writes (stb walks every block of
// the image once a scan: a few bytes a scan made a 20 KB file decode for
// minutes), or with less coded data than its w x h blocks need (stb decodes
// what is missing as zeros: 140 bytes had become a 16384 x 4096 grey
// image). "" when sound, or not a JPEG.
std::string jpeg_problem(const unsigned char* data, std::size_t size, long long w, long long h);
constexpr int kMaxJpegScans = 64;

// A PNG one of whose critical chunks (IHDR, PLTE, IDAT, IEND) fails its
// CRC: stb never checks them, and a damaged file decoded to other pixels
// or another size. "" when sound, or not a PNG.
std::string png_crc_problem(const unsigned char* data, std::size_t size);

// A palette PNG whose palette has fewer entries than its bit depth can
// index: stb reads an index past the palette from memory it never filled.
// Where there is something to guard, `padded.bytes` is the file with its
// palette filled up to 2^depth entries of a colour none of its own entries
// has (`sentinel`, r | g << 8 | b << 16): a decoded pixel of that colour
// came from an index past the `entries`. Otherwise (not such a PNG, or
// stb will refuse it anyway) `padded.bytes` stays empty. Returns why the
// file is refused ("" when it is not): more than one palette.
struct PaddedPalette {
  std::string bytes;
  std::uint32_t sentinel = 0;
  int entries = 0;
};
std::string pad_png_palette(const unsigned char* data, std::size_t size, PaddedPalette& padded);

}  // namespace opsila
