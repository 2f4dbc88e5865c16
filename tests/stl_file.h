// Binary STL files for the tests: an 80-byte header, the facet count and
// 50 bytes a facet, written from values.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

namespace opsila {
namespace test {

struct StlFacet {
  std::array<float, 3> normal{};
  std::array<std::array<float, 3>, 3> corner{};
  std::uint16_t attribute = 0;
};

struct StlFile {
  std::string header = "binary STL made by a test";  // padded with NUL bytes to 80
  std::vector<StlFacet> facets;
  std::uint64_t count = UINT64_MAX;  // the header's, when not facets.size()
};

inline std::string stl_bytes(const StlFile& s) {
  std::string out = s.header.substr(0, 80);
  out.resize(80, '\0');
  const auto put32 = [&](std::uint32_t u) {
    for (int b = 0; b < 4; ++b) out += char((u >> (8 * b)) & 0xff);
  };
  const auto put_float = [&](float f) {
    std::uint32_t u;
    std::memcpy(&u, &f, 4);
    put32(u);
  };
  put32(std::uint32_t(s.count != UINT64_MAX ? s.count : s.facets.size()));
  for (const StlFacet& f : s.facets) {
    for (float x : f.normal) put_float(x);
    for (const auto& c : f.corner)
      for (float x : c) put_float(x);
    out += char(f.attribute & 0xff), out += char(f.attribute >> 8);
  }
  return out;
}

inline void write_stl(const std::string& path, const StlFile& s) { std::ofstream(path, std::ios::binary) << stl_bytes(s); }

// A w x h grid of quads on a bump, two facets a quad, each with its unit
// normal as a writer computes it; then a facet of zero area, one with a
// zero normal (some writers leave it so) and one whose attribute is a
// colour.
inline StlFile stl_grid(int w, int h) {
  StlFile s;
  const auto at = [](int i, int j) {
    return std::array<float, 3>{float(0.25 * i - 1.0 / 3.0), float(0.5 * j + 0.1),
                                float(std::sin(i * 0.7) * std::cos(j * 0.3))};
  };
  const auto facet = [&](std::array<float, 3> a, std::array<float, 3> b, std::array<float, 3> c) {
    StlFacet f;
    f.corner = {a, b, c};
    const float e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const float n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    const float l = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (l > 0) f.normal = {n[0] / l, n[1] / l, n[2] / l};
    s.facets.push_back(f);
  };
  for (int j = 0; j + 1 < h; ++j)
    for (int i = 0; i + 1 < w; ++i) {
      facet(at(i, j), at(i + 1, j), at(i + 1, j + 1));
      facet(at(i, j), at(i + 1, j + 1), at(i, j + 1));
    }
  facet(at(0, 0), at(1, 0), at(1, 0));  // zero area
  facet(at(0, 1), at(1, 1), at(1, 2));
  s.facets.back().normal = {0, 0, 0};
  facet(at(2, 1), at(3, 1), at(3, 2));
  s.facets.back().attribute = 0x8000 | 0x1f;  // a colour
  return s;
}

}  // namespace test
}  // namespace opsila
