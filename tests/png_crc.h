// PNG chunk checksums for tests that build or edit PNG files by hand: the
// CRC-32 computed bit by bit, as the PNG specification states it, apart
// from the table-driven one the image checks use.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace opsila {

inline std::uint32_t png_crc_bitwise(const std::string& type_and_data) {
  std::uint32_t c = 0xFFFFFFFFu;
  for (unsigned char b : type_and_data) {
    c ^= b;
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? (c >> 1) ^ 0xEDB88320u : c >> 1;
  }
  return ~c;
}

// The chunk starting at byte `at` of `png` given its right CRC again after
// an edit of its data.
inline void reseal_png_chunk(std::string& png, std::size_t at) {
  std::uint32_t len = 0;
  for (int k = 0; k < 4; ++k) len = len << 8 | static_cast<unsigned char>(png[at + std::size_t(k)]);
  const std::uint32_t crc = png_crc_bitwise(png.substr(at + 4, len + 4));
  for (int k = 0; k < 4; ++k) png[at + 8 + len + std::size_t(k)] = static_cast<char>((crc >> (8 * (3 - k))) & 0xFFu);
}

}  // namespace opsila
