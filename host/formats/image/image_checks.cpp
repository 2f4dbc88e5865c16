// Checks of image files before stb_image decodes them (image_checks.h).
#include "formats/image/image_checks.h"

#include <algorithm>
#include <array>
#include <cstring>

namespace opsila {

namespace {

std::uint32_t le(const unsigned char* data, std::size_t at, int bytes) {
  std::uint32_t v = 0;
  for (int k = bytes - 1; k >= 0; --k) v = v << 8 | data[at + std::size_t(k)];
  return v;
}

std::uint32_t be(const unsigned char* data, std::size_t at, int bytes) {
  std::uint32_t v = 0;
  for (int k = 0; k < bytes; ++k) v = v << 8 | data[at + std::size_t(k)];
  return v;
}

// PNG's chunk checksum (ISO 3309 CRC-32 of the type and data), a byte at a
// time through the table of the polynomial's remainders.
std::uint32_t png_crc(const unsigned char* data, std::size_t size) {
  static const auto table = [] {
    std::array<std::uint32_t, 256> t{};
    for (std::uint32_t b = 0; b < 256; ++b) {
      std::uint32_t c = b;
      for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
      t[b] = c;
    }
    return t;
  }();
  std::uint32_t c = 0xFFFFFFFFu;
  for (std::size_t i = 0; i < size; ++i) c = table[(c ^ data[i]) & 0xFFu] ^ (c >> 8);
  return c ^ 0xFFFFFFFFu;
}
std::uint32_t png_crc(const std::string& type_and_data) {
  return png_crc(reinterpret_cast<const unsigned char*>(type_and_data.data()), type_and_data.size());
}

void put_be32(std::string& out, std::uint32_t v) {
  for (int k = 3; k >= 0; --k) out.push_back(static_cast<char>((v >> (8 * k)) & 0xFFu));
}

// The entropy-coded bytes of a JPEG scan from `at` (just past its header)
// to the next marker that is not a stuffed 0xFF00 or a restart; `at` ends
// on that marker.
std::size_t jpeg_coded_bytes(const unsigned char* d, std::size_t n, std::size_t& at) {
  std::size_t coded = 0;
  while (at < n) {
    if (d[at] == 0xFF && at + 1 < n && d[at + 1] != 0x00 && !(d[at + 1] >= 0xD0 && d[at + 1] <= 0xD7)) break;
    if (d[at] == 0xFF && at + 1 < n) {
      coded += d[at + 1] == 0x00;  // a stuffed 0xFF data byte; a restart codes nothing
      at += 2;
      continue;
    }
    ++coded, ++at;
  }
  return coded;
}

}  // namespace

bool is_png(const unsigned char* data, std::size_t size) {
  static const unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  return size >= 8 && std::equal(kSignature, kSignature + 8, data);
}

std::string png_side_problem(const unsigned char* data, std::size_t size, int max_side) {
  if (!is_png(data, size) || size < 24) return "";
  const std::uint32_t w = be(data, 16, 4), h = be(data, 20, 4);
  if (w <= std::uint32_t(max_side) && h <= std::uint32_t(max_side)) return "";
  return "image too large (" + std::to_string(w) + "x" + std::to_string(h) + ")";
}

// A TGA's run-length packets hold at most 128 pixels each, in at least one
// byte more than a pixel.
std::string short_bmp_or_tga(const unsigned char* data, std::size_t size, long long w, long long h) {
  const unsigned long long pixels = static_cast<unsigned long long>(w) * static_cast<unsigned long long>(h);
  unsigned long long need = 0;
  const char* format = "";
  if (size >= 34 && data[0] == 'B' && data[1] == 'M') {
    const bool os2 = le(data, 14, 4) == 12;  // the old 12-byte header: no compression field
    const std::uint32_t compression = os2 ? 0 : le(data, 30, 4), bits = le(data, os2 ? 24 : 28, 2);
    if (compression != 0 && compression != 3) return "";
    format = "BMP";
    need = le(data, 10, 4) + (static_cast<unsigned long long>(w) * bits + 31) / 32 * 4 * static_cast<unsigned long long>(h);
  } else if (size >= 18 && (data[2] & 7) != 0 && (data[2] & ~0xBu) == 0 && (data[1] == 0 || data[1] == 1)) {
    const unsigned long long pixel_bytes = (data[16] + 7u) / 8u;
    const unsigned long long palette = data[1] ? le(data, 5, 2) * ((data[7] + 7u) / 8u) : 0;
    format = "TGA";
    need = 18 + data[0] + palette + ((data[2] & 8) ? (pixels + 127) / 128 * (1 + pixel_bytes) : pixels * pixel_bytes);
  }
  if (need <= size) return "";
  return std::string("truncated ") + format + ": " + std::to_string(w) + "x" + std::to_string(h) + " needs at least " +
         std::to_string(need) + " bytes, the file has " + std::to_string(size);
}

// Markers walked as stb walks them; a file stb would refuse for its
// structure is left to stb ("" here). The bound on the coded data: every
// scan that codes a block's DC codes at least one bit for it (a Huffman
// code is at least a bit long), and a component at full sampling in one
// direction has at least one block per 8 x 16 pixels: one bit per 16 x 16
// pixels is below any sound file's data.
std::string jpeg_problem(const unsigned char* d, std::size_t n, long long w, long long h) {
  if (n < 4 || d[0] != 0xFF || d[1] != 0xD8) return "";
  std::size_t at = 2, coded = 0;
  int scans = 0;
  while (at + 1 < n && d[at] == 0xFF) {
    const unsigned m = d[at + 1];
    at += m == 0xFF ? 1 : 2;  // fill bytes before a marker
    if (m == 0xFF || m == 0xD8 || (m >= 0xD0 && m <= 0xD7) || m == 0x01) continue;
    if (m == 0xD9 || at + 2 > n) break;
    const std::size_t len = be(d, at, 2);
    if (len < 2 || len > n - at) return "";
    at += len;
    if (m != 0xDA) continue;
    if (++scans > kMaxJpegScans)
      return "JPEG with more than " + std::to_string(kMaxJpegScans) + " scans, more than encoders write";
    coded += jpeg_coded_bytes(d, n, at);
  }
  // No scan at all: stb decoded a frame header alone into invented texels.
  if (scans == 0) return "JPEG without image data: its markers end before any scan";
  const unsigned long long need = ((static_cast<unsigned long long>(w) + 15) / 16 * ((h + 15) / 16) + 7) / 8;
  if (coded >= need) return "";
  return "JPEG data ends early: " + std::to_string(w) + "x" + std::to_string(h) + " needs at least " +
         std::to_string(need) + " bytes of coded data, the file has " + std::to_string(coded);
}

std::string png_crc_problem(const unsigned char* d, std::size_t n) {
  if (!is_png(d, n)) return "";
  std::size_t at = 8;
  while (n - at >= 12) {
    const std::size_t len = be(d, at, 4);
    if (len > n - at - 12) return "";  // a truncated chunk: the decoder names it
    const unsigned char* type = d + at + 4;
    // Critical chunks (the type's first letter upper case) are the image;
    // an ancillary chunk's damage is ignored, as libpng ignores it.
    if ((type[0] & 0x20) == 0 && png_crc(type, len + 4) != be(d, at + 8 + len, 4))
      return "damaged PNG: its " + std::string(reinterpret_cast<const char*>(type), 4) + " chunk at byte " +
             std::to_string(at) + " fails its CRC check";
    if (std::memcmp(type, "IEND", 4) == 0) break;
    at += 12 + len;
  }
  return "";
}

std::string pad_png_palette(const unsigned char* d, std::size_t n, PaddedPalette& out) {
  out = PaddedPalette();
  if (n < 33 || !is_png(d, n) || std::memcmp(d + 12, "IHDR", 4) != 0 || d[25] != 3)
    return "";
  const int depth = d[24];
  if (depth != 1 && depth != 2 && depth != 4 && depth != 8) return "";
  std::size_t at = 8, plte = 0, plte_len = 0;
  int palettes = 0;
  while (n - at >= 12) {
    const std::size_t len = be(d, at, 4);
    if (len > n - at - 12) break;
    const char* type = reinterpret_cast<const char*>(d + at + 4);
    if (std::memcmp(type, "IDAT", 4) == 0 || std::memcmp(type, "IEND", 4) == 0) break;
    if (std::memcmp(type, "PLTE", 4) == 0 && palettes++ == 0) plte = at, plte_len = len;
    at += 12 + len;
  }
  if (palettes > 1) return "PNG with " + std::to_string(palettes) + " PLTE chunks, where a PNG has one palette";
  const std::size_t slots = std::size_t(1) << depth, entries = plte_len / 3;
  if (palettes == 0 || plte_len % 3 != 0 || entries == 0 || entries >= slots) return "";  // stb judges, or all fit
  const unsigned char* pal = d + plte + 8;
  std::uint32_t sentinel = 0;
  for (std::uint32_t r = 0; r < 256; ++r) {  // at most 255 entries: some red is free
    sentinel = r | 0x5Au << 8 | 0xA5u << 16;
    bool used = false;
    for (std::size_t e = 0; e < entries && !used; ++e) used = le(pal, 3 * e, 3) == sentinel;
    if (!used) break;
  }
  std::string chunk = "PLTE" + std::string(reinterpret_cast<const char*>(pal), plte_len);
  for (std::size_t e = entries; e < slots; ++e)
    for (int k = 0; k < 3; ++k) chunk.push_back(static_cast<char>((sentinel >> (8 * k)) & 0xFFu));
  out.bytes.assign(reinterpret_cast<const char*>(d), plte);
  put_be32(out.bytes, static_cast<std::uint32_t>(chunk.size() - 4));
  out.bytes += chunk;
  put_be32(out.bytes, png_crc(chunk));
  out.bytes.append(reinterpret_cast<const char*>(d) + plte + 12 + plte_len, n - plte - 12 - plte_len);
  out.sentinel = sentinel;
  out.entries = static_cast<int>(entries);
  return "";
}

}  // namespace opsila
